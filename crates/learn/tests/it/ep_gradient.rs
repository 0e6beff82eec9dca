//! Equilibrium propagation against theory: at small beta its local update
//! points along the backprop gradient (ERRATA: eta beta grad / (1 + a) for one
//! output), the Euler free phase settles on the feed-forward pass, and Euler
//! steps lower the energy of eq. 3.10.
use crate::support;

use support::{cosine, sample};
use tactrace_learn::{ClampedPhase, DenNN, EpConfig, FreePhase, Layers, LrScaling, Mlp};

/// All parameters, canonical orientation, flattened.
fn flat(layers: &Layers) -> Vec<f64> {
    let mut out = Vec::new();
    for l in 1..layers.sizes().len() {
        out.extend(layers.weight(l).iter().map(|&v| v as f64));
        out.extend(layers.bias(l).iter().map(|&v| v as f64));
    }
    out
}

fn delta(before: &[f64], after: &Layers) -> Vec<f64> {
    flat(after).iter().zip(before).map(|(a, b)| a - b).collect()
}

/// Parameter change of one EP step and of one backprop step from the same
/// weights on the same sample.
fn ep_and_backprop(sizes: &[usize], cfg: &EpConfig, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let layers = Layers::new(sizes, seed).unwrap();
    let before = flat(&layers);
    let (x, t) = sample(sizes[0], sizes[sizes.len() - 1], seed + 100);
    let mut ep = DenNN::from_layers(layers.clone());
    ep.train_sample(&x, &t, cfg).unwrap();
    let mut bp = Mlp::from_layers(layers);
    bp.train_sample(&x, &t, cfg.learning_rate).unwrap();
    (delta(&before, ep.layers()), delta(&before, bp.layers()))
}

fn small_beta(clamped: ClampedPhase) -> EpConfig {
    // A large enough eta keeps the f32 weight changes well above rounding.
    EpConfig {
        learning_rate: 0.05,
        beta: 1e-3,
        clamped_phase: clamped,
        ..EpConfig::default()
    }
}

#[test]
fn closed_form_update_is_the_backprop_gradient_for_one_output() {
    let (ep, bp) = ep_and_backprop(&[35, 200, 1], &small_beta(ClampedPhase::Linearised), 1);
    let c = cosine(&ep, &bp);
    assert!(c > 0.999_9, "cosine {c}");
}

#[test]
fn closed_form_update_ratio_is_beta_over_one_plus_a() {
    let layers = Layers::new(&[10, 50, 1], 3).unwrap();
    let (x, t) = sample(10, 1, 4);
    // a = sum_i W2_i^2 phi'(h_i)^2 at the free state.
    let w1 = layers.weight(1);
    let w2 = layers.weight(2);
    let a: f64 = (0..50)
        .map(|i| {
            let h: f64 = (0..10)
                .map(|k| w1[k * 50 + i] as f64 * x[k] as f64)
                .sum::<f64>()
                + layers.bias(1)[i] as f64;
            let p = 1.0 / (1.0 + (-h).exp());
            (w2[i] as f64 * p * (1.0 - p)).powi(2)
        })
        .sum();
    let beta = 0.01;
    let cfg = EpConfig {
        learning_rate: 1e-3,
        beta,
        ..EpConfig::default()
    };
    let before = flat(&layers);
    let mut ep = DenNN::from_layers(layers.clone());
    ep.train_sample(&x, &t, &cfg).unwrap();
    let mut bp = Mlp::from_layers(layers);
    bp.train_sample(&x, &t, 1e-3).unwrap();
    let (de, db) = (delta(&before, ep.layers()), delta(&before, bp.layers()));
    // Compare on the output weights (linear in e2, no second-order term).
    let n2 = 50;
    let w2_start = 10 * 50 + 50;
    let ratio: f64 = (0..n2)
        .map(|i| de[w2_start + i] / db[w2_start + i])
        .sum::<f64>()
        / n2 as f64;
    let expected = beta / (1.0 + a);
    assert!(
        (ratio - expected).abs() / expected < 2e-2,
        "ratio {ratio}, expected {expected}"
    );
}

#[test]
fn closed_form_update_is_the_backprop_gradient_for_two_outputs() {
    let (ep, bp) = ep_and_backprop(&[30, 120, 2], &small_beta(ClampedPhase::Linearised), 2);
    let c = cosine(&ep, &bp);
    assert!(c > 0.99, "cosine {c}");
}

#[test]
fn euler_clamped_phase_update_is_the_backprop_gradient() {
    let cfg = small_beta(ClampedPhase::Euler { n_i: 200, dt: 0.2 });
    let (ep, bp) = ep_and_backprop(&[20, 80, 1], &cfg, 5);
    let c = cosine(&ep, &bp);
    assert!(c > 0.99, "cosine {c}");
}

#[test]
fn deep_net_update_is_the_backprop_gradient() {
    let cfg = small_beta(ClampedPhase::Euler { n_i: 400, dt: 0.2 });
    let (ep, bp) = ep_and_backprop(&[12, 40, 30, 2], &cfg, 6);
    let c = cosine(&ep, &bp);
    assert!(c > 0.99, "cosine {c}");
}

#[test]
fn report_euler_free_phase_converges_to_feed_forward() {
    let net = DenNN::new(&[15, 60, 1], 8).unwrap();
    let (x, t) = sample(15, 1, 9);
    let mut ff = [0.0f32];
    net.predict(&x, &mut ff).unwrap();
    // A tiny learning rate keeps the weights (and so the fixed point) put;
    // the stored states are those after the clamped phase, so use beta -> 0.
    let cfg = EpConfig {
        learning_rate: 1e-12,
        beta: 1e-9,
        free_phase: FreePhase::Euler { n_i: 60, dt: 0.5 },
        clamped_phase: ClampedPhase::Euler { n_i: 1, dt: 0.5 },
        ..EpConfig::default()
    };
    let mut net2 = net.clone();
    net2.train_sample(&x, &t, &cfg).unwrap();
    let y = net2.last_states()[2][0];
    assert!(
        (y - ff[0]).abs() < 1e-4,
        "Euler output {y} vs feed-forward {}",
        ff[0]
    );
}

#[test]
fn euler_steps_lower_the_free_energy() {
    let net = DenNN::new(&[8, 30, 2], 10).unwrap();
    let (x, t) = sample(8, 2, 11);
    let mut energies = Vec::new();
    for n_i in [1, 3, 10, 40] {
        let cfg = EpConfig {
            learning_rate: 1e-12,
            beta: 1e-9,
            free_phase: FreePhase::Euler { n_i, dt: 0.3 },
            clamped_phase: ClampedPhase::Euler { n_i: 1, dt: 1e-9 },
            ..EpConfig::default()
        };
        let mut probe = net.clone();
        probe.train_sample(&x, &t, &cfg).unwrap();
        energies.push(probe.energy(probe.last_states(), None, 0.0));
    }
    assert!(
        energies.windows(2).all(|w| w[1] < w[0]),
        "energies {energies:?}"
    );
    assert!(energies[3] < 1e-6, "energies {energies:?}");
}

#[test]
fn wrong_lengths_are_errors() {
    let mut net = DenNN::new(&[4, 6, 1], 0).unwrap();
    let cfg = EpConfig::default();
    assert!(net.train_sample(&[0.0; 3], &[0.0], &cfg).is_err());
    assert!(net.train_sample(&[0.0; 4], &[0.0, 1.0], &cfg).is_err());
    assert!(net.predict(&[0.0; 5], &mut [0.0]).is_err());
    assert!(DenNN::new(&[4], 0).is_err());
    assert!(DenNN::new(&[4, 0, 1], 0).is_err());
}

#[test]
fn fan_in_scaling_divides_each_layer_step_by_its_fan_in() {
    let sizes = [6, 40, 1];
    let layers = Layers::new(&sizes, 12).unwrap();
    let (x, t) = sample(6, 1, 13);
    let before = flat(&layers);
    let mut plain = Mlp::from_layers(layers.clone());
    // A large rate keeps the f32 weight changes well above rounding.
    plain.train_sample(&x, &t, 1.0).unwrap();
    let mut scaled = Mlp::from_layers(layers.clone()).with_lr_scaling(LrScaling::FanIn);
    scaled.train_sample(&x, &t, 1.0).unwrap();
    let (dp, ds) = (
        delta(&before, plain.layers()),
        delta(&before, scaled.layers()),
    );
    // Parameter blocks in `flat` order: W1, b1, W2, b2.
    let blocks = [
        (0, 6 * 40, 6.0),
        (240, 40, 6.0),
        (280, 40, 40.0),
        (320, 1, 40.0),
    ];
    for (start, len, fan_in) in blocks {
        for i in start..start + len {
            if dp[i].abs() > 1e-4 {
                let r = ds[i] / dp[i];
                assert!((r * fan_in - 1.0).abs() < 1e-2, "param {i}: ratio {r}");
            }
        }
    }
    // The EP twin applies the same scaling: its update still points along
    // the (scaled) backprop step.
    let cfg = EpConfig {
        learning_rate: 0.05,
        lr_scaling: LrScaling::FanIn,
        beta: 1e-3,
        ..EpConfig::default()
    };
    let mut ep = DenNN::from_layers(layers.clone());
    ep.train_sample(&x, &t, &cfg).unwrap();
    let c = cosine(&delta(&before, ep.layers()), &ds);
    assert!(c > 0.99, "cosine {c}");
}
