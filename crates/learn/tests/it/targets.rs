//! Models of N named targets (issue 21, item 4): every kind fits and
//! round-trips three targets, a circular angle learnt as (sin, cos) is
//! learnt over the full circle where a scalar fails at the wrap, and a
//! model file written before the targets were named (version 2) still
//! loads as the edge task's r and theta.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_learn::{
    target_mae, Dataset, LearnError, ModelConfig, ModelKind, ModelTarget, PoseModel, Preset, Unit,
};

/// Features of a tap with a depth (mm), a tilt (deg) and an angle over
/// the full circle (deg): smooth functions of the depth, the tilt and the
/// angle's direction (so the angle is observable everywhere).
fn three_targets(n: usize, seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut mix = ChaCha8Rng::seed_from_u64(7);
    let dim = 16;
    let coef: Vec<[f32; 4]> = (0..dim)
        .map(|_| std::array::from_fn(|_| mix.random_range(-1.5..1.5)))
        .collect();
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let depth: f32 = rng.random_range(0.0..2.0);
        let tilt: f32 = rng.random_range(-10.0..10.0);
        let angle: f32 = rng.random_range(-180.0..180.0);
        let (s, c) = angle.to_radians().sin_cos();
        for k in &coef {
            x.push(
                2.0 * (k[0] * depth + k[1] * tilt / 10.0 + k[2] * s + k[3] * c).tanh()
                    + 0.005 * rng.random_range(-1.0..1.0),
            );
        }
        y.extend([depth, tilt, angle]);
    }
    Dataset::new(x, y, n, dim, 3).unwrap()
}

fn targets(circular: bool) -> Vec<ModelTarget> {
    let mut angle = ModelTarget::new("pose_6", Unit::Deg);
    angle.circular = circular;
    vec![
        ModelTarget::new("pose_3", Unit::Mm),
        ModelTarget::new("pose_4", Unit::Deg),
        angle,
    ]
}

fn small(kind: ModelKind, epochs: usize) -> ModelConfig {
    let mut cfg = ModelConfig::preset(kind, Preset::Default);
    cfg.epochs = epochs;
    for net in [&mut cfg.pose, &mut cfg.position, &mut cfg.angle]
        .into_iter()
        .flatten()
    {
        net.hidden = vec![48];
        if net.n_components.is_some() {
            net.n_components = Some(10);
        }
    }
    cfg
}

fn truth(ds: &Dataset) -> Vec<Vec<f64>> {
    (0..ds.n)
        .map(|i| ds.y_row(i).iter().map(|&v| f64::from(v)).collect())
        .collect()
}

#[test]
fn every_kind_fits_three_targets_and_round_trips_them() {
    let data = three_targets(300, 1);
    let outputs = targets(true);
    for kind in [
        ModelKind::DisDenNN,
        ModelKind::PcaDenNN,
        ModelKind::PDenNN,
        ModelKind::Mlp,
    ] {
        let (model, history) =
            PoseModel::fit_targets(&small(kind, 5), &outputs, &data, None, &mut |_| {}).unwrap();
        assert_eq!(model.outputs(), outputs.as_slice());
        let nets = model.architecture();
        if matches!(kind, ModelKind::PDenNN | ModelKind::Mlp) {
            // One net a target, named by it; the circular one has 2 outputs.
            let names: Vec<&str> = nets.iter().map(|(n, _)| n.as_str()).collect();
            assert_eq!(names, ["pose_3", "pose_4", "pose_6"], "{kind}");
            assert_eq!(nets[2].1.last(), Some(&2));
        } else {
            assert_eq!(nets[0].1.last(), Some(&4), "{kind}: 1 + 1 + 2 outputs");
        }
        assert!(history.epochs.len() == 5);
        let pred = model.predict_targets(data.x_row(3)).unwrap();
        assert_eq!(pred.len(), 3);
        assert!(pred[2] > -180.0 && pred[2] <= 180.0);
        // Not an edge model: the edge pose is refused, by type.
        assert!(matches!(
            model.predict(data.x_row(3)),
            Err(LearnError::NotAnEdgeModel { .. })
        ));
        let (json, weights) = model.to_bytes().unwrap();
        assert!(json.contains("\"circular\": true"), "{json}");
        let back = PoseModel::from_bytes(&json, &weights).unwrap();
        assert_eq!(back.outputs(), outputs.as_slice());
        assert_eq!(back.predict_targets(data.x_row(3)).unwrap(), pred);
    }
}

#[test]
fn a_full_circle_angle_is_learnt_as_sin_cos_where_a_scalar_fails() {
    let train = three_targets(1500, 2);
    let test = three_targets(400, 3);
    let mae = |circular: bool| {
        let outputs = targets(circular);
        let (model, _) = PoseModel::fit_targets(
            &small(ModelKind::PDenNN, 30),
            &outputs,
            &train,
            None,
            &mut |_| {},
        )
        .unwrap();
        let pred = model.predict_targets_batch(&test).unwrap();
        // Both scored wrapped: the scalar's failure is not the metric's.
        target_mae(&targets(true), &pred, &truth(&test))
    };
    let circular = mae(true);
    let scalar = mae(false);
    assert!(circular[2] < 2.0, "sin/cos angle MAE {circular:?}");
    assert!(
        scalar[2] > 3.0 * circular[2],
        "a scalar angle should fail at the wrap: {scalar:?} vs {circular:?}"
    );
    // The other targets are learnt either way.
    assert!(circular[0] < 0.25 && circular[1] < 1.5, "{circular:?}");
}

#[test]
fn a_version_2_model_file_loads_as_the_edge_task() {
    let data = {
        let three = three_targets(120, 4);
        let y: Vec<f32> = (0..three.n)
            .flat_map(|i| [three.y_row(i)[0], three.y_row(i)[1]])
            .collect();
        Dataset::new(three.x.clone(), y, three.n, three.dim_x, 2).unwrap()
    };
    let (model, _) = PoseModel::fit(&small(ModelKind::PDenNN, 2), &data, &mut |_| {}).unwrap();
    let (json, weights) = model.to_bytes().unwrap();
    // A file as version 2 wrote it: no `outputs`.
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    let obj = value.as_object_mut().unwrap();
    assert!(obj.remove("outputs").is_some());
    obj.insert("version".into(), 2.into());
    let old = serde_json::to_string(&value).unwrap();
    let back = PoseModel::from_bytes(&old, &weights).unwrap();
    let names: Vec<&str> = back.outputs().iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, ["r", "theta"]);
    assert_eq!(
        back.predict(data.x_row(0)).unwrap(),
        model.predict(data.x_row(0)).unwrap()
    );
    let nets: Vec<String> = back.architecture().into_iter().map(|(n, _)| n).collect();
    assert_eq!(nets, ["position", "angle"]);
}

/// `train --search`'s search (issue 21, pin331 item 2) scores every target
/// of a model, not the first two: each trial's errors are the three
/// targets' (the circular one wrapped), equal to those of the same
/// configuration fitted alone, and its score is the sum of each error over
/// its spread (the circular spread wrapped) or over the goals given.
#[test]
fn search_scores_all_n_targets_circular_ones_wrapped() {
    use tactrace_learn::{hyperparameter_search, SearchSpace, TargetScale};
    let data = three_targets(240, 5);
    let (train, val) = data.split(0.75, 6);
    let outputs = targets(true);
    let space = SearchSpace {
        learning_rates: vec![18.0],
        output_learning_rates: vec![0.5, 5.0],
        betas: vec![1.0],
        hidden: vec![24],
        n_components: vec![10],
        trials: 2,
        seed: 3,
        goals: Vec::new(),
    };
    let base = small(ModelKind::PDenNN, 15);
    let trials = hyperparameter_search(&base, &space, &outputs, &train, &val, &mut |_| {}).unwrap();
    assert_eq!(trials.len(), 2);
    let spread = TargetScale::spreads(&outputs, &train).unwrap();
    // The circular angle spans the whole circle: its wrapped spread is
    // about 360 / sqrt(12), not the 0-centred linear one.
    assert!(
        (spread.scales()[2] - 104.0).abs() < 8.0,
        "{:?}",
        spread.scales()
    );
    for t in &trials {
        assert_eq!(t.val_mae.len(), 3);
        let (model, _) =
            PoseModel::fit_targets(&t.config, &outputs, &train, None, &mut |_| {}).unwrap();
        let alone = target_mae(
            &outputs,
            &model.predict_targets_batch(&val).unwrap(),
            &truth(&val),
        );
        assert_eq!(t.val_mae, alone);
        assert!(
            t.val_mae[2] < 90.0,
            "the angle's error is wrapped: {:?}",
            t.val_mae
        );
        let expected: f64 = (0..3).map(|j| t.val_mae[j] / spread.scales()[j]).sum();
        assert!(
            (t.score - expected).abs() < 1e-12,
            "{} vs {expected}",
            t.score
        );
    }
    assert!(trials[0].score <= trials[1].score);
    // With goals, each error is divided by its goal instead.
    let goals = SearchSpace {
        goals: vec![0.1, 1.0, 5.0],
        trials: 1,
        ..space
    };
    let t = &hyperparameter_search(&base, &goals, &outputs, &train, &val, &mut |_| {}).unwrap()[0];
    let expected = t.val_mae[0] / 0.1 + t.val_mae[1] / 1.0 + t.val_mae[2] / 5.0;
    assert!((t.score - expected).abs() < 1e-12);
    // A goal list of the wrong length, and validation rows of other
    // targets, are refused.
    let short = SearchSpace {
        goals: vec![0.1],
        ..goals.clone()
    };
    assert!(hyperparameter_search(&base, &short, &outputs, &train, &val, &mut |_| {}).is_err());
    let two = Dataset::new(
        val.x.clone(),
        val.y.iter().copied().take(val.n * 2).collect(),
        val.n,
        val.dim_x,
        2,
    )
    .unwrap();
    assert!(hyperparameter_search(&base, &goals, &outputs, &train, &two, &mut |_| {}).is_err());
}
