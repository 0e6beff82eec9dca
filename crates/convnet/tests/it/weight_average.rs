//! Averaged weights (`weight_average`, issue 22's accuracy work): the
//! model keeps an exponential moving average of each network's parameters
//! over the optimiser's steps and predicts with it. With decay 0 it is
//! the plain model bit for bit; on a tiny run of two steps the average
//! equals its definition `d^2 theta0 + d (1 - d) theta1 + (1 - d) theta2`;
//! it survives saving; out-of-range decays are refused.
use crate::common;

use common::{moving_pair_frames, tiny_config, SIDE};
use tactrace_convnet::{
    ConvConfig, ConvError, ConvModel, Frames, ModelKind, Network, Parameters, Targets,
};

const COUNT: usize = 24;

/// One batch an epoch (the batch holds every frame), so an epoch is one
/// optimiser step.
fn config(kind: ModelKind, epochs: usize, average: Option<f64>) -> ConvConfig {
    let mut c = tiny_config(kind);
    c.epochs = epochs;
    c.batch_size = COUNT;
    c.chunk_size = 8;
    c.learning_rate = 0.01;
    c.weight_average = average;
    c
}

fn fit(config: &ConvConfig) -> ConvModel {
    let (pixels, targets) = moving_pair_frames(COUNT);
    let f = Frames::new(&pixels, COUNT, SIDE, SIDE).unwrap();
    let t = Targets::new(&targets, COUNT, 2).unwrap();
    ConvModel::fit(&f, &t, config, 5).unwrap().0
}

fn bits(p: &Parameters) -> Vec<u32> {
    p.values().flatten().map(|v| v.to_bits()).collect()
}

#[test]
fn weight_average_of_decay_zero_is_the_plain_model_bit_for_bit() {
    for kind in [ModelKind::ConvDennn, ModelKind::ConvMlp] {
        let mut plain = config(kind, 3, None);
        plain.batch_size = 8;
        let mut zero = plain.clone();
        zero.weight_average = Some(0.0);
        let (a, b) = (fit(&plain), fit(&zero));
        assert_eq!(
            bits(a.network().parameters()),
            bits(b.network().parameters())
        );
    }
}

#[test]
fn weight_average_equals_its_definition_on_two_steps() {
    let d = 0.6f64;
    for kind in [ModelKind::ConvDennn, ModelKind::ConvMlp] {
        // theta0: the initial weights; theta1: after one step (a one-epoch
        // fit takes the same first step as a two-epoch one: the step size
        // starts at the full rate and the shuffle is the same);
        // theta2: after two steps.
        let fitted = fit(&config(kind, 2, None));
        let layout = fitted.network().layout().clone();
        let theta0 = Network::new(layout, fitted.network().activation(), 5);
        let theta1 = fit(&config(kind, 1, None));
        let theta2 = fitted;
        let averaged = fit(&config(kind, 2, Some(d)));
        let (p0, p1, p2) = (
            theta0.parameters().flatten(),
            theta1.network().parameters().flatten(),
            theta2.network().parameters().flatten(),
        );
        let got = averaged.network().parameters().flatten();
        let mut moved = 0.0f64;
        for (i, g) in got.iter().enumerate() {
            let want = d * d * p0[i] + d * (1.0 - d) * p1[i] + (1.0 - d) * p2[i];
            assert!((g - want).abs() < 1e-6, "{kind:?} value {i}: {g} vs {want}");
            moved = moved.max((g - p2[i]).abs());
        }
        // The average is not the last weights.
        assert!(moved > 1e-3, "{kind:?}: the average is the last step");
    }
}

#[test]
fn weight_average_survives_saving_and_is_checked() {
    let model = fit(&config(ModelKind::ConvMlp, 2, Some(0.5)));
    let (json, tensors) = model.to_bytes().unwrap();
    assert!(json.contains("\"weight_average\": 0.5"), "{json}");
    let back = ConvModel::from_bytes(&json, &tensors).unwrap();
    assert_eq!(back, model);
    // A model saved without the key reads as no average.
    let plain = fit(&config(ModelKind::ConvMlp, 1, None));
    let (json, _) = plain.to_bytes().unwrap();
    assert!(!json.contains("weight_average"), "{json}");
    for bad in [1.0, -0.1, f64::NAN] {
        let c = config(ModelKind::ConvMlp, 1, Some(bad));
        match c.validate() {
            Err(ConvError::Config { field, .. }) => assert_eq!(field, "weight_average"),
            other => panic!("decay {bad}: {other:?}"),
        }
    }
}
