//! Two hidden layers (issue 21, the 331-pin edge over the full circle): the
//! linearised clamped phase in closed form through every hidden layer
//! (`ClampedPhase::Linearised` at any depth) against theory: at small beta
//! its update points along the backprop gradient, it is the equilibrium a
//! long Euler relaxation reaches, and pose models with two hidden layers
//! train and learn. And the loss weight of a circular target's (sine,
//! cosine) pair (`circular_weight`).
use crate::support;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use support::{cosine, sample};
use tactrace_learn::{
    mean_absolute_error, target_mae, ClampedPhase, Dataset, DenNN, EpConfig, Layers, Mlp,
    ModelConfig, ModelKind, ModelTarget, PoseModel, Preset, Unit,
};

/// All parameters, canonical orientation, flattened.
fn flat(layers: &Layers) -> Vec<f64> {
    let mut out = Vec::new();
    for l in 1..layers.sizes().len() {
        out.extend(layers.weight(l).iter().map(|&v| v as f64));
        out.extend(layers.bias(l).iter().map(|&v| v as f64));
    }
    out
}

/// The parameter change of one EP step with `clamped` from seeded weights.
fn ep_delta(sizes: &[usize], clamped: ClampedPhase, beta: f64, seed: u64) -> Vec<f64> {
    let layers = Layers::new(sizes, seed).unwrap();
    let before = flat(&layers);
    let (x, t) = sample(sizes[0], sizes[sizes.len() - 1], seed + 100);
    let cfg = EpConfig {
        learning_rate: 0.05,
        beta,
        clamped_phase: clamped,
        ..EpConfig::default()
    };
    let mut ep = DenNN::from_layers(layers);
    ep.train_sample(&x, &t, &cfg).unwrap();
    let after = flat(ep.layers());
    after.iter().zip(&before).map(|(a, b)| a - b).collect()
}

/// The parameter change of one backprop step from the same weights.
fn bp_delta(sizes: &[usize], seed: u64) -> Vec<f64> {
    let layers = Layers::new(sizes, seed).unwrap();
    let before = flat(&layers);
    let (x, t) = sample(sizes[0], sizes[sizes.len() - 1], seed + 100);
    let mut bp = Mlp::from_layers(layers);
    bp.train_sample(&x, &t, 0.05).unwrap();
    let after = flat(bp.layers());
    after.iter().zip(&before).map(|(a, b)| a - b).collect()
}

#[test]
fn two_hidden_layers_linearised_update_is_the_backprop_gradient() {
    // One, two and three outputs (the 331-pin edge's pose net has three:
    // the position and the angle's sine and cosine), and three hidden layers.
    for (sizes, seed) in [
        (vec![12, 40, 30, 1], 1),
        (vec![12, 40, 30, 2], 2),
        (vec![35, 64, 32, 3], 3),
        (vec![10, 24, 20, 16, 2], 4),
    ] {
        let ep = ep_delta(&sizes, ClampedPhase::Linearised, 1e-3, seed);
        let bp = bp_delta(&sizes, seed);
        let c = cosine(&ep, &bp);
        assert!(c > 0.999, "{sizes:?}: cosine {c}");
        // The step is beta times a contraction of the gradient: smaller.
        let (ne, nb) = (norm(&ep), norm(&bp));
        assert!(
            ne < 1e-3 * nb * 1.001 && ne > 1e-4 * nb,
            "{sizes:?}: {ne} vs {nb}"
        );
    }
}

#[test]
fn two_hidden_layers_closed_form_is_the_euler_equilibrium() {
    // A long, fine Euler relaxation of the clamped phase settles where the
    // closed form says (to first order in beta, so a small beta).
    for (sizes, seed) in [(vec![12, 40, 30, 2], 5), (vec![20, 30, 25, 3], 6)] {
        let closed = ep_delta(&sizes, ClampedPhase::Linearised, 1e-3, seed);
        let euler = ep_delta(
            &sizes,
            ClampedPhase::Euler { n_i: 3000, dt: 0.1 },
            1e-3,
            seed,
        );
        let diff: Vec<f64> = closed.iter().zip(&euler).map(|(a, b)| a - b).collect();
        let rel = norm(&diff) / norm(&euler);
        assert!(rel < 5e-3, "{sizes:?}: relative difference {rel}");
    }
}

#[test]
fn one_hidden_layer_keeps_its_closed_form() {
    // The general closed form reduces to the one-layer one: a net of one
    // hidden layer and 16 outputs (too many for the fused one-layer step)
    // moves along the same direction as backprop.
    let ep = ep_delta(&[12, 40, 16], ClampedPhase::Linearised, 1e-3, 7);
    let bp = bp_delta(&[12, 40, 16], 7);
    assert!(cosine(&ep, &bp) > 0.999);
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// `n` rows of `dim` correlated values and their two targets.
fn data(n: usize, dim: usize, seed: u64) -> Dataset {
    let (x, y) = support::correlated_rows(n, dim, seed);
    Dataset::new(x, y, n, dim, 2).expect("data")
}

#[test]
fn pose_models_with_two_hidden_layers_learn() {
    // Every kind with `hidden = [a, b]` trains at the default rates and
    // beats predicting the training mean by far on held-out rows.
    let (train, val) = (data(300, 30, 1), data(100, 30, 2));
    let mean = |j: usize| train.column(j).unwrap().iter().sum::<f32>() as f64 / 300.0;
    let base: Vec<[f64; 2]> = (0..val.n).map(|_| [mean(0), mean(1)]).collect();
    let base = mean_absolute_error(&base, &val);
    for kind in [ModelKind::PcaDenNN, ModelKind::PDenNN, ModelKind::Mlp] {
        let mut cfg = ModelConfig::preset(kind, Preset::Default);
        cfg.set_epochs(30);
        for net in [&mut cfg.pose, &mut cfg.position, &mut cfg.angle]
            .into_iter()
            .flatten()
        {
            net.hidden = vec![48, 24];
            net.n_components = Some(10);
        }
        cfg.validate().expect("config");
        let (model, _) = PoseModel::fit(&cfg, &train, &mut |_| {}).expect("fit");
        let arch = model.architecture();
        assert!(
            arch.iter().all(|(_, s)| s[1..s.len() - 1] == [48, 24]),
            "{arch:?}"
        );
        let mae = mean_absolute_error(&model.predict_batch(&val).unwrap(), &val);
        assert!(
            mae[0] < 0.25 * base[0] && mae[1] < 0.25 * base[1],
            "{kind}: {mae:?} against the mean's {base:?}"
        );
    }
}

/// Taps with a position (mm) and an angle over the full circle (deg):
/// features smooth in the position and the angle's direction.
fn full_circle(n: usize, seed: u64) -> Dataset {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut mix = ChaCha8Rng::seed_from_u64(11);
    let coef: Vec<[f32; 3]> = (0..16)
        .map(|_| std::array::from_fn(|_| mix.random_range(-1.5..1.5)))
        .collect();
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let r: f32 = rng.random_range(-3.0..3.0);
        let angle: f32 = rng.random_range(-180.0..180.0);
        let (s, c) = angle.to_radians().sin_cos();
        for k in &coef {
            x.push(2.0 * (k[0] * r / 3.0 + k[1] * s + k[2] * c).tanh());
        }
        y.extend([r, angle]);
    }
    Dataset::new(x, y, n, 16, 2).unwrap()
}

/// The fitted target scaling's spreads, from the model file.
fn target_spreads(model: &PoseModel) -> Vec<f64> {
    let (json, _) = model.to_bytes().unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let std = &v["target_scaling"]["std"];
    std.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_f64().unwrap())
        .collect()
}

#[test]
fn circular_weight_scales_only_the_sine_and_cosine_and_reads_back() {
    let (train, val) = (full_circle(300, 1), full_circle(100, 2));
    let mut angle = ModelTarget::new("pose_6", Unit::Deg);
    angle.circular = true;
    let outputs = [ModelTarget::new("pose_2", Unit::Mm), angle];
    let fit = |w: f64| {
        let mut cfg = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
        cfg.set_epochs(40);
        cfg.circular_weight = w;
        let net = cfg.pose.as_mut().unwrap();
        net.hidden = vec![48];
        net.n_components = Some(10);
        PoseModel::fit_targets(&cfg, &outputs, &train, None, &mut |_| {})
            .unwrap()
            .0
    };
    let (plain, weighted) = (fit(1.0), fit(3.0));
    let (a, b) = (target_spreads(&plain), target_spreads(&weighted));
    assert_eq!(a.len(), 3, "position, sine, cosine");
    assert_eq!(a[0], b[0], "the position's scaling is untouched");
    for c in [1, 2] {
        assert!((a[c] / b[c] - 3.0).abs() < 1e-12, "{a:?} / {b:?}");
    }
    // Written only when set; both read back in degrees over the circle.
    assert!(!plain.to_bytes().unwrap().0.contains("circular_weight"));
    assert!(weighted
        .to_bytes()
        .unwrap()
        .0
        .contains("\"circular_weight\": 3.0"));
    let truth: Vec<Vec<f64>> = (0..val.n)
        .map(|i| val.y_row(i).iter().map(|&v| f64::from(v)).collect())
        .collect();
    for model in [&plain, &weighted] {
        let pred = model.predict_targets_batch(&val).unwrap();
        let mae = target_mae(&outputs, &pred, &truth);
        assert!(mae[0] < 0.6 && mae[1] < 15.0, "{mae:?}");
    }
    let again = PoseModel::from_bytes(
        &weighted.to_bytes().unwrap().0,
        &weighted.to_bytes().unwrap().1,
    );
    assert_eq!(again.unwrap().config().circular_weight, 3.0);
}

#[test]
fn circular_weight_out_of_range_is_refused_by_name() {
    for w in [0.0, -1.0, f64::NAN, 1e3] {
        let mut cfg = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
        cfg.circular_weight = w;
        let err = cfg.validate().unwrap_err();
        assert!(err.to_string().contains("circular_weight"), "{w}: {err}");
    }
}
