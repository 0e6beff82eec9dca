//! The pins-and-pixels network (docs/learning.md, "Pins and pixels"):
//! the pin vector appended to the flattened convolutions, as more inputs
//! of the first dense layer. Theory first: the EP update points along the
//! backprop gradient on a small hybrid net, backprop agrees with finite
//! differences on the pins' weights, and the pins' weights set to zero
//! give the pixels-only network's output. Then the model: it learns a
//! target the pins carry and the pixels do not, saves and reloads bit
//! for bit, and refuses frames without their pins.
use crate::common;

use common::{ep_rule, random, small_conv, tiny_config};
use tactrace_convnet::{
    Activation, ConvConfig, ConvError, ConvModel, Frames, InputKind, Layout, ModelKind, Network,
    Rule, Targets,
};

/// Pin values a frame in the small net.
const PINS: usize = 6;

/// The small net of the theory tests, 12 x 12 px, two convolutions and a
/// dense layer of 10, with `PINS` side inputs on the dense layer.
fn hybrid_layout() -> Layout {
    let plain = Layout::new(12, 12, &small_conv(), &[10], 2).expect("layout");
    plain.with_side_inputs(2, PINS).expect("side inputs")
}

/// The pins' columns of the dense layer's weights (`cout x fan_in`, the
/// pins last in each row).
fn pin_columns(net: &Network, w: &[f32]) -> Vec<f64> {
    let s = net.layout().layers()[2];
    w.chunks_exact(s.fan_in())
        .flat_map(|row| row[s.window()..].iter().map(|&v| v as f64))
        .collect()
}

fn cosine(a: &[f64], b: &[f64]) -> f64 {
    let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let na: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    let nb: f64 = b.iter().map(|x| x * x).sum::<f64>().sqrt();
    dot / (na * nb)
}

#[test]
fn ep_update_of_a_hybrid_net_points_along_the_backprop_gradient() {
    let n = 3;
    for (k, act) in [Activation::Tanh, Activation::Sigmoid, Activation::Relu]
        .into_iter()
        .enumerate()
    {
        let net = Network::new(hybrid_layout(), act, 20 + k as u64);
        let (x, z, t) = (random(n * 144, 1), random(n * PINS, 2), random(n * 2, 3));
        let bp = net.gradient_pins((&x, &z), &t, n, Rule::Backprop).unwrap();
        let est = net.gradient_pins((&x, &z), &t, n, ep_rule(0.01)).unwrap();
        assert!(est.cosine(&bp) > 0.99, "{act:?}: {}", est.cosine(&bp));
        let (wb, we) = (&bp.weights[2], &est.weights[2]);
        let pins = cosine(&pin_columns(&net, we), &pin_columns(&net, wb));
        assert!(pins > 0.99, "{act:?}: the pins' weights, cosine {pins}");
        assert!(pin_columns(&net, wb).iter().any(|g| g.abs() > 1e-4));
    }
}

#[test]
fn backprop_gradient_of_the_pin_weights_matches_finite_differences() {
    let n = 2;
    let mut net = Network::new(hybrid_layout(), Activation::Tanh, 7);
    let (x, z, t) = (random(n * 144, 4), random(n * PINS, 5), random(n * 2, 6));
    let bp = net.gradient_pins((&x, &z), &t, n, Rule::Backprop).unwrap();
    let loss = |net: &Network| -> f64 {
        let y = net.feed_forward_pins(&x, &z, n).unwrap();
        y.iter()
            .zip(&t)
            .map(|(y, t)| 0.5 * ((y - t) as f64).powi(2))
            .sum()
    };
    let s = net.layout().layers()[2];
    let h = 1e-2f32;
    for unit in [0, 4, 9] {
        for j in [0, 3, PINS - 1] {
            let i = unit * s.fan_in() + s.window() + j;
            let v0 = net.parameters().weights[2][i];
            net.parameters_mut().weights[2][i] = v0 + h;
            let up = loss(&net);
            net.parameters_mut().weights[2][i] = v0 - h;
            let down = loss(&net);
            net.parameters_mut().weights[2][i] = v0;
            let fd = (up - down) / (2.0 * h as f64);
            let an = bp.weights[2][i] as f64;
            assert!(
                (fd - an).abs() < 1e-3 + 1e-2 * an.abs(),
                "unit {unit} pin {j}: finite differences {fd}, backprop {an}"
            );
        }
    }
}

#[test]
fn zero_pin_weights_give_the_pixels_only_output() {
    let n = 2;
    let hybrid = Network::new(hybrid_layout(), Activation::Tanh, 9);
    let plain_layout = Layout::new(12, 12, &small_conv(), &[10], 2).unwrap();
    let mut params = hybrid.parameters().clone();
    let s = hybrid.layout().layers()[2];
    params.weights[2] = params.weights[2]
        .chunks_exact(s.fan_in())
        .flat_map(|row| row[..s.window()].to_vec())
        .collect();
    let plain = Network::from_parts(plain_layout, Activation::Tanh, params).unwrap();
    let mut zeroed = hybrid.clone();
    for row in zeroed.parameters_mut().weights[2].chunks_exact_mut(s.fan_in()) {
        row[s.window()..].fill(0.0);
    }
    let (x, z) = (random(n * 144, 10), random(n * PINS, 11));
    let y_plain = plain.feed_forward(&x, n).unwrap();
    assert_eq!(zeroed.feed_forward_pins(&x, &z, n).unwrap(), y_plain);
    assert_ne!(hybrid.feed_forward_pins(&x, &z, n).unwrap(), y_plain);
}

/// Frames that are all alike (the pixels say nothing) and pin vectors
/// whose first two values set the two targets.
fn blank_frames_and_pins(count: usize) -> (Vec<u8>, Vec<f32>, Vec<f64>) {
    let pins = random(count * 4, 31);
    let pixels = vec![90u8; count * 12 * 12];
    let targets = pins
        .chunks_exact(4)
        .flat_map(|p| [2.0 * p[0] as f64 + 1.0, 3.0 * p[1] as f64 - p[2] as f64])
        .collect();
    (pixels, pins, targets)
}

fn hybrid_config(kind: ModelKind) -> ConvConfig {
    let mut c = tiny_config(kind);
    c.input = InputKind::PinsAndPixels;
    c.epochs = 30;
    c.learning_rate = 3e-3;
    c
}

/// Mean absolute error of the model's predictions, both targets.
fn mae(model: &ConvModel, frames: &Frames, targets: &[f64]) -> f64 {
    let y = model.predict_batch(frames).unwrap();
    y.iter()
        .zip(targets)
        .map(|(y, t)| (y - t).abs())
        .sum::<f64>()
        / targets.len() as f64
}

#[test]
fn a_hybrid_model_learns_what_only_the_pins_carry() {
    let count = 96;
    let (pixels, pins, targets) = blank_frames_and_pins(count);
    let frames = Frames::new(&pixels, count, 12, 12)
        .unwrap()
        .with_pins(&pins, 4)
        .unwrap();
    let t = Targets::new(&targets, count, 2).unwrap();
    let spread = {
        let mean = targets.iter().sum::<f64>() / targets.len() as f64;
        targets.iter().map(|v| (v - mean).abs()).sum::<f64>() / targets.len() as f64
    };
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let (hybrid, _) = ConvModel::fit(&frames, &t, &hybrid_config(kind), 1).unwrap();
        let mut pixels_only = hybrid_config(kind);
        pixels_only.input = InputKind::Pixels;
        let (plain, _) = ConvModel::fit(&frames, &t, &pixels_only, 1).unwrap();
        let (e_hybrid, e_plain) = (
            mae(&hybrid, &frames, &targets),
            mae(&plain, &frames, &targets),
        );
        assert!(
            e_hybrid < 0.3 * e_plain && e_plain > 0.5 * spread,
            "{kind:?}: hybrid {e_hybrid}, pixels only {e_plain}, spread {spread}"
        );
        assert_eq!(hybrid.pin_inputs(), 4);
        assert_eq!(plain.pin_inputs(), 0);
    }
}

#[test]
fn a_hybrid_model_reloads_bit_for_bit_and_refuses_frames_without_pins() {
    let count = 24;
    let (pixels, pins, targets) = blank_frames_and_pins(count);
    let bare = Frames::new(&pixels, count, 12, 12).unwrap();
    let frames = bare.with_pins(&pins, 4).unwrap();
    let t = Targets::new(&targets, count, 2).unwrap();
    let mut config = hybrid_config(ModelKind::ConvMlp);
    config.epochs = 2;
    let (model, _) = ConvModel::fit(&frames, &t, &config, 3).unwrap();
    let (json, weights) = model.to_bytes().unwrap();
    assert!(json.contains("\"input\": \"pins_and_pixels\"") && json.contains("\"pins\": 4"));
    let back = ConvModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(back, model);
    assert_eq!(
        back.predict_batch(&frames).unwrap(),
        model.predict_batch(&frames).unwrap()
    );
    // One frame and its pins alone: the batch's figures, to the rounding
    // of another product width.
    let one = back.predict_with_pins(bare.frame(5), frames.pins(5).unwrap());
    let batch = model.predict_batch(&frames).unwrap();
    for (a, b) in one.unwrap().iter().zip(&batch[10..12]) {
        assert!((a - b).abs() < 1e-5 * (1.0 + b.abs()), "{a} against {b}");
    }
    let refused =
        |r: Result<_, ConvError>| matches!(r, Err(ConvError::PinCount { expected: 4, .. }));
    assert!(refused(model.predict_batch(&bare)));
    assert!(refused(model.predict(bare.frame(0))));
    assert!(refused(model.predict_with_pins(bare.frame(0), &[0.0; 3])));
    let no_pins = ConvModel::fit(&bare, &t, &config, 3);
    assert!(matches!(no_pins, Err(ConvError::PinCount { got: 0, .. })));
    let bad = [f32::NAN; 4 * 24];
    assert!(matches!(
        bare.with_pins(&bad, 4),
        Err(ConvError::PinNonFinite { row: 0, .. })
    ));
    // A pixels-only model's file says nothing of pins, and ignores them.
    config.input = InputKind::Pixels;
    let (plain, _) = ConvModel::fit(&frames, &t, &config, 3).unwrap();
    let (json, _) = plain.to_bytes().unwrap();
    assert!(!json.contains("pins"), "{json}");
    assert_eq!(
        plain.predict_batch(&frames).unwrap(),
        plain.predict_batch(&bare).unwrap()
    );
}

#[test]
fn the_input_kind_reads_from_a_configuration() {
    let json = r#"{"kind": "conv-mlp", "conv": [], "dense": [4], "activation": "tanh",
        "input_centring": "global", "ep": {"beta": 0.1, "nudging": "symmetric",
        "free_phase": "feed_forward", "clamped_phase": {"sweeps": {"iterations": 1}}},
        "epochs": 1, "batch_size": 2, "chunk_size": 2, "learning_rate": 0.001,
        "final_lr_fraction": 0.1, "weight_decay": 0.0, "shift_augment": 0,
        "input": "pins_and_pixels"}"#;
    let c: ConvConfig = serde_json::from_str(json).unwrap();
    assert_eq!(c.input, InputKind::PinsAndPixels);
    assert_eq!(ConvConfig::new(ModelKind::ConvMlp).input, InputKind::Pixels);
    let bad = json.replace("pins_and_pixels", "pins");
    assert!(serde_json::from_str::<ConvConfig>(&bad).is_err());
}
