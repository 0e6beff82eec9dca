//! The residual on a pin model (`input = "pin_model_and_pixels"`,
//! docs/learning.md, "The residual on a pin model"): each frame's side
//! values are a base prediction of its targets, the output is the base
//! plus the network's correction. Theory first: from the zeroed output
//! layer, the EP update on the corrections `t - z` points along the
//! backprop gradient. Then the model: it starts at the base's figure,
//! learns what the base lacks and the pixels carry (conv-mlp and
//! conv-dennn alike), reloads bit for bit, refuses a base of another
//! width.
use crate::common;

use common::{ep_rule, moving_pair_frames, random, small_conv, tiny_config, SIDE};
use tactrace_convnet::{
    Activation, ConvConfig, ConvError, ConvModel, Frames, InputKind, Layout, ModelKind, Network,
    Rule, Targets,
};

/// The base of the moving pair's frames: right in the column, the rows'
/// mean in the row (what the pixels must add).
fn base_of(targets: &[f64]) -> Vec<f32> {
    let rows: Vec<f64> = targets.chunks_exact(2).map(|t| t[1]).collect();
    let mean = rows.iter().sum::<f64>() / rows.len() as f64;
    targets
        .chunks_exact(2)
        .flat_map(|t| [t[0] as f32, mean as f32])
        .collect()
}

/// `count` moving-pair frames, their targets and their base.
fn residual_set(count: usize) -> (Vec<u8>, Vec<f64>, Vec<f32>) {
    let (pixels, targets) = moving_pair_frames(count);
    let base = base_of(&targets);
    (pixels, targets, base)
}

/// The frames of `pixels`, each with its two values of `base`.
fn with_base<'a>(pixels: &'a [u8], base: &'a [f32]) -> Frames<'a> {
    let frames = Frames::new(pixels, base.len() / 2, SIDE, SIDE).unwrap();
    frames.with_pins(base, 2).unwrap()
}

fn residual_config(kind: ModelKind) -> ConvConfig {
    let mut c = tiny_config(kind);
    c.input = InputKind::PinModelAndPixels;
    c.epochs = 40;
    c.learning_rate = 3e-3;
    c
}

/// Mean absolute error of `predicted` (`count x 2`) against `targets`.
fn mae(predicted: &[f64], targets: &[f64]) -> f64 {
    let sum: f64 = predicted
        .iter()
        .zip(targets)
        .map(|(y, t)| (y - t).abs())
        .sum();
    sum / targets.len() as f64
}

#[test]
fn ep_update_from_the_zeroed_output_points_along_the_backprop_gradient() {
    let n = 3;
    let layout = Layout::new(12, 12, &small_conv(), &[10], 2).unwrap();
    let layout = layout.with_side_inputs(2, 2).unwrap();
    for (k, act) in [Activation::Tanh, Activation::Sigmoid]
        .into_iter()
        .enumerate()
    {
        let mut net = Network::new(layout.clone(), act, 40 + k as u64);
        let last = net.layout().depth() - 1;
        net.parameters_mut().weights[last].fill(0.0);
        net.parameters_mut().biases[last].fill(0.0);
        let (x, z, t) = (random(n * 144, 1), random(n * 2, 2), random(n * 2, 3));
        // The corrections the network is fitted to: the target less the base.
        let c: Vec<f32> = t.iter().zip(&z).map(|(t, z)| t - z).collect();
        let bp = net.gradient_pins((&x, &z), &c, n, Rule::Backprop).unwrap();
        let est = net.gradient_pins((&x, &z), &c, n, ep_rule(0.01)).unwrap();
        assert!(est.cosine(&bp) > 0.99, "{act:?}: {}", est.cosine(&bp));
        // From zero output weights only the output layer learns at first.
        assert!(bp.weights[0].iter().all(|&g| g == 0.0));
        assert!(bp.weights[last].iter().any(|g| g.abs() > 1e-3));
    }
}

#[test]
fn a_fresh_residual_model_predicts_its_base() {
    let count = 48;
    let (pixels, targets, base) = residual_set(count);
    let frames = with_base(&pixels, &base);
    let t = Targets::new(&targets, count, 2).unwrap();
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let mut c = residual_config(kind);
        (c.epochs, c.learning_rate) = (1, 1e-30);
        let (model, history) =
            ConvModel::fit_with(&frames, &t, &c, 2, Some((frames, t)), &mut |_| ()).unwrap();
        let y = model.predict_batch(&frames).unwrap();
        for (y, b) in y.iter().zip(&base) {
            assert!(
                (y - *b as f64).abs() < 1e-5 * (1.0 + b.abs() as f64),
                "{y} against {b}"
            );
        }
        let at_start = &history.epochs[0].validation.as_ref().unwrap().mae;
        let base_mae = mae(
            &base.iter().map(|&b| b as f64).collect::<Vec<_>>(),
            &targets,
        );
        let mean: f64 = at_start.iter().sum::<f64>() / 2.0;
        assert!(
            (mean - base_mae).abs() < 1e-5,
            "{kind:?}: {mean} against {base_mae}"
        );
    }
}

#[test]
fn a_residual_model_learns_what_the_base_lacks_by_either_rule() {
    let count = 96;
    let (pixels, targets, base) = residual_set(count);
    let frames = with_base(&pixels, &base);
    let t = Targets::new(&targets, count, 2).unwrap();
    let base_mae = mae(
        &base.iter().map(|&b| b as f64).collect::<Vec<_>>(),
        &targets,
    );
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let (model, _) = ConvModel::fit(&frames, &t, &residual_config(kind), 1).unwrap();
        let fitted = mae(&model.predict_batch(&frames).unwrap(), &targets);
        assert!(
            fitted < 0.5 * base_mae,
            "{kind:?}: {fitted} against the base's {base_mae}"
        );
    }
}

#[test]
fn a_residual_model_reloads_bit_for_bit_and_refuses_another_base_width() {
    let count = 24;
    let (pixels, targets) = moving_pair_frames(count);
    let base = base_of(&targets);
    let bare = Frames::new(&pixels, count, SIDE, SIDE).unwrap();
    let frames = bare.with_pins(&base, 2).unwrap();
    let t = Targets::new(&targets, count, 2).unwrap();
    let mut c = residual_config(ModelKind::ConvMlp);
    c.epochs = 2;
    let (model, _) = ConvModel::fit(&frames, &t, &c, 3).unwrap();
    let (json, weights) = model.to_bytes().unwrap();
    assert!(
        json.contains("\"input\": \"pin_model_and_pixels\""),
        "{json}"
    );
    let back = ConvModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(back, model);
    assert_eq!(
        back.predict_batch(&frames).unwrap(),
        model.predict_batch(&frames).unwrap()
    );
    let wide = random(count * 3, 5);
    let refused = ConvModel::fit(&bare.with_pins(&wide, 3).unwrap(), &t, &c, 3);
    assert!(matches!(
        refused,
        Err(ConvError::PinCount {
            expected: 2,
            got: 3
        })
    ));
    assert!(matches!(
        model.predict_batch(&bare),
        Err(ConvError::PinCount {
            expected: 2,
            got: 0
        })
    ));
}

#[test]
fn pixel_rate_scales_the_convolutions_steps_only() {
    let count = 24;
    let (pixels, targets) = moving_pair_frames(count);
    let frames = Frames::new(&pixels, count, SIDE, SIDE).unwrap();
    let t = Targets::new(&targets, count, 2).unwrap();
    let mut c = tiny_config(ModelKind::ConvMlp);
    (c.epochs, c.learning_rate) = (1, 1e-2);
    let (plain, _) = ConvModel::fit(&frames, &t, &c, 4).unwrap();
    c.pixel_rate = 1e-9;
    let (slow, _) = ConvModel::fit(&frames, &t, &c, 4).unwrap();
    let layout = Layout::new(SIDE, SIDE, &c.conv, &c.dense, 2).unwrap();
    let start = Network::new(layout, c.activation, 4);
    let moved = |m: &ConvModel, l: usize| -> f32 {
        let (w, w0) = (
            &m.network().parameters().weights[l],
            &start.parameters().weights[l],
        );
        w.iter()
            .zip(w0)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max)
    };
    assert!(
        moved(&slow, 0) < 1e-8,
        "the convolution moved {}",
        moved(&slow, 0)
    );
    assert!(moved(&plain, 0) > 1e-3 && moved(&slow, 1) > 1e-3);
    let (json, _) = plain.to_bytes().unwrap();
    assert!(!json.contains("pixel_rate"), "{json}");
    c.pixel_rate = 0.0;
    assert!(matches!(c.validate(), Err(ConvError::Config { .. })));
}
