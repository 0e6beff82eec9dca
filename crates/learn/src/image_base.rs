//! The residual image model (`input = "pin_model_and_pixels"`,
//! docs/learning.md, "The residual on a pin model"): a pin model, the
//! base, predicts the targets from the tap's pins; the convolutional
//! network reads the frame and that prediction and learns the correction
//! (`tactrace_convnet`'s skip: `y = z + s(L)` in standardised units,
//! its output layer starting at zero, so the fresh model predicts the
//! base). The base travels inside the model: every prediction of a frame
//! and its pins computes the base's prediction first, the way the model
//! was trained.
//!
//! The training rows' base predictions are given by the caller
//! ([`BaseFit`]): out-of-fold predictions, each row's from a pin model
//! that did not see it, so the corrections are learnt against a base as
//! good as it is on new taps, not as good as on its own training rows.
use crate::error::LearnError;
use crate::image_model::{encode, vector_columns, width, with_encoded, ImageModel};
use crate::pose_model::PoseModel;
use crate::targets::{self, ModelTarget};
use tactrace_convnet::{ConvConfig, ConvModel, EpochReport, Frames, TrainingHistory};

/// What a residual model is fitted from besides its frames and targets.
#[derive(Debug, Clone, Copy)]
pub struct BaseFit<'a> {
    /// The pin model every prediction starts from (fitted on all the
    /// training rows), kept inside the model.
    pub model: &'a PoseModel,
    /// Each training row's base prediction (`count x T`, the targets'
    /// order and units): out-of-fold, by pin models that did not see it.
    pub rows: &'a [f64],
}

/// The refusal of a residual configuration without its pin model.
pub(crate) fn needs_base() -> LearnError {
    LearnError::Config {
        field: "input",
        reason: "\"pin_model_and_pixels\" corrects a pin model: fit it with its base \
                 (ImageModel::fit_on_base; `train` fits one)"
            .into(),
    }
}

/// A network that reads a base with its pin model, or one that does not
/// without: anything else is refused, as is a base of other targets.
pub(crate) fn check_base(
    conv: &ConvModel,
    outputs: &[ModelTarget],
    base: Option<&PoseModel>,
) -> Result<(), LearnError> {
    match (conv.config().input.reads_base(), base) {
        (false, None) => Ok(()),
        (true, None) => Err(needs_base()),
        (false, Some(_)) => Err(LearnError::Config {
            field: "input",
            reason: "a pin model was given to an image model that does not read one".into(),
        }),
        (true, Some(b)) if b.outputs() == outputs => Ok(()),
        (true, Some(b)) => Err(LearnError::Targets {
            reason: format!(
                "the pin model predicts {}, the image model {}",
                names(b.outputs()),
                names(outputs)
            ),
        }),
    }
}

fn names(outputs: &[ModelTarget]) -> String {
    let v: Vec<&str> = outputs.iter().map(|t| t.name.as_str()).collect();
    v.join(", ")
}

/// The network's side values of `count` taps from their base predictions
/// `rows` (`count x T`, targets' units): each encoded as the targets are
/// (a circular angle as its sine and cosine), `count x width`.
fn encode_rows(
    outputs: &[ModelTarget],
    rows: &[f64],
    count: usize,
) -> Result<Vec<f32>, LearnError> {
    let values: Vec<f32> = rows.iter().map(|&v| v as f32).collect();
    Ok(encode(outputs, &values, count)?
        .into_iter()
        .map(|v| v as f32)
        .collect())
}

/// The side values of `count` taps from their pin displacement vectors
/// `pins` (`count x base.input_dim()`): the base's prediction, encoded.
pub(crate) fn base_side(
    base: &PoseModel,
    outputs: &[ModelTarget],
    pins: &[f32],
    count: usize,
) -> Result<Vec<f32>, LearnError> {
    let dim = base.input_dim();
    if pins.len() != count * dim {
        return Err(LearnError::DimensionMismatch {
            expected: count * dim,
            got: pins.len(),
        });
    }
    let mut rows = Vec::with_capacity(count * outputs.len());
    for tap in pins.chunks_exact(dim.max(1)) {
        rows.extend(base.predict_targets(tap)?);
    }
    encode_rows(outputs, &rows, count)
}

/// [`base_side`] of every frame of `frames` from the pins they carry
/// (refused when they carry none, or another count).
pub(crate) fn frames_side(
    base: &PoseModel,
    outputs: &[ModelTarget],
    frames: &Frames,
) -> Result<Vec<f32>, LearnError> {
    let dim = frames.pin_dim();
    if dim != base.input_dim() {
        return Err(tactrace_convnet::ConvError::PinCount {
            expected: base.input_dim(),
            got: dim,
        }
        .into());
    }
    let mut pins = Vec::with_capacity(frames.count() * dim);
    for i in 0..frames.count() {
        pins.extend_from_slice(frames.pins(i).unwrap_or(&[]));
    }
    base_side(base, outputs, &pins, frames.count())
}

impl ImageModel {
    /// Fit a residual model of `config` (`input = "pin_model_and_pixels"`)
    /// on `frames`, their targets `values` (`count x T`, `outputs`' order
    /// and units) and the base `base`, from `seed`: the network reads each
    /// training frame with its row of `base.rows`; `validation` frames
    /// carry their pins, which the base model reads as at prediction.
    #[allow(clippy::too_many_arguments)]
    pub fn fit_on_base(
        frames: &Frames,
        values: &[f32],
        outputs: &[ModelTarget],
        base: BaseFit,
        config: &ConvConfig,
        seed: u64,
        validation: Option<(Frames, &[f32])>,
        on_epoch: &mut dyn FnMut(&EpochReport),
    ) -> Result<(Self, TrainingHistory), LearnError> {
        targets::check_targets(outputs)?;
        if !config.input.reads_base() {
            return Err(LearnError::Config {
                field: "input",
                reason: "a base pin model is read by input = \"pin_model_and_pixels\"".into(),
            });
        }
        let count = frames.count();
        if base.rows.len() != count * outputs.len() {
            return Err(LearnError::Shape {
                what: "base predictions (one row a frame)",
                expected: count * outputs.len(),
                got: base.rows.len(),
            });
        }
        let w = width(outputs);
        let side = encode_rows(outputs, base.rows, count)?;
        let train = frames.with_pins(&side, w)?;
        let val_side = match &validation {
            Some((vf, _)) => Some(frames_side(base.model, outputs, vf)?),
            None => None,
        };
        let validation = match (validation, &val_side) {
            (Some((vf, vv)), Some(s)) => Some((vf.with_pins(s, w)?, vv)),
            _ => None,
        };
        let vectors = vector_columns(outputs, config)?;
        let (conv, history) =
            with_encoded(outputs, &train, values, validation, &vectors, |t, v| {
                ConvModel::fit_with(&train, t, config, seed, v, on_epoch)
            })?;
        let model = Self {
            conv,
            outputs: outputs.to_vec(),
            base: Some(Box::new(base.model.clone())),
        };
        check_base(&model.conv, outputs, model.base())?;
        Ok((model, history))
    }
}
