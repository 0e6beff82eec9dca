//! Dropout that EP keeps (`dense_dropout`, `channel_dropout`; issue 22's
//! accuracy work): with one mask a frame held through the free and both
//! nudged phases, the EP update approaches the backprop gradient of the
//! masked network as beta shrinks; that gradient is the masked network's
//! (finite differences); a unit dropped in every frame learns nothing; a
//! fit with dropout is seeded, thread-count independent, and predicts
//! with no mask.
use crate::common;

use common::{ep_rule, random, small_net, tiny_config, SIDE};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_convnet::{
    Activation, ConvConfig, ConvError, ConvModel, Frames, ModelKind, Network, Parameters, Rule,
    Targets,
};

const N: usize = 3;

/// Masks (frame by frame) for layer 1 (channels, p = 0.5) and layer 2
/// (dense units, p = 0.5, unit 0 dropped in every frame); scale 2 kept.
fn masks(net: &Network, seed: u64) -> Vec<Vec<f32>> {
    let layers = net.layout().layers();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut draw = || if rng.random::<bool>() { 2.0 } else { 0.0 };
    let mut out = vec![Vec::new(); layers.len()];
    let l1 = &layers[1];
    for _ in 0..N {
        for _ in 0..l1.cout {
            let v = draw();
            out[1].extend(std::iter::repeat_n(v, l1.positions()));
        }
    }
    for _ in 0..N {
        for u in 0..layers[2].cout {
            let v = draw();
            out[2].push(if u == 0 { 0.0 } else { v });
        }
    }
    out
}

fn loss(net: &Network, x: &[f32], t: &[f32], m: &[Vec<f32>]) -> f64 {
    let y = net.feed_forward_masked(x, N, m).unwrap();
    y.iter()
        .zip(t)
        .map(|(y, t)| 0.5 * ((y - t) as f64).powi(2))
        .sum()
}

#[test]
fn ep_update_with_a_dropout_mask_approaches_the_masked_backprop_gradient() {
    let x = random(N * 144, 1);
    let t = random(N * 2, 2);
    for (k, act) in [Activation::Tanh, Activation::Sigmoid, Activation::Relu]
        .into_iter()
        .enumerate()
    {
        let net = small_net(act, 2, 20 + k as u64);
        let m = masks(&net, 3 + k as u64);
        let bp = net.gradient_masked(&x, &t, N, Rule::Backprop, &m).unwrap();
        let plain = net.gradient(&x, &t, N, Rule::Backprop).unwrap();
        assert!(
            bp.cosine(&plain) < 0.99,
            "{act:?}: the mask changes nothing"
        );
        for beta in [0.05, 0.01] {
            let est = net.gradient_masked(&x, &t, N, ep_rule(beta), &m).unwrap();
            let cos = est.cosine(&bp);
            assert!(cos > 0.99, "{act:?} beta {beta}: cosine {cos}");
        }
    }
}

#[test]
fn masked_backprop_is_the_masked_networks_gradient() {
    let x = random(N * 144, 4);
    let t = random(N * 2, 5);
    let mut net = small_net(Activation::Tanh, 2, 7);
    let m = masks(&net, 8);
    let bp = net.gradient_masked(&x, &t, N, Rule::Backprop, &m).unwrap();
    let h = 1e-2f32;
    let mut checked = 0;
    for l in 0..net.layout().depth() {
        let len = net.parameters().weights[l].len();
        for i in (0..len).step_by(len / 7 + 1) {
            let g = bp.weights[l][i] as f64;
            let w = net.parameters().weights[l][i];
            net.parameters_mut().weights[l][i] = w + h;
            let up = loss(&net, &x, &t, &m);
            net.parameters_mut().weights[l][i] = w - h;
            let down = loss(&net, &x, &t, &m);
            net.parameters_mut().weights[l][i] = w;
            let fd = (up - down) / (2.0 * h as f64);
            assert!(
                (fd - g).abs() < 2e-3 + 2e-2 * g.abs(),
                "W{} [{i}]: finite difference {fd}, backprop {g}",
                l + 1
            );
            checked += 1;
        }
    }
    assert!(checked > 20);
}

#[test]
fn a_unit_dropped_in_every_frame_learns_nothing() {
    let x = random(N * 144, 6);
    let t = random(N * 2, 7);
    let net = small_net(Activation::Tanh, 2, 9);
    let m = masks(&net, 10);
    let fan_in = net.layout().layers()[2].fan_in();
    for rule in [Rule::Backprop, ep_rule(0.1)] {
        let g: Parameters = net.gradient_masked(&x, &t, N, rule, &m).unwrap();
        // Unit 0 of the dense layer (layer index 2): its incoming weights,
        // its bias and its outgoing weights get no update.
        assert!(g.weights[2][..fan_in].iter().all(|&v| v == 0.0));
        assert_eq!(g.biases[2][0], 0.0);
        assert!(g.weights[3].iter().step_by(10).all(|&v| v == 0.0));
        assert!(g.weights[2][fan_in..].iter().any(|&v| v != 0.0));
    }
}

fn fit(config: &ConvConfig, threads: usize) -> ConvModel {
    let count = 32;
    let (mut pixels, mut targets) = (Vec::new(), Vec::new());
    for k in 0..count {
        let (cx, cy) = (1 + (k * 7) % (SIDE - 3), 1 + (k * 5) % (SIDE - 2));
        let mut f = vec![10u8; SIDE * SIDE];
        f[cy * SIDE + cx] = 240;
        pixels.extend(f);
        targets.extend([cx as f64, cy as f64]);
    }
    let f = Frames::new(&pixels, count, SIDE, SIDE).unwrap();
    let t = Targets::new(&targets, count, 2).unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| ConvModel::fit(&f, &t, config, 3).unwrap().0)
}

fn config(kind: ModelKind, dense: f64, channel: f64) -> ConvConfig {
    let mut c = tiny_config(kind);
    c.dense_dropout = dense;
    c.channel_dropout = channel;
    c
}

#[test]
fn dropout_fit_is_seeded_and_only_in_training() {
    for kind in [ModelKind::ConvDennn, ModelKind::ConvMlp] {
        let dropped = fit(&config(kind, 0.3, 0.2), 1);
        let again = fit(&config(kind, 0.3, 0.2), 3);
        assert_eq!(dropped.to_bytes().unwrap(), again.to_bytes().unwrap());
        let plain = fit(&config(kind, 0.0, 0.0), 1);
        assert_ne!(dropped.network().parameters(), plain.network().parameters());
        assert!(!plain.to_bytes().unwrap().0.contains("dropout"));
        // Prediction draws no mask: the same frame, the same numbers, and
        // they are the plain feed-forward pass of the saved weights.
        let frame = vec![50u8; SIDE * SIDE];
        assert_eq!(
            dropped.predict(&frame).unwrap(),
            dropped.predict(&frame).unwrap()
        );
        let (json, tensors) = dropped.to_bytes().unwrap();
        assert!(json.contains("\"dense_dropout\": 0.3"), "{json}");
        let back = ConvModel::from_bytes(&json, &tensors).unwrap();
        assert_eq!(
            back.predict(&frame).unwrap(),
            dropped.predict(&frame).unwrap()
        );
    }
    for (dense, channel, field) in [(0.95, 0.0, "dense_dropout"), (0.0, -0.1, "channel_dropout")] {
        match config(ModelKind::ConvMlp, dense, channel).validate() {
            Err(ConvError::Config { field: f, .. }) => assert_eq!(f, field),
            other => panic!("{dense} {channel}: {other:?}"),
        }
    }
}
