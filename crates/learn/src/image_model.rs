//! The image pose model: a convolutional network of `tactrace_convnet`
//! (`conv-dennn` learnt by equilibrium propagation, or its backprop twin
//! `conv-mlp`) over N named targets as the pin models have them
//! ([`ModelTarget`]: mm or deg, a circular angle learnt as its sine and
//! cosine and read back by `atan2`). One grey frame of the model's input
//! size in, the N targets out.
//!
//! Serialised as a JSON string (format, version, targets, the network's
//! own JSON) plus the network's safetensors bytes; the caller writes them.
use crate::error::LearnError;
use crate::pose_model::PoseModel;
use crate::targets::{self, ModelTarget};
use serde::{Deserialize, Serialize};
use tactrace_convnet::{
    ConvConfig, ConvModel, EpochReport, Frames, Targets, TrainingHistory, TurnedColumns,
    VectorColumns,
};

/// Identifies an image model's `model.json`.
pub const IMAGE_FORMAT: &str = "tactrace-image-model";
/// Bumped on any incompatible change.
pub const IMAGE_FORMAT_VERSION: u32 = 1;

/// A fitted image model: the network and the targets it predicts, and
/// for a residual model (`input = "pin_model_and_pixels"`) the pin model
/// whose prediction it corrects (`crate::image_base`).
#[derive(Debug, Clone)]
pub struct ImageModel {
    pub(crate) conv: ConvModel,
    pub(crate) outputs: Vec<ModelTarget>,
    pub(crate) base: Option<Box<PoseModel>>,
}

impl PartialEq for ImageModel {
    /// The same network and targets, and bases that serialise alike.
    fn eq(&self, other: &Self) -> bool {
        let base = |m: &Self| m.base.as_ref().map(|b| b.to_bytes().ok());
        self.conv == other.conv && self.outputs == other.outputs && base(self) == base(other)
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ImageFile {
    format: String,
    version: u32,
    targets: Vec<ModelTarget>,
    network: serde_json::Value,
}

/// The encoded columns (circular targets as sine and cosine) of the
/// `count x T` target rows `values`.
pub(crate) fn encode(
    outputs: &[ModelTarget],
    values: &[f32],
    count: usize,
) -> Result<Vec<f64>, LearnError> {
    let t = outputs.len();
    if values.len() != count * t {
        return Err(LearnError::Shape {
            what: "target values (one row a frame)",
            expected: count * t,
            got: values.len(),
        });
    }
    let mut out = Vec::new();
    let mut row = Vec::new();
    for r in values.chunks_exact(t.max(1)) {
        row.clear();
        targets::encode_into(outputs, r, &mut row);
        out.extend(row.iter().map(|&v| f64::from(v)));
    }
    Ok(out)
}

pub(crate) fn width(outputs: &[ModelTarget]) -> usize {
    outputs.iter().map(ModelTarget::width).sum()
}

/// The encoded columns holding a circular target's sine (its cosine is
/// the next): what a turned training frame turns.
pub(crate) fn angle_columns(outputs: &[ModelTarget]) -> Vec<usize> {
    let mut start = 0;
    let mut angles = Vec::new();
    for t in outputs {
        if t.circular {
            angles.push(start);
        }
        start += t.width();
    }
    angles
}

/// The encoded columns of the vectors `config`'s turned frames name
/// ([`tactrace_convnet::TurnedVector`]): each name one of `outputs`, not
/// circular, the two of one unit.
pub(crate) fn vector_columns(
    outputs: &[ModelTarget],
    config: &ConvConfig,
) -> Result<Vec<VectorColumns>, LearnError> {
    let Some(turns) = &config.rotations else {
        return Ok(Vec::new());
    };
    let column = |name: &str| -> Result<(usize, &ModelTarget), LearnError> {
        let mut start = 0;
        for t in outputs {
            if t.name == name && !t.circular {
                return Ok((start, t));
            }
            start += t.width();
        }
        Err(LearnError::Config {
            field: "rotations.vectors",
            reason: format!("{name} is not one of the model's targets that is not circular"),
        })
    };
    turns
        .vectors
        .iter()
        .map(|v| {
            let ((a, ta), (b, tb)) = (column(&v.targets[0])?, column(&v.targets[1])?);
            if ta.unit != tb.unit {
                return Err(LearnError::Config {
                    field: "rotations.vectors",
                    reason: format!("{} and {} are not in one unit", ta.name, tb.name),
                });
            }
            Ok(VectorColumns {
                columns: [a, b],
                sign: v.sign,
            })
        })
        .collect()
}

/// Run `fit` on the encoded targets of the training rows `values` (one a
/// frame of `frames`) and of the validation frames' rows.
pub(crate) fn with_encoded(
    outputs: &[ModelTarget],
    frames: &Frames,
    values: &[f32],
    validation: Option<(Frames, &[f32])>,
    vectors: &[VectorColumns],
    fit: impl FnOnce(
        &Targets,
        Option<(Frames, Targets)>,
    ) -> Result<(ConvModel, TrainingHistory), tactrace_convnet::ConvError>,
) -> Result<(ConvModel, TrainingHistory), LearnError> {
    let w = width(outputs);
    let encoded = encode(outputs, values, frames.count())?;
    let angles = angle_columns(outputs);
    let train = Targets::new(&encoded, frames.count(), w)?
        .with_angles(&angles)?
        .with_vectors(vectors)?;
    let val = match validation {
        Some((vf, vv)) => Some((vf, encode(outputs, vv, vf.count())?)),
        None => None,
    };
    let val_views = match &val {
        Some((vf, enc)) => Some((*vf, Targets::new(enc, vf.count(), w)?)),
        None => None,
    };
    Ok(fit(&train, val_views)?)
}

impl ImageModel {
    /// Fit a model of `config` on `frames` and their targets `values`
    /// (`count x T`, in `outputs`' order and units) from `seed`, scoring
    /// `validation` (frames and their target rows) after each epoch and
    /// handing each epoch's report (errors in encoded units) to `on_epoch`.
    pub fn fit(
        frames: &Frames,
        values: &[f32],
        outputs: &[ModelTarget],
        config: &ConvConfig,
        seed: u64,
        validation: Option<(Frames, &[f32])>,
        on_epoch: &mut dyn FnMut(&EpochReport),
    ) -> Result<(Self, TrainingHistory), LearnError> {
        targets::check_targets(outputs)?;
        if config.input.reads_base() {
            return Err(crate::image_base::needs_base());
        }
        let vectors = vector_columns(outputs, config)?;
        let (conv, history) =
            with_encoded(outputs, frames, values, validation, &vectors, |t, v| {
                ConvModel::fit_with(frames, t, config, seed, v, on_epoch)
            })?;
        Ok((
            Self {
                conv,
                outputs: outputs.to_vec(),
                base: None,
            },
            history,
        ))
    }

    /// This model trained further on `frames` and their target rows
    /// `values` (in [`Self::outputs`]' order and units) by `config`'s
    /// rule and schedule from `seed` ([`ConvModel::fine_tune_with`]: its
    /// networks, scalings and targets kept; `config` must describe the
    /// same networks): pretrain on one set of frames, fine-tune on another.
    pub fn fine_tune(
        &self,
        frames: &Frames,
        values: &[f32],
        config: &ConvConfig,
        seed: u64,
        validation: Option<(Frames, &[f32])>,
        on_epoch: &mut dyn FnMut(&EpochReport),
    ) -> Result<(Self, TrainingHistory), LearnError> {
        if self.base.is_some() {
            return Err(LearnError::Config {
                field: "input",
                reason: "a model that corrects a pin model is trained whole (its training rows \
                         need out-of-fold predictions of the pin model); --init takes another"
                    .into(),
            });
        }
        let outputs = &self.outputs;
        let vectors = vector_columns(outputs, config)?;
        let (conv, history) =
            with_encoded(outputs, frames, values, validation, &vectors, |t, v| {
                self.conv
                    .fine_tune_with(frames, t, config, seed, v, on_epoch)
            })?;
        let outputs = outputs.clone();
        let base = None;
        Ok((
            Self {
                conv,
                outputs,
                base,
            },
            history,
        ))
    }

    /// Every target, in [`Self::outputs`]' order and units (circular
    /// angles within (-180, 180] deg), for one frame of the input size.
    pub fn predict_targets(&self, frame: &[u8]) -> Result<Vec<f64>, LearnError> {
        let encoded = if self.turned_views() {
            let (h, w) = self.input_size();
            let one = Frames::new(frame, 1, h, w)?;
            self.predict_encoded_turned(&one)?
        } else {
            self.conv.predict(frame)?
        };
        Ok(targets::decode(&self.outputs, &encoded))
    }

    /// The encoded prediction of `frames` ([`ConvModel::predict_batch_turned`]:
    /// with its configuration's turned views, if any).
    fn predict_encoded_turned(&self, frames: &Frames) -> Result<Vec<f64>, LearnError> {
        let angles = angle_columns(&self.outputs);
        let vectors = vector_columns(&self.outputs, self.conv.config())?;
        let columns = TurnedColumns {
            angles: &angles,
            vectors: &vectors,
        };
        Ok(self.conv.predict_batch_turned(frames, columns)?)
    }

    /// Whether it predicts with the mean of a frame's turned views
    /// (`rotations.at_prediction` of its configuration; a model of pixels).
    fn turned_views(&self) -> bool {
        self.conv.turned_views() == Some(true)
    }

    /// Whether every prediction is the mean over the frame's turned views
    /// (`rotations.at_prediction`); `None` for a model fitted without
    /// `rotations`.
    pub fn views_at_prediction(&self) -> Option<bool> {
        self.conv.turned_views()
    }

    /// Switch the mean over turned views at prediction on or off (the
    /// configuration's `rotations.at_prediction`, as
    /// [`PoseModel::set_turned_views`] for a pin model); refused for a
    /// model fitted without `rotations`.
    pub fn set_turned_views(&mut self, on: bool) -> Result<(), LearnError> {
        Ok(self.conv.set_turned_views(on)?)
    }

    /// [`Self::predict_targets`] of one frame and its pin displacement
    /// vector `pins` (x of every pin, then y, px, in the training
    /// dataset's pin order): read by a pins-and-pixels model, ignored by
    /// one of pixels only.
    pub fn predict_targets_with_pins(
        &self,
        frame: &[u8],
        pins: &[f32],
    ) -> Result<Vec<f64>, LearnError> {
        if self.turned_views() {
            return self.predict_targets(frame);
        }
        let encoded = match &self.base {
            Some(base) => {
                let side = crate::image_base::base_side(base, &self.outputs, pins, 1)?;
                self.conv.predict_with_pins(frame, &side)?
            }
            None => self.conv.predict_with_pins(frame, pins)?,
        };
        Ok(targets::decode(&self.outputs, &encoded))
    }

    /// The edge pose `[r mm, theta deg]` of one frame and its pins
    /// (as [`Self::predict_targets_with_pins`]), refused
    /// ([`LearnError::NotAnEdgeModel`]) for a model of other targets.
    pub fn predict_with_pins(&self, frame: &[u8], pins: &[f32]) -> Result<[f64; 2], LearnError> {
        let [r, theta] = self.edge_roles()?;
        let values = self.predict_targets_with_pins(frame, pins)?;
        Ok([values[r], values[theta]])
    }

    /// Pin values a frame it reads beside the pixels (0: pixels only; a
    /// residual model's, those its pin model reads).
    pub fn pin_inputs(&self) -> usize {
        match &self.base {
            Some(base) => base.input_dim(),
            None => self.conv.pin_inputs(),
        }
    }

    /// The pin model whose prediction it corrects (`input =
    /// "pin_model_and_pixels"`), `None` for any other model.
    pub fn base(&self) -> Option<&PoseModel> {
        self.base.as_deref()
    }

    /// The edge pose `[r mm, theta deg]` of one frame, refused
    /// ([`LearnError::NotAnEdgeModel`]) for a model of other targets.
    pub fn predict(&self, frame: &[u8]) -> Result<[f64; 2], LearnError> {
        let [r, theta] = self.edge_roles()?;
        let values = self.predict_targets(frame)?;
        Ok([values[r], values[theta]])
    }

    /// [`Self::predict`] of a frame of any size `(height, width)` px,
    /// area-averaged to the input size first (as `frames.npy` was made).
    pub fn predict_resampled(
        &self,
        frame: &[u8],
        size: (usize, usize),
    ) -> Result<[f64; 2], LearnError> {
        if frame.len() != size.0 * size.1 {
            return Err(LearnError::Shape {
                what: "frame pixels",
                expected: size.0 * size.1,
                got: frame.len(),
            });
        }
        let small = tactrace_convnet::area_resample(frame, size, self.input_size());
        self.predict(&small)
    }

    /// Every frame's targets, one row a frame (frames shared among the
    /// threads of the current rayon pool).
    pub fn predict_batch(&self, frames: &Frames) -> Result<Vec<Vec<f64>>, LearnError> {
        let side;
        let frames = match &self.base {
            Some(base) => {
                side = crate::image_base::frames_side(base, &self.outputs, frames)?;
                frames.with_pins(&side, width(&self.outputs))?
            }
            None => *frames,
        };
        let encoded = self.predict_encoded_turned(&frames)?;
        let w = width(&self.outputs).max(1);
        Ok(encoded
            .chunks_exact(w)
            .map(|row| targets::decode(&self.outputs, row))
            .collect())
    }

    /// The indices of the position (mm) and angle (deg) targets of an edge
    /// model: exactly one of each.
    pub fn edge_roles(&self) -> Result<[usize; 2], LearnError> {
        crate::targets::edge_roles(&self.outputs)
    }

    /// What the model predicts, in order.
    pub fn outputs(&self) -> &[ModelTarget] {
        &self.outputs
    }

    /// The frame size it takes, `(height, width)` px.
    pub fn input_size(&self) -> (usize, usize) {
        self.conv.input_size()
    }

    /// The network, its configuration and seed.
    pub fn network(&self) -> &ConvModel {
        &self.conv
    }

    /// "conv-dennn" or "conv-mlp".
    pub fn kind_name(&self) -> &'static str {
        self.conv.config().kind.name()
    }

    /// Serialise: `(json, safetensors weights)`.
    pub fn to_bytes(&self) -> Result<(String, Vec<u8>), LearnError> {
        let (net_json, weights) = self.conv.to_bytes()?;
        let file = ImageFile {
            format: IMAGE_FORMAT.into(),
            version: IMAGE_FORMAT_VERSION,
            targets: self.outputs.clone(),
            network: serde_json::from_str(&net_json).map_err(corrupt)?,
        };
        let json = serde_json::to_string_pretty(&file).map_err(corrupt)?;
        Ok((json, weights))
    }

    /// Rebuild a model from [`Self::to_bytes`] output; another format
    /// version, or targets that do not match the network, are errors, and
    /// so is a residual model (its pin model is stored beside it:
    /// [`Self::from_bytes_with_base`]).
    pub fn from_bytes(json: &str, weights: &[u8]) -> Result<Self, LearnError> {
        Self::from_bytes_with_base(json, weights, None)
    }

    /// [`Self::from_bytes`] with the pin model `base` a residual model
    /// corrects (required by one, refused by any other model; it must
    /// predict the same targets).
    pub fn from_bytes_with_base(
        json: &str,
        weights: &[u8],
        base: Option<PoseModel>,
    ) -> Result<Self, LearnError> {
        let value: serde_json::Value =
            serde_json::from_str(json).map_err(|e| corrupt(format!("model json: {e}")))?;
        if !is_image_model_json(&value) {
            return Err(corrupt(format!("not a {IMAGE_FORMAT} file")));
        }
        let version = value.get("version").and_then(|v| v.as_u64()).unwrap_or(0);
        if version != u64::from(IMAGE_FORMAT_VERSION) {
            return Err(LearnError::Version {
                found: version.min(u64::from(u32::MAX)) as u32,
                supported: IMAGE_FORMAT_VERSION,
            });
        }
        let file: ImageFile =
            serde_json::from_value(value).map_err(|e| corrupt(format!("model json: {e}")))?;
        targets::check_targets(&file.targets)?;
        let conv = ConvModel::from_bytes(&file.network.to_string(), weights)?;
        vector_columns(&file.targets, conv.config())?;
        if conv.outputs() != width(&file.targets) {
            return Err(corrupt(format!(
                "{} network outputs for targets that take {}",
                conv.outputs(),
                width(&file.targets)
            )));
        }
        crate::image_base::check_base(&conv, &file.targets, base.as_ref())?;
        Ok(Self {
            conv,
            outputs: file.targets,
            base: base.map(Box::new),
        })
    }
}

/// Whether a parsed `model.json` is an image model's.
pub fn is_image_model_json(value: &serde_json::Value) -> bool {
    value.get("format").and_then(|f| f.as_str()) == Some(IMAGE_FORMAT)
}

fn corrupt(reason: impl ToString) -> LearnError {
    LearnError::Corrupt {
        reason: reason.to_string(),
    }
}
