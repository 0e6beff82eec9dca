//! Leaning on the pins (docs/learning.md, "Leaning on the pins"):
//! `pixel_dropout` sets a training frame's pixel features (the last
//! convolution's output) to 0. Theory first: with them masked in every
//! frame (`pixel_dropout = 1`) no error reaches the convolutions, so
//! neither rule moves them, and the model reads the pins alone. Then the
//! two stages: a fine-tune with the pixels on starts at the pin model's
//! figure and learns what only the pixels carry. Last, a fit at 0.5 is
//! seeded, thread-count independent, recorded and checked.
use crate::common;

use common::{moving_pair_frames, random, tiny_config, SIDE};
use tactrace_convnet::{
    ConvConfig, ConvError, ConvModel, Frames, InputKind, ModelKind, Network, Targets,
};

/// Pin values a frame.
const PINS: usize = 4;

/// Frames whose bright pair moves with the index, random pins, and two
/// targets: the first a function of the pins, the second the pair's
/// column (the pixels').
struct PinsAndPairs {
    count: usize,
    pixels: Vec<u8>,
    pins: Vec<f32>,
    targets: Vec<f64>,
}

impl PinsAndPairs {
    fn new(count: usize) -> Self {
        let (pixels, pair) = moving_pair_frames(count);
        let pins = random(count * PINS, 41);
        let targets = pins
            .chunks_exact(PINS)
            .zip(pair.chunks_exact(2))
            .flat_map(|(p, xy)| [2.0 * p[0] as f64 - p[1] as f64, xy[0]])
            .collect();
        PinsAndPairs {
            count,
            pixels,
            pins,
            targets,
        }
    }

    fn frames(&self) -> Frames<'_> {
        let frames = Frames::new(&self.pixels, self.count, SIDE, SIDE).unwrap();
        frames.with_pins(&self.pins, PINS).unwrap()
    }

    fn targets(&self) -> Targets<'_> {
        Targets::new(&self.targets, self.count, 2).unwrap()
    }
}

fn config(kind: ModelKind, pixel_dropout: f64) -> ConvConfig {
    let mut c = tiny_config(kind);
    c.input = InputKind::PinsAndPixels;
    c.pixel_dropout = pixel_dropout;
    c.epochs = 40;
    c.learning_rate = 1e-2;
    c
}

/// Mean absolute error of target `j` (of two).
fn mae(model: &ConvModel, frames: &Frames, targets: &[f64], j: usize) -> f64 {
    let y = model.predict_batch(frames).unwrap();
    let n = targets.len() / 2;
    (0..n)
        .map(|i| (y[2 * i + j] - targets[2 * i + j]).abs())
        .sum::<f64>()
        / n as f64
}

/// The dense layer's weights on the pixel features (all but the pins').
fn pixel_columns(net: &Network) -> Vec<f32> {
    let s = net.layout().layers()[1];
    net.parameters().weights[1]
        .chunks_exact(s.fan_in())
        .flat_map(|row| row[..s.window()].to_vec())
        .collect()
}

#[test]
fn masked_pixel_features_train_the_pins_alone() {
    let set = PinsAndPairs::new(96);
    let (count, pins, targets) = (set.count, &set.pins, &set.targets);
    let (frames, t) = (set.frames(), set.targets());
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let (model, _) = ConvModel::fit(&frames, &t, &config(kind, 1.0), 5).unwrap();
        let net = model.network();
        let init = Network::new(net.layout().clone(), net.activation(), 5);
        // No error reaches the convolution: its weights and biases are
        // bit for bit the initial ones, under EP as under backprop.
        assert_eq!(net.parameters().weights[0], init.parameters().weights[0]);
        assert_eq!(net.parameters().biases[0], init.parameters().biases[0]);
        assert!(pixel_columns(net).iter().all(|&w| w == 0.0));
        assert_ne!(net.parameters().weights[1], init.parameters().weights[1]);
        // Other pixels, the same pins: the same prediction.
        let dark = vec![0u8; count * SIDE * SIDE];
        let other = Frames::new(&dark, count, SIDE, SIDE).unwrap();
        let other = other.with_pins(pins, PINS).unwrap();
        assert_eq!(
            model.predict_batch(&frames).unwrap(),
            model.predict_batch(&other).unwrap()
        );
        // It reads the pins: the pins' target well below its spread.
        let first: Vec<f64> = targets.iter().step_by(2).copied().collect();
        let mean = first.iter().sum::<f64>() / count as f64;
        let spread = first.iter().map(|v| (v - mean).abs()).sum::<f64>() / count as f64;
        let error = mae(&model, &frames, targets, 0);
        assert!(error < 0.1 * spread, "{kind:?}: {error} against {spread}");
    }
}

#[test]
fn a_fine_tune_with_the_pixels_on_starts_at_the_pin_models_figure() {
    let set = PinsAndPairs::new(48);
    let targets = &set.targets;
    let (frames, t) = (set.frames(), set.targets());
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let (pin_model, _) = ConvModel::fit(&frames, &t, &config(kind, 1.0), 5).unwrap();
        let mut still = config(kind, 0.0);
        (still.epochs, still.learning_rate) = (1, 1e-12);
        let (barely, _) = pin_model
            .fine_tune_with(&frames, &t, &still, 6, None, &mut |_| ())
            .unwrap();
        let (a, b) = (
            pin_model.predict_batch(&frames).unwrap(),
            barely.predict_batch(&frames).unwrap(),
        );
        for (a, b) in a.iter().zip(&b) {
            assert!((a - b).abs() < 1e-6, "{kind:?}: {a} against {b}");
        }
        let mut second = config(kind, 0.0);
        second.epochs = 30;
        let (tuned, _) = pin_model
            .fine_tune_with(&frames, &t, &second, 6, None, &mut |_| ())
            .unwrap();
        assert!(pixel_columns(tuned.network()).iter().any(|&w| w != 0.0));
        let (before, after) = (
            mae(&pin_model, &frames, targets, 1),
            mae(&tuned, &frames, targets, 1),
        );
        assert!(after < 0.2 * before, "{kind:?}: column {before} -> {after}");
    }
}

#[test]
fn pixel_dropout_is_seeded_recorded_and_checked() {
    let set = PinsAndPairs::new(32);
    let (frames, t) = (set.frames(), set.targets());
    let fit = |c: &ConvConfig, threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| ConvModel::fit(&frames, &t, c, 3).unwrap().0)
    };
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let mut half = config(kind, 0.5);
        half.epochs = 3;
        let (one, three) = (fit(&half, 1), fit(&half, 3));
        assert_eq!(one.to_bytes().unwrap(), three.to_bytes().unwrap());
        let (json, tensors) = one.to_bytes().unwrap();
        assert!(json.contains("\"pixel_dropout\": 0.5"), "{json}");
        assert_eq!(ConvModel::from_bytes(&json, &tensors).unwrap(), one);
        half.pixel_dropout = 0.0;
        let plain = fit(&half, 1);
        assert!(!plain.to_bytes().unwrap().0.contains("pixel_dropout"));
        assert_ne!(plain.network().parameters(), one.network().parameters());
    }
    let mut pixels_only = config(ModelKind::ConvMlp, 0.5);
    pixels_only.input = InputKind::Pixels;
    let mut dense_only = config(ModelKind::ConvMlp, 0.5);
    dense_only.conv.clear();
    for bad in [config(ModelKind::ConvMlp, 1.5), pixels_only, dense_only] {
        match bad.validate() {
            Err(ConvError::Config { field, .. }) => assert_eq!(field, "pixel_dropout"),
            other => panic!("{other:?}"),
        }
    }
}
