//! Ensembles of pin models (`ModelConfig::ensemble`): one member is the
//! single model bit for bit, K members average the models their seeds
//! give alone, and an ensemble saves and loads as any model.
use crate::support;
use tactrace_learn::{Dataset, ModelConfig, ModelKind, ModelTarget, PoseModel, Preset, Unit};

/// `n` random rows of `dim` correlated values and their two targets (a
/// position in mm and an angle in deg), a smooth function of them.
fn data(n: usize, dim: usize, seed: u64) -> Dataset {
    let (x, y) = support::correlated_rows(n, dim, seed);
    Dataset::new(x, y, n, dim, 2).expect("data")
}

/// A small, fast configuration of `kind`.
fn small(kind: ModelKind, ensemble: usize) -> ModelConfig {
    let mut cfg = ModelConfig::preset(kind, Preset::Default);
    cfg.set_epochs(3);
    cfg.seed = 7;
    cfg.ensemble = ensemble;
    // Below the defaults: a small net on 80 rows must not diverge.
    cfg.scale_learning_rates(0.25);
    for net in [&mut cfg.pose, &mut cfg.position, &mut cfg.angle]
        .into_iter()
        .flatten()
    {
        net.hidden = vec![40];
        net.n_components = net.n_components.map(|_| 8);
    }
    cfg.validate().expect("config");
    cfg
}

fn fit(cfg: &ModelConfig, outputs: &[ModelTarget], d: &Dataset) -> PoseModel {
    let (model, history) = PoseModel::fit_targets(cfg, outputs, d, None, &mut |_| {}).expect("fit");
    assert_eq!(history.lr_halvings, 0, "a small fit diverged");
    model
}

fn edge() -> Vec<ModelTarget> {
    vec![
        ModelTarget::new("r", Unit::Mm),
        ModelTarget::new("theta", Unit::Deg),
    ]
}

#[test]
fn an_ensemble_of_one_is_the_single_model_bit_for_bit() {
    let d = data(80, 30, 1);
    for kind in [ModelKind::PDenNN, ModelKind::PcaDenNN, ModelKind::Mlp] {
        let single = fit(&small(kind, 1), &edge(), &d);
        let mut explicit = small(kind, 1);
        explicit.ensemble = 1;
        let one = fit(&explicit, &edge(), &d);
        let (json, weights) = one.to_bytes().expect("save");
        assert_eq!((json.clone(), weights), single.to_bytes().expect("save"));
        // Written as before ensembles existed: older readers load it.
        assert!(!json.contains("ensemble"), "{kind:?}");
        // The first member of an ensemble of three is that model too.
        let three = fit(&small(kind, 3), &edge(), &d);
        assert_eq!(
            three.member(0).expect("member").to_bytes().expect("save"),
            single.to_bytes().expect("save"),
            "{kind:?}"
        );
        let rows = &d.x[..10 * d.dim_x];
        assert_eq!(
            one.predict_rows(rows).expect("one"),
            single.predict_rows(rows).expect("single")
        );
    }
}

/// Largest difference between `a` and `b`, over rows and targets.
fn worst(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn an_ensemble_of_three_averages_its_members() {
    let d = data(80, 30, 2);
    for kind in [ModelKind::PDenNN, ModelKind::PcaDenNN, ModelKind::DisDenNN] {
        let cfg = small(kind, 3);
        let three = fit(&cfg, &edge(), &d);
        assert_eq!(three.ensemble(), 3);
        let mut alone = Vec::new();
        for m in 0..3 {
            // Member m is the model its seed gives trained alone.
            let mut single = small(kind, 1);
            single.seed = cfg.member_seed(m);
            let model = fit(&single, &edge(), &d);
            let member = three.member(m).expect("member");
            assert_eq!(
                member.to_bytes().expect("save"),
                model.to_bytes().expect("save")
            );
            alone.push(model.predict_targets_batch(&d).expect("member"));
        }
        // The members differ, and the ensemble predicts their mean (the
        // fast path of every row, and one row at a time).
        assert!(worst(&alone[0], &alone[1]) > 1e-3, "{kind:?}");
        let mean: Vec<Vec<f64>> = (0..d.n)
            .map(|i| {
                (0..2)
                    .map(|t| alone.iter().map(|p| p[i][t]).sum::<f64>() / 3.0)
                    .collect()
            })
            .collect();
        let batch = three.predict_targets_batch(&d).expect("batch");
        let rows: Vec<Vec<f64>> = (0..d.n)
            .map(|i| three.predict_targets(d.x_row(i)).expect("row"))
            .collect();
        assert!(
            worst(&batch, &mean) < 1e-4,
            "{kind:?}: {}",
            worst(&batch, &mean)
        );
        assert!(
            worst(&rows, &mean) < 1e-4,
            "{kind:?}: {}",
            worst(&rows, &mean)
        );
        // Saved and loaded: the same predictions, bit for bit.
        let (json, weights) = three.to_bytes().expect("save");
        let loaded = PoseModel::from_bytes(&json, &weights).expect("load");
        assert_eq!(loaded.predict_targets_batch(&d).expect("loaded"), batch);
        assert_eq!(
            loaded.architecture().len(),
            3 * three.member(0).unwrap().architecture().len()
        );
    }
}

#[test]
fn an_ensemble_of_a_circular_target_trains_and_loads() {
    // A circular angle: the ensemble's encoded columns are averaged
    // before atan2 (checked exactly by the unit test in member.rs); here
    // its predictions stay within the members' spread of each other.
    let mut d = data(80, 30, 3);
    for i in 0..d.n {
        d.y[2 * i + 1] *= 4.0; // +-180 deg
    }
    let outputs = vec![
        ModelTarget::new("pose_2", Unit::Mm),
        ModelTarget::circular("pose_6"),
    ];
    let three = fit(&small(ModelKind::PcaDenNN, 3), &outputs, &d);
    let (json, weights) = three.to_bytes().expect("save");
    assert!(json.contains("\"ensemble\": 3"));
    let loaded = PoseModel::from_bytes(&json, &weights).expect("load");
    assert_eq!(
        loaded.predict_targets_batch(&d).expect("loaded"),
        three.predict_targets_batch(&d).expect("model")
    );
    // A file whose nets do not make its members is refused.
    let bad = json.replace("\"ensemble\": 3", "\"ensemble\": 2");
    assert!(PoseModel::from_bytes(&bad, &weights).is_err());
}

#[test]
fn an_ensemble_size_out_of_range_is_refused() {
    for k in [0, tactrace_learn::MAX_ENSEMBLE + 1] {
        let mut cfg = small(ModelKind::PDenNN, 1);
        cfg.ensemble = k;
        let err = cfg.validate().expect_err("refused").to_string();
        assert!(err.contains("ensemble"), "{err}");
    }
}

/// A user's seed is bounded where it is given (the TOML loader, `--seed`:
/// tests/it/seed_range.rs); members' seeds span all 64 bits, and a member
/// trained alone on its own seed validates.
#[test]
fn a_members_seed_past_max_seed_validates() {
    let cfg = small(ModelKind::PDenNN, 1);
    let wide = (1..64)
        .map(|m| cfg.member_seed(m))
        .find(|&s| s > tactrace_learn::MAX_SEED)
        .expect("a member seed past i64 among 63");
    let alone = ModelConfig {
        seed: wide,
        ..cfg.clone()
    };
    alone.validate().expect("a member's own seed");
}

#[test]
fn input_noise_is_seeded_training_only_and_checked() {
    let d = data(80, 30, 4);
    let clean = fit(&small(ModelKind::PDenNN, 1), &edge(), &d);
    let mut cfg = small(ModelKind::PDenNN, 1);
    cfg.input_noise = 0.3;
    let a = fit(&cfg, &edge(), &d);
    let b = fit(&cfg, &edge(), &d);
    // The same seed gives the same model; the noise changes the fit ...
    assert_eq!(a.to_bytes().expect("a"), b.to_bytes().expect("b"));
    let (pa, pc) = (
        a.predict_targets_batch(&d).expect("a"),
        clean.predict_targets_batch(&d).expect("clean"),
    );
    assert!(worst(&pa, &pc) > 1e-4);
    // ... but not the prediction: the same input, the same output.
    assert_eq!(pa, a.predict_targets_batch(&d).expect("again"));
    let (json, _) = a.to_bytes().expect("save");
    assert!(json.contains("\"input_noise\": 0.3"), "{json}");
    for bad in [-0.1, f64::NAN, 11.0] {
        cfg.input_noise = bad;
        let err = cfg.validate().expect_err("refused").to_string();
        assert!(err.contains("input_noise"), "{err}");
    }
}

#[test]
fn models_trained_apart_join_into_the_ensemble_of_them() {
    // `PoseModel::join`: one model joined alone is that model, and an
    // ensemble's members, each trained alone, joined are the ensemble,
    // bit for bit; a model of other rows is refused.
    let d = data(80, 30, 5);
    let kind = ModelKind::PcaDenNN;
    let one = fit(&small(kind, 1), &edge(), &d);
    let alone = PoseModel::join(std::slice::from_ref(&one)).expect("join");
    assert_eq!(
        alone.to_bytes().expect("save"),
        one.to_bytes().expect("save")
    );
    let cfg = small(kind, 2);
    let two = fit(&cfg, &edge(), &d);
    let members: Vec<PoseModel> = (0..2)
        .map(|m| {
            let mut single = small(kind, 1);
            single.seed = cfg.member_seed(m);
            fit(&single, &edge(), &d)
        })
        .collect();
    let joined = PoseModel::join(&members).expect("join");
    assert_eq!(
        joined.to_bytes().expect("save"),
        two.to_bytes().expect("save")
    );
    assert_eq!(
        joined.predict_targets_batch(&d).expect("joined"),
        two.predict_targets_batch(&d).expect("two")
    );
    let elsewhere = fit(&small(kind, 1), &edge(), &data(80, 30, 6));
    let err = PoseModel::join(&[one, elsewhere]).expect_err("refused");
    assert!(err.to_string().contains("standardised"), "{err}");
}
