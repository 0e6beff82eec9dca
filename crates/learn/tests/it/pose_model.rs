//! Pose models end to end on a smooth synthetic problem: training lowers the
//! loss, serialisation round-trips exactly, and bad inputs are errors.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_learn::{
    hyperparameter_search, mean_absolute_error, Dataset, LearnError, ModelConfig, ModelKind,
    PoseModel, Preset, SearchSpace, FORMAT_VERSION,
};

/// Displacement-like features that depend smoothly on (r, theta).
fn synthetic(n: usize, dim: usize, seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut mix = ChaCha8Rng::seed_from_u64(99);
    let coef: Vec<[f32; 3]> = (0..dim)
        .map(|_| {
            [
                mix.random_range(-2.0..2.0),
                mix.random_range(-2.0..2.0),
                mix.random_range(0.0..6.3),
            ]
        })
        .collect();
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let r: f32 = rng.random_range(-5.0..5.0);
        let theta: f32 = rng.random_range(-45.0..45.0);
        for c in &coef {
            x.push(
                3.0 * (c[0] * r / 5.0 + c[1] * theta / 45.0 + c[2]).sin()
                    + 0.01 * rng.random_range(-1.0..1.0),
            );
        }
        y.extend([r, theta]);
    }
    Dataset::new(x, y, n, dim, 2).unwrap()
}

fn small(kind: ModelKind, epochs: usize) -> ModelConfig {
    let mut cfg = ModelConfig::preset(kind, Preset::Default);
    cfg.epochs = epochs;
    for net in [&mut cfg.pose, &mut cfg.position, &mut cfg.angle]
        .into_iter()
        .flatten()
    {
        net.hidden = vec![64];
        if net.n_components.is_some() {
            net.n_components = Some(8);
        }
    }
    cfg
}

#[test]
fn training_lowers_the_loss_for_every_kind() {
    let data = synthetic(400, 24, 1);
    for kind in [
        ModelKind::DisDenNN,
        ModelKind::PcaDenNN,
        ModelKind::PDenNN,
        ModelKind::Mlp,
    ] {
        let mut epochs_seen = 0;
        let (model, history) =
            PoseModel::fit(&small(kind, 15), &data, &mut |r| epochs_seen = r.epoch + 1).unwrap();
        assert_eq!(epochs_seen, 15);
        for k in 0..history.epochs[0].nets.len() {
            let first = history.epochs[0].nets[k].loss;
            let last = history.epochs[14].nets[k].loss;
            assert!(
                last < 0.3 * first,
                "{kind:?} net {k}: loss {first} -> {last}"
            );
        }
        let mae = mean_absolute_error(&model.predict_batch(&data).unwrap(), &data);
        assert!(
            mae[0] < 1.0 && mae[1] < 9.0,
            "{kind:?}: training MAE {mae:?}"
        );
    }
}

/// The default preset at full size (35 PCs, 1000 hidden units): the
/// backprop twin used to diverge at epoch 0 with a plain learning rate.
#[test]
fn default_preset_trains_stably_at_full_size() {
    let data = synthetic(300, 60, 11);
    for kind in [ModelKind::Mlp, ModelKind::PDenNN] {
        let mut cfg = ModelConfig::preset(kind, Preset::Default);
        cfg.epochs = 4;
        let (model, history) = PoseModel::fit(&cfg, &data, &mut |_| {}).unwrap();
        for net in 0..2 {
            let losses: Vec<f64> = history.epochs.iter().map(|e| e.nets[net].loss).collect();
            assert!(losses.iter().all(|l| l.is_finite()), "{kind:?}: {losses:?}");
            assert!(losses[3] < losses[0], "{kind:?}: {losses:?}");
        }
        let mae = mean_absolute_error(&model.predict_batch(&data).unwrap(), &data);
        assert!(mae[0] < 2.0 && mae[1] < 18.0, "{kind:?}: MAE {mae:?}");
    }
}

#[test]
fn diverging_training_is_an_error_not_a_panic() {
    let data = synthetic(100, 12, 12);
    let mut cfg = small(ModelKind::Mlp, 3);
    cfg.lr_scaling = tactrace_learn::LrScaling::None;
    for net in [&mut cfg.position, &mut cfg.angle].into_iter().flatten() {
        net.learning_rate = 1e4;
        net.output_learning_rate = None;
    }
    assert!(matches!(
        PoseModel::fit(&cfg, &data, &mut |_| {}),
        Err(LearnError::Diverged { .. })
    ));
}

#[test]
fn divergence_retries_halve_the_rates_and_record_them() {
    let data = synthetic(200, 12, 13);
    let mut cfg = small(ModelKind::Mlp, 3);
    // Output step about 0.3 x 40 = 12 times the error: diverges at once.
    for net in [&mut cfg.position, &mut cfg.angle].into_iter().flatten() {
        net.learning_rate = 40.0;
        net.output_learning_rate = Some(40.0);
    }
    cfg.divergence_retries = 0;
    assert!(matches!(
        PoseModel::fit(&cfg, &data, &mut |_| {}),
        Err(LearnError::Diverged { .. })
    ));
    cfg.divergence_retries = 5;
    let (model, history) = PoseModel::fit(&cfg, &data, &mut |_| {}).unwrap();
    let k = history.lr_halvings;
    assert!((1..=5).contains(&k), "halvings {k}");
    let used = 40.0 / f64::from(1u32 << k);
    for net in [&model.config().position, &model.config().angle] {
        let net = net.as_ref().unwrap();
        assert_eq!(
            (net.learning_rate, net.output_learning_rate),
            (used, Some(used))
        );
    }
    assert_eq!(history.epochs.len(), 3);
}

#[test]
fn validation_loss_is_reported_and_falls() {
    let (train, val) = synthetic(500, 20, 2).split(0.8, 3);
    let (_, history) = PoseModel::fit_with_validation(
        &small(ModelKind::PDenNN, 10),
        &train,
        Some(&val),
        &mut |_| {},
    )
    .unwrap();
    let v0 = history.epochs[0].nets[0].val_loss.unwrap();
    let v9 = history.epochs[9].nets[0].val_loss.unwrap();
    assert!(v9 < v0, "val loss {v0} -> {v9}");
}

#[test]
fn round_trip_predicts_identically() {
    let data = synthetic(200, 16, 4);
    for kind in [ModelKind::DisDenNN, ModelKind::PDenNN] {
        let (model, _) = PoseModel::fit(&small(kind, 3), &data, &mut |_| {}).unwrap();
        let (json, weights) = model.to_bytes().unwrap();
        let back = PoseModel::from_bytes(&json, &weights).unwrap();
        assert_eq!(back.input_dim(), 16);
        for i in 0..data.n {
            assert_eq!(
                model.predict(data.x_row(i)).unwrap(),
                back.predict(data.x_row(i)).unwrap()
            );
        }
    }
}

#[test]
fn bad_model_bytes_are_errors() {
    let data = synthetic(100, 10, 5);
    let (model, _) = PoseModel::fit(&small(ModelKind::PDenNN, 1), &data, &mut |_| {}).unwrap();
    let (json, weights) = model.to_bytes().unwrap();
    let truncated = &weights[..weights.len() - 17];
    assert!(matches!(
        PoseModel::from_bytes(&json, truncated),
        Err(LearnError::Corrupt { .. })
    ));
    assert!(matches!(
        PoseModel::from_bytes(&json[..json.len() / 2], &weights),
        Err(LearnError::Corrupt { .. })
    ));
    let other = json.replacen(
        &format!("\"version\": {FORMAT_VERSION}"),
        "\"version\": 1",
        1,
    );
    assert!(matches!(
        PoseModel::from_bytes(&other, &weights),
        Err(LearnError::Version {
            found: 1,
            supported: FORMAT_VERSION
        })
    ));
    assert!(PoseModel::from_bytes(&json, b"not safetensors").is_err());
}

#[test]
fn dimension_mismatch_is_an_error() {
    let data = synthetic(100, 10, 6);
    let (model, _) = PoseModel::fit(&small(ModelKind::PcaDenNN, 1), &data, &mut |_| {}).unwrap();
    assert!(matches!(
        model.predict(&[0.0; 9]),
        Err(LearnError::DimensionMismatch {
            expected: 10,
            got: 9
        })
    ));
    let wide = synthetic(5, 11, 7);
    assert!(model.predict_batch(&wide).is_err());
}

#[test]
fn nan_in_data_is_an_error_naming_row_and_column() {
    let mut x = vec![0.0f32; 12];
    x[7] = f32::NAN;
    match Dataset::new(x, vec![0.0; 6], 3, 4, 2) {
        Err(LearnError::NonFinite {
            row: 1, column: 3, ..
        }) => {}
        other => panic!("expected NonFinite at row 1, column 3, got {other:?}"),
    }
    let mut y = vec![0.0f32; 6];
    y[4] = f32::INFINITY;
    assert!(matches!(
        Dataset::new(vec![0.0; 12], y, 3, 4, 2),
        Err(LearnError::NonFinite {
            row: 2,
            column: 0,
            ..
        })
    ));
    assert!(Dataset::new(vec![0.0; 11], vec![0.0; 6], 3, 4, 2).is_err());
    assert!(Dataset::new(vec![], vec![], 0, 4, 2).is_err());
}

#[test]
fn presets_validate_and_round_trip_through_toml() {
    for preset in [Preset::Report, Preset::Default] {
        for kind in [
            ModelKind::DisDenNN,
            ModelKind::PcaDenNN,
            ModelKind::PDenNN,
            ModelKind::Mlp,
        ] {
            let cfg = ModelConfig::preset(kind, preset);
            cfg.validate().unwrap();
            let text = toml::to_string(&cfg).unwrap();
            let back: ModelConfig = toml::from_str(&text).unwrap();
            assert_eq!(back, cfg);
        }
    }
    let report = ModelConfig::preset(ModelKind::PDenNN, Preset::Report);
    let (pos, ang) = (report.position.unwrap(), report.angle.unwrap());
    assert_eq!(
        (pos.n_components, pos.hidden[0], pos.beta),
        (Some(30), 500, 1.2)
    );
    assert_eq!(
        (ang.n_components, ang.hidden[0], ang.beta),
        (Some(35), 1000, 0.5)
    );
    let text = toml::to_string(&ModelConfig::preset(ModelKind::Mlp, Preset::Default)).unwrap();
    assert!(toml::from_str::<ModelConfig>(&format!("{text}\nsurprise = 1\n")).is_err());
}

#[test]
fn invalid_configs_are_errors() {
    let data = synthetic(50, 8, 8);
    let mut cfg = small(ModelKind::PDenNN, 1);
    cfg.angle.as_mut().unwrap().learning_rate = -1.0;
    assert!(matches!(
        PoseModel::fit(&cfg, &data, &mut |_| {}),
        Err(LearnError::NetConfig {
            net: "angle",
            field: "learning_rate",
            ..
        })
    ));
    let mut cfg = small(ModelKind::PDenNN, 1);
    cfg.pose = cfg.angle.clone();
    assert!(PoseModel::fit(&cfg, &data, &mut |_| {}).is_err());
}

#[test]
fn search_ranks_trials_on_the_validation_split() {
    let (train, val) = synthetic(300, 12, 9).split(0.75, 10);
    let space = SearchSpace {
        learning_rates: vec![0.02],
        output_learning_rates: vec![1e-4, 0.02],
        betas: vec![1.0],
        hidden: vec![32],
        n_components: vec![6],
        trials: 2,
        seed: 1,
        goals: Vec::new(),
    };
    let mut seen = 0;
    let trials = hyperparameter_search(
        &small(ModelKind::PDenNN, 5),
        &space,
        &tactrace_learn::edge_targets(),
        &train,
        &val,
        &mut |_| seen += 1,
    )
    .unwrap();
    assert_eq!((trials.len(), seen), (2, 2));
    assert!(trials[0].score <= trials[1].score);
    let best = trials[0].config.angle.as_ref().unwrap();
    assert_eq!(best.output_learning_rate, Some(0.02));
}
