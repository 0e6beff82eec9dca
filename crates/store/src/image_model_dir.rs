//! Image model folders (`conv-dennn`, `conv-mlp`): `model.json` and
//! `weights.safetensors` as a pin model's (the JSON says which kind),
//! `frames.json` (the training frames' [`FramesInfo`]: the input size and
//! what it was averaged from), `training.json` and `history.csv`. No
//! `pins.json`: an image model reads pixels, whatever the pin order.
//! A residual model (`input = "pin_model_and_pixels"`) holds the pin model
//! it corrects in `base/`, a pin model folder of its own (with its
//! `pins.json`), so the folder moves whole; its pins are checked against
//! the data's or the rig's ([`StoredImageModel::check_pins`]).
//!
//! [`LoadedModel`] is the one entry that loads any model folder, pin or
//! image model, for the commands that take either.
use crate::error::{Result, StoreError};
use crate::fsutil::{read_text, StagedDir};
use crate::image_frames::FramesInfo;
use crate::model_dir::{write_model_into, StoredModel};
use crate::model_files::{
    network_error, read_network, read_training, write_common, write_file, CommonParts, MODEL_JSON,
};
use crate::training_record::TrainingRecord;
use std::path::{Path, PathBuf};
use tactrace_learn::ImageModel;

const FRAMES_JSON: &str = "frames.json";
/// The sub-folder holding a residual model's pin model.
pub const BASE_DIR: &str = "base";

/// An image model with what its training frames were.
#[derive(Debug, Clone)]
pub struct StoredImageModel {
    model: ImageModel,
    frames: FramesInfo,
    training: Option<TrainingRecord>,
    /// A residual model's pin model with its reference pins.
    base: Option<Box<StoredModel>>,
    source: PathBuf,
}

impl StoredImageModel {
    /// A model just trained on frames described by `frames`.
    pub fn new(model: ImageModel, frames: FramesInfo) -> Self {
        Self {
            model,
            frames,
            training: None,
            base: None,
            source: PathBuf::new(),
        }
    }

    /// A residual model's pin model given its training data's reference
    /// pins and what it was trained on (written to `base/`); nothing for
    /// any other image model.
    pub fn with_base_pins(
        mut self,
        reference_pins: Vec<[f64; 2]>,
        training: TrainingRecord,
    ) -> Self {
        self.base = self
            .model
            .base()
            .map(|b| Box::new(StoredModel::new(b.clone(), reference_pins).with_training(training)));
        self
    }

    /// A residual model's pin model as stored (`base/`), `None` otherwise.
    pub fn base(&self) -> Option<&StoredModel> {
        self.base.as_deref()
    }

    /// Refuse data or a rig whose reference pins (`pins`, named `what`)
    /// are ordered otherwise than a residual model's pin model reads
    /// them; any other image model takes any order.
    pub fn check_pins(&self, pins: &[[f64; 2]], what: &Path) -> Result<()> {
        match &self.base {
            Some(b) => b.for_pins(pins, what).map(|_| ()),
            None => Ok(()),
        }
    }

    /// The model with the record of what it was trained on.
    pub fn with_training(mut self, training: TrainingRecord) -> Self {
        self.training = Some(training);
        self
    }

    /// Load an image model folder, with errors naming the file.
    pub fn load(dir: &Path) -> Result<Self> {
        let (json, weights) = read_network(dir)?;
        let base_dir = dir.join(BASE_DIR);
        let base = match base_dir.join(MODEL_JSON).is_file() {
            true => Some(Box::new(StoredModel::load(&base_dir)?)),
            false => None,
        };
        let pose = base.as_ref().map(|b| b.model_unchecked().clone());
        let model = ImageModel::from_bytes_with_base(&json, &weights, pose)
            .map_err(|e| network_error(dir, e))?;
        let frames_path = dir.join(FRAMES_JSON);
        let frames: FramesInfo =
            serde_json::from_str(&read_text(&frames_path)?).map_err(|e| StoreError::Format {
                path: frames_path.clone(),
                reason: e.to_string(),
            })?;
        if (frames.height, frames.width) != model.input_size() {
            return Err(StoreError::Format {
                path: frames_path,
                reason: format!(
                    "frames of {} x {} px, but the model takes {} x {} px",
                    frames.height,
                    frames.width,
                    model.input_size().0,
                    model.input_size().1
                ),
            });
        }
        Ok(Self {
            model,
            frames,
            training: read_training(dir)?,
            base,
            source: dir.to_path_buf(),
        })
    }

    /// The model.
    pub fn model(&self) -> &ImageModel {
        &self.model
    }

    /// Whether its predictions average turned views (`None`: fitted
    /// without rotations), as [`ImageModel::views_at_prediction`].
    pub fn views_at_prediction(&self) -> Option<bool> {
        self.model.views_at_prediction()
    }

    /// Switch the mean over turned views at prediction on or off
    /// ([`ImageModel::set_turned_views`]), refused naming the model folder.
    pub fn set_turned_views(&mut self, on: bool) -> Result<()> {
        self.model
            .set_turned_views(on)
            .map_err(crate::model_dir::setting_refused(&self.source))
    }

    /// What its training frames were (size, source size).
    pub fn frames(&self) -> &FramesInfo {
        &self.frames
    }

    /// What the model was trained on, when its folder records it.
    pub fn training(&self) -> Option<&TrainingRecord> {
        self.training.as_ref()
    }

    /// Where the model was loaded from (empty for one made in memory).
    pub fn source(&self) -> &Path {
        &self.source
    }
}

/// Write a trained image model, what it was trained on, its history
/// (`history.csv` bytes) and `extra` text files into a staging folder
/// for `dir`; the caller adds figures and commits it.
pub fn stage_image_model(
    dir: &Path,
    model: &StoredImageModel,
    history_csv: &[u8],
    force: bool,
    extra: &[(&str, String)],
) -> Result<StagedDir> {
    let stage = StagedDir::new(dir, force)?;
    match (&model.base, model.model.base()) {
        (Some(base), Some(_)) => {
            let base_dir = stage.path().join(BASE_DIR);
            std::fs::create_dir(&base_dir).map_err(crate::error::write_err(&base_dir))?;
            let history = tactrace_learn::TrainingHistory::default();
            write_model_into(&base_dir, base, &history, &[])?;
        }
        (None, None) => {}
        _ => {
            return Err(network_error(
                dir,
                "a model that corrects a pin model is saved with that model's reference pins",
            ))
        }
    }
    let network = model.model.to_bytes().map_err(|e| network_error(dir, e))?;
    let frames = serde_json::to_string_pretty(&model.frames).expect("info serialises");
    write_file(&stage.path().join(FRAMES_JSON), frames.as_bytes())?;
    let parts = CommonParts {
        network,
        training: model.training.as_ref(),
        history_csv,
        extra,
    };
    write_common(stage.path(), parts)?;
    Ok(stage)
}

/// Any model folder: a pin model (displacement vectors in) or an image
/// model (frames in), as its `model.json` says.
// One is loaded per command, and both variants are about a kilobyte of
// settings beside their boxed weights: boxing one would only add a hop.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum LoadedModel {
    Pins(StoredModel),
    Image(StoredImageModel),
}

impl LoadedModel {
    /// Load the model folder `dir`, whichever kind it holds.
    pub fn load(dir: &Path) -> Result<Self> {
        if is_image_model_dir(dir) {
            StoredImageModel::load(dir).map(LoadedModel::Image)
        } else {
            StoredModel::load(dir).map(LoadedModel::Pins)
        }
    }

    /// Whether its predictions average turned views (`None`: fitted
    /// without rotations).
    pub fn views_at_prediction(&self) -> Option<bool> {
        match self {
            LoadedModel::Pins(m) => m.views_at_prediction(),
            LoadedModel::Image(m) => m.views_at_prediction(),
        }
    }

    /// Switch the mean over turned views at prediction on or off, pin or
    /// image model; refused (bad input, naming the folder) for a model
    /// fitted without rotations.
    pub fn set_turned_views(&mut self, on: bool) -> Result<()> {
        match self {
            LoadedModel::Pins(m) => m.set_turned_views(on),
            LoadedModel::Image(m) => m.set_turned_views(on),
        }
    }

    /// What the model was trained on, when its folder records it.
    pub fn training(&self) -> Option<&TrainingRecord> {
        match self {
            LoadedModel::Pins(m) => m.training(),
            LoadedModel::Image(m) => m.training(),
        }
    }
}

/// Whether `dir`'s `model.json` is an image model's (false when it cannot
/// be read: the pin model's loader then says what is wrong).
pub fn is_image_model_dir(dir: &Path) -> bool {
    image_model_kind(dir).is_some()
}

/// The kind of the image model in `dir` ("conv-dennn", "conv-mlp"), or
/// `None` when it holds none.
pub(crate) fn image_model_kind(dir: &Path) -> Option<String> {
    let text = read_text(&dir.join(MODEL_JSON)).ok()?;
    let value: serde_json::Value = serde_json::from_str(&text).ok()?;
    if !tactrace_learn::is_image_model_json(&value) {
        return None;
    }
    let kind = value
        .pointer("/network/config/kind")
        .and_then(|k| k.as_str());
    Some(kind.unwrap_or("image model").to_string())
}
