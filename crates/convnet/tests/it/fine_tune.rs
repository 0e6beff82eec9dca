//! Fine-tuning a fitted image model (`ConvModel::fine_tune_with`): it
//! starts from the model's networks, not from fresh weights, keeps the
//! model's pixel and target scalings whatever the new frames, is
//! reproducible from its seed, and refuses other networks or frames
//! before any work.
use crate::common;

use common::{moving_pair_frames, tiny_config, SIDE};
use tactrace_convnet::{ConvConfig, ConvError, ConvModel, Frames, ModelKind, Targets};

/// The tiny configuration, 6 epochs at 3e-3.
fn config(kind: ModelKind) -> ConvConfig {
    let mut c = tiny_config(kind);
    c.epochs = 6;
    c.learning_rate = 3e-3;
    c
}

fn data(count: usize) -> (Vec<u8>, Vec<f64>) {
    moving_pair_frames(count)
}

fn pretrained(kind: ModelKind) -> ConvModel {
    let (pixels, targets) = data(48);
    let frames = Frames::new(&pixels, 48, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 48, 2).unwrap();
    ConvModel::fit(&frames, &targets, &config(kind), 0)
        .unwrap()
        .0
}

/// The first epoch's loss of fitting `data(48)` from `start` (fresh
/// weights when `None`).
fn first_epoch_loss(start: Option<&ConvModel>, kind: ModelKind) -> f64 {
    let (pixels, targets) = data(48);
    let frames = Frames::new(&pixels, 48, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 48, 2).unwrap();
    let mut cfg = config(kind);
    cfg.epochs = 1;
    let history = match start {
        Some(m) => m.fine_tune_with(&frames, &targets, &cfg, 5, None, &mut |_| ()),
        None => ConvModel::fit_with(&frames, &targets, &cfg, 5, None, &mut |_| ()),
    };
    history.unwrap().1.epochs[0].loss
}

#[test]
fn fine_tuning_starts_from_the_model_not_from_fresh_weights() {
    for kind in [ModelKind::ConvMlp, ModelKind::ConvDennn] {
        let start = pretrained(kind);
        let tuned = first_epoch_loss(Some(&start), kind);
        let fresh = first_epoch_loss(None, kind);
        // The pretrained model has already fitted these frames: its first
        // epoch starts far below a fresh network's (mean 0.5 ||y - t||^2
        // in standardised units: about 1 for a fresh network).
        assert!(
            tuned < 0.5 * fresh,
            "{}: first epoch loss {tuned} from the model, {fresh} fresh",
            kind.name()
        );
    }
}

#[test]
fn fine_tuning_keeps_the_scalings_and_is_reproducible_from_its_seed() {
    let start = pretrained(ModelKind::ConvMlp);
    // Brighter frames and shifted targets: a fresh fit would scale them
    // otherwise; the fine-tuned model keeps the units its weights are in.
    let (mut pixels, mut targets) = data(24);
    pixels.iter_mut().for_each(|p| *p = p.saturating_add(5));
    targets.iter_mut().for_each(|t| *t += 0.5);
    let frames = Frames::new(&pixels, 24, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 24, 2).unwrap();
    let cfg = config(ModelKind::ConvMlp);
    let tune = || {
        start
            .fine_tune_with(&frames, &targets, &cfg, 3, None, &mut |_| ())
            .unwrap()
            .0
    };
    let (a, b) = (tune(), tune());
    assert_eq!(a.input_scaling(), start.input_scaling());
    assert_eq!(a.target_scaling(), start.target_scaling());
    assert_ne!(a.network(), start.network());
    assert_eq!(a, b, "the same seed gives the same model");
    assert_eq!(a.seed(), 3);
}

#[test]
fn fine_tuning_refuses_other_networks_and_other_frames() {
    let start = pretrained(ModelKind::ConvMlp);
    let (pixels, targets) = data(12);
    let frames = Frames::new(&pixels, 12, SIDE, SIDE).unwrap();
    let targets2 = Targets::new(&targets, 12, 2).unwrap();
    let mut wider = config(ModelKind::ConvMlp);
    wider.dense = vec![9];
    let err = start
        .fine_tune_with(&frames, &targets2, &wider, 0, None, &mut |_| ())
        .unwrap_err();
    assert!(
        matches!(err, ConvError::Config { field: "dense", .. }),
        "{err}"
    );
    let mut two = config(ModelKind::ConvMlp);
    two.members = 2;
    let err = start
        .fine_tune_with(&frames, &targets2, &two, 0, None, &mut |_| ())
        .unwrap_err();
    assert!(
        matches!(
            err,
            ConvError::Config {
                field: "members",
                ..
            }
        ),
        "{err}"
    );
    let small = vec![0u8; 12 * 10 * 10];
    let small = Frames::new(&small, 12, 10, 10).unwrap();
    let cfg = config(ModelKind::ConvMlp);
    let err = start
        .fine_tune_with(&small, &targets2, &cfg, 0, None, &mut |_| ())
        .unwrap_err();
    assert!(matches!(err, ConvError::FrameSize { .. }), "{err}");
    let one = Targets::new(&targets[..12], 12, 1).unwrap();
    let err = start
        .fine_tune_with(&frames, &one, &cfg, 0, None, &mut |_| ())
        .unwrap_err();
    assert!(matches!(err, ConvError::Shape { .. }), "{err}");
}

#[test]
fn fine_tuning_refuses_another_input_kind() {
    let start = pretrained(ModelKind::ConvMlp);
    let (pixels, targets) = data(12);
    let frames = Frames::new(&pixels, 12, SIDE, SIDE).unwrap();
    let targets = Targets::new(&targets, 12, 2).unwrap();
    let mut hybrid = config(ModelKind::ConvMlp);
    hybrid.input = tactrace_convnet::InputKind::PinsAndPixels;
    let err = start
        .fine_tune_with(&frames, &targets, &hybrid, 0, None, &mut |_| ())
        .unwrap_err();
    assert!(
        matches!(err, ConvError::Config { field: "input", .. }),
        "{err}"
    );
}
