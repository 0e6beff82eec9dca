//! A training cost other than the squared one (`[cost]`: log-cosh, Huber)
//! against theory: EP's update with the cost points along the backprop
//! gradient of the same cost as beta -> 0; backprop's gradient of the cost
//! is the squared cost's scaled by `C'(r) / r` (one output); log-cosh at a
//! large scale is the squared cost's update; the squared cost (or none)
//! is today's training bit for bit; a small scale aims at the median of
//! skewed targets where the squared cost aims at their mean; the setting
//! is kept in the model file, and bad settings are refused by name.
use crate::support;

use support::{correlated_rows, cosine, sample};
use tactrace_learn::{
    ClampedPhase, Cost, CostKind, Dataset, DenNN, EpConfig, Layers, LearnError, Mlp, ModelConfig,
    ModelKind, ModelTarget, NetCost, PoseModel, Preset, Unit,
};

/// Every parameter's change from `before` to `after`, layer by layer
/// (weights in canonical orientation, then biases).
fn change(before: &Layers, after: &Layers) -> Vec<f64> {
    let diff = |a: &[f32], b: &[f32]| -> Vec<f64> {
        a.iter()
            .zip(b)
            .map(|(&a, &b)| f64::from(a) - f64::from(b))
            .collect()
    };
    (1..before.sizes().len())
        .flat_map(|l| {
            let w = diff(&after.weight(l), &before.weight(l));
            w.into_iter().chain(diff(after.bias(l), before.bias(l)))
        })
        .collect()
}

fn net_cost(kind: CostKind, output: usize, scale: f32) -> NetCost {
    NetCost {
        output,
        kind,
        scale,
    }
}

/// A sample whose targets sit 2 above the net's free outputs, so that a
/// scale of 0.5 bends the cost's slope well away from the squared one.
fn far_sample(layers: &Layers, seed: u64) -> (Vec<f32>, Vec<f32>) {
    let sizes = layers.sizes();
    let (x, _) = sample(sizes[0], sizes[sizes.len() - 1], seed);
    let mut y = vec![0.0; sizes[sizes.len() - 1]];
    layers.predict(&x, &mut y).unwrap();
    (x, y.iter().map(|y| y + 2.0).collect())
}

/// One EP step and one backprop step with `cost`, from the same weights.
fn ep_and_backprop(sizes: &[usize], cfg: &EpConfig, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let layers = Layers::new(sizes, seed).unwrap();
    let (x, t) = far_sample(&layers, seed + 100);
    let mut ep = DenNN::from_layers(layers.clone());
    ep.train_sample(&x, &t, cfg).unwrap();
    let mut bp = Mlp::from_layers(layers.clone()).with_cost(cfg.cost);
    bp.train_sample(&x, &t, cfg.learning_rate).unwrap();
    (change(&layers, ep.layers()), change(&layers, bp.layers()))
}

fn small_beta(clamped: ClampedPhase, cost: NetCost) -> EpConfig {
    EpConfig {
        learning_rate: 0.05,
        beta: 1e-3,
        clamped_phase: clamped,
        cost: Some(cost),
        ..EpConfig::default()
    }
}

#[test]
fn ep_with_a_cost_follows_the_backprop_gradient_of_that_cost() {
    // One output (closed form), two (closed form, the cost on the second),
    // two hidden layers (the general step), and Euler's clamped phase.
    let cases: [(&[usize], ClampedPhase, usize); 4] = [
        (&[20, 60, 1], ClampedPhase::Linearised, 0),
        (&[20, 60, 2], ClampedPhase::Linearised, 1),
        (&[12, 30, 20, 2], ClampedPhase::Linearised, 0),
        (&[12, 30, 1], ClampedPhase::Euler { n_i: 200, dt: 0.2 }, 0),
    ];
    for kind in [CostKind::LogCosh, CostKind::Huber] {
        for (sizes, clamped, output) in cases {
            let cfg = small_beta(clamped, net_cost(kind, output, 0.5));
            let (ep, bp) = ep_and_backprop(sizes, &cfg, 3);
            let c = cosine(&ep, &bp);
            assert!(c > 0.99, "{kind:?} {sizes:?} {clamped:?}: cosine {c}");
        }
    }
}

#[test]
fn backprop_of_a_cost_is_the_squared_update_scaled_by_its_slope() {
    // One output: dC/dtheta = C'(r) dy/dtheta, the squared cost's r dy/dtheta
    // times C'(r) / r.
    let layers = Layers::new(&[15, 40, 1], 5).unwrap();
    let (x, t) = far_sample(&layers, 6);
    let mut y = [0.0f32];
    layers.predict(&x, &mut y).unwrap();
    let r = y[0] - t[0];
    let lr = 1e-3;
    let squared = {
        let mut bp = Mlp::from_layers(layers.clone());
        bp.train_sample(&x, &t, lr).unwrap();
        change(&layers, bp.layers())
    };
    for (kind, a) in [(CostKind::LogCosh, 0.5f32), (CostKind::Huber, 0.5)] {
        let cost = net_cost(kind, 0, a);
        let mut bp = Mlp::from_layers(layers.clone()).with_cost(Some(cost));
        bp.train_sample(&x, &t, lr).unwrap();
        let ratio = f64::from(cost.slope(r) / r);
        assert!(ratio < 0.3, "{kind:?}: the slope is not bent ({ratio})");
        for (c, s) in change(&layers, bp.layers()).iter().zip(&squared) {
            assert!((c - ratio * s).abs() <= 1e-6 + 1e-3 * s.abs(), "{kind:?}");
        }
    }
}

#[test]
fn log_cosh_at_a_large_scale_is_the_squared_update() {
    for sizes in [&[20, 60, 1][..], &[20, 60, 2], &[12, 30, 20, 2]] {
        let layers = Layers::new(sizes, 7).unwrap();
        let (x, t) = far_sample(&layers, 8);
        let plain = EpConfig {
            learning_rate: 0.05,
            beta: 0.5,
            ..EpConfig::default()
        };
        let wide = EpConfig {
            cost: Some(net_cost(CostKind::LogCosh, 0, 1e4)),
            ..plain
        };
        let step = |cfg: &EpConfig| {
            let mut ep = DenNN::from_layers(layers.clone());
            ep.train_sample(&x, &t, cfg).unwrap();
            change(&layers, ep.layers())
        };
        let (a, b) = (step(&plain), step(&wide));
        let worst = a
            .iter()
            .zip(&b)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let largest = a.iter().map(|a| a.abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-4 * largest, "{sizes:?}: {worst} of {largest}");
    }
}

fn outputs() -> Vec<ModelTarget> {
    vec![
        ModelTarget::new("pose_2", Unit::Mm),
        ModelTarget::new("pose_6", Unit::Deg),
    ]
}

/// A small model of `kind`, `epochs` epochs, with `cost`.
fn small(kind: ModelKind, cost: Option<Cost>, epochs: usize) -> ModelConfig {
    let mut cfg = ModelConfig::preset(kind, Preset::Default);
    cfg.set_epochs(epochs);
    cfg.cost = cost;
    for net in [&mut cfg.pose, &mut cfg.position, &mut cfg.angle]
        .into_iter()
        .flatten()
    {
        net.hidden = vec![24];
        net.n_components = Some(8);
    }
    cfg
}

fn cost(kind: CostKind, target: &str, scale: f64) -> Option<Cost> {
    Some(Cost {
        kind,
        target: target.into(),
        scale,
    })
}

fn rows(n: usize, seed: u64) -> Dataset {
    let (x, y) = correlated_rows(n, 24, seed);
    Dataset::new(x, y, n, 24, 2).unwrap()
}

fn fit(cfg: &ModelConfig, data: &Dataset) -> Result<PoseModel, LearnError> {
    Ok(PoseModel::fit_targets(cfg, &outputs(), data, None, &mut |_| {})?.0)
}

#[test]
fn the_squared_cost_is_todays_training_bit_for_bit() {
    let data = rows(100, 1);
    for kind in [ModelKind::PcaDenNN, ModelKind::Mlp] {
        let plain = fit(&small(kind, None, 2), &data).unwrap();
        let squared = fit(
            &small(kind, cost(CostKind::Squared, "pose_2", 0.1), 2),
            &data,
        )
        .unwrap();
        let bytes = |m: &PoseModel| m.to_bytes().unwrap().1;
        assert_eq!(bytes(&plain), bytes(&squared), "{kind:?}");
        // A cost on the angle leaves the MLP's depth net as it was.
        if kind == ModelKind::Mlp {
            let angle = fit(&small(kind, cost(CostKind::Huber, "pose_6", 0.1), 2), &data).unwrap();
            let p = plain.predict_targets_batch(&data).unwrap();
            let a = angle.predict_targets_batch(&data).unwrap();
            assert!(p.iter().zip(&a).all(|(p, a)| p[0] == a[0]));
            assert!(p.iter().zip(&a).any(|(p, a)| p[1] != a[1]));
        }
    }
}

/// Rows whose depth is exponential noise (mean 1 mm, median ln 2 mm), the
/// angle a function of the inputs.
fn skewed_rows(n: usize, seed: u64) -> Dataset {
    let (x, mut y) = correlated_rows(n, 24, seed);
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    for row in y.chunks_mut(2) {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let u = (state >> 11) as f64 / (1u64 << 53) as f64;
        row[0] = -(1.0 - u).ln() as f32;
    }
    Dataset::new(x, y, n, 24, 2).unwrap()
}

#[test]
fn a_small_scale_aims_at_the_median_of_skewed_targets() {
    // Squared cost: the conditional mean (1 mm); an absolute-like cost: the
    // median (ln 2 = 0.69 mm), which has the lower mean absolute error.
    let data = skewed_rows(600, 2);
    let mean_depth = |m: &PoseModel| {
        let p = m.predict_targets_batch(&data).unwrap();
        p.iter().map(|p| p[0]).sum::<f64>() / p.len() as f64
    };
    let squared = mean_depth(&fit(&small(ModelKind::Mlp, None, 20), &data).unwrap());
    assert!((squared - 1.0).abs() < 0.12, "squared cost: {squared} mm");
    for kind in [CostKind::LogCosh, CostKind::Huber] {
        let model = fit(
            &small(ModelKind::Mlp, cost(kind, "pose_2", 0.05), 20),
            &data,
        )
        .unwrap();
        let robust = mean_depth(&model);
        assert!((robust - 2f64.ln()).abs() < 0.12, "{kind:?}: {robust} mm");
    }
}

#[test]
fn the_cost_is_kept_in_the_model_file() {
    let data = rows(100, 3);
    let plain = fit(&small(ModelKind::PcaDenNN, None, 2), &data).unwrap();
    assert!(!plain.to_bytes().unwrap().0.contains("\"cost\""));
    let setting = cost(CostKind::LogCosh, "pose_2", 0.05);
    let model = fit(&small(ModelKind::PcaDenNN, setting.clone(), 2), &data).unwrap();
    let (json, weights) = model.to_bytes().unwrap();
    assert!(json.contains("\"log_cosh\""), "{json}");
    let again = PoseModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(again.config().cost, setting);
    assert_ne!(
        plain.predict_targets_batch(&data).unwrap(),
        model.predict_targets_batch(&data).unwrap()
    );
}

#[test]
fn bad_costs_are_refused_by_name() {
    let data = rows(60, 4);
    let circular = vec![
        ModelTarget::new("pose_2", Unit::Mm),
        ModelTarget::circular("pose_6"),
    ];
    for (setting, targets) in [
        (cost(CostKind::Huber, "pose_9", 0.1), outputs()),
        (cost(CostKind::Huber, "pose_6", 0.1), circular),
        (cost(CostKind::LogCosh, "pose_2", 0.0), outputs()),
        (cost(CostKind::LogCosh, "pose_2", f64::NAN), outputs()),
    ] {
        let cfg = small(ModelKind::Mlp, setting, 1);
        let err = PoseModel::fit_targets(&cfg, &targets, &data, None, &mut |_| {}).unwrap_err();
        assert!(
            matches!(err, LearnError::Config { field: "cost", .. }),
            "{err}"
        );
    }
}
