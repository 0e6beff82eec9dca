//! Model folders: `model.json` (architecture, hyper-parameters,
//! standardisation, PCA), `weights.safetensors`, `pins.json` (the reference
//! pins of the training data, whose order the inputs follow; see
//! [`crate::pin_order`]), `training.json` (which rows of which dataset it
//! was trained on: [`crate::training_record`]; absent in folders written
//! before it was kept), `history.csv` and, written by the caller before
//! the folder is committed, the loss/energy figure (report Fig. 4.5).
//!
//! A loaded model is a [`StoredModel`]: the network and its reference pins
//! as one value. The network is reached only through methods that take the
//! pins of the data or rig it is about to see, so the pin-order check
//! cannot be forgotten.
use crate::dataset::TapData;
use crate::error::{Result, StoreError};
use crate::fsutil::{read_text, StagedDir};
use crate::model_files::{
    network_error, read_network, read_training, write_common, write_file, CommonParts, MODEL_JSON,
};
use crate::pin_order::pin_order_mismatch;
use crate::training_record::TrainingRecord;
use std::path::{Path, PathBuf};
use tactrace_learn::{PoseModel, TrainingHistory};

const PINS: &str = "pins.json";

/// `pins.json`: the training data's reference pins (px, their order).
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct PinsFile {
    reference_pins: Vec<[f64; 2]>,
}

/// A pose model with the reference pins of its training data.
#[derive(Debug, Clone)]
pub struct StoredModel {
    model: PoseModel,
    reference_pins: Vec<[f64; 2]>,
    /// What it was trained on; `None` when unknown (older folders).
    training: Option<TrainingRecord>,
    /// Where it was loaded from (for messages); empty for one in memory.
    source: PathBuf,
}

impl StoredModel {
    /// A model just trained on data ordered against `reference_pins`.
    pub fn new(model: PoseModel, reference_pins: Vec<[f64; 2]>) -> Self {
        Self {
            model,
            reference_pins,
            training: None,
            source: PathBuf::new(),
        }
    }

    /// The model with the record of what it was trained on.
    pub fn with_training(mut self, training: TrainingRecord) -> Self {
        self.training = Some(training);
        self
    }

    /// Load a model folder written by [`stage_model`], with errors naming
    /// the file.
    pub fn load(dir: &Path) -> Result<Self> {
        let json_path = dir.join(MODEL_JSON);
        if !json_path.is_file() {
            use crate::folder_kind::{wrong_folder, MODEL_EXPECTED};
            return Err(StoreError::Format {
                path: dir.into(),
                reason: wrong_folder(dir, "model", MODEL_JSON, MODEL_EXPECTED),
            });
        }
        if let Some(kind) = crate::image_model_dir::image_model_kind(dir) {
            return Err(StoreError::Format {
                path: dir.into(),
                reason: format!(
                    "an image model ({kind}, frames in): this takes a pin model (pdennn, \
                     pcadennn, disdennn, mlp)"
                ),
            });
        }
        let (json, weights) = read_network(dir)?;
        let model = PoseModel::from_bytes(&json, &weights).map_err(|e| network_error(dir, e))?;
        let reference_pins = read_pins(dir)?;
        if 2 * reference_pins.len() != model.input_dim() {
            return Err(StoreError::Format {
                path: dir.join(PINS),
                reason: format!(
                    "{} reference pins, but the model takes {} inputs (2 x pins)",
                    reference_pins.len(),
                    model.input_dim()
                ),
            });
        }
        Ok(Self {
            model,
            reference_pins,
            training: read_training(dir)?,
            source: dir.to_path_buf(),
        })
    }

    /// What the model was trained on, when its folder records it.
    pub fn training(&self) -> Option<&TrainingRecord> {
        self.training.as_ref()
    }

    /// The training data's reference pins (px), in input order.
    pub fn reference_pins(&self) -> &[[f64; 2]] {
        &self.reference_pins
    }

    /// Where the model was loaded from (empty for one made in memory).
    pub fn source(&self) -> &Path {
        &self.source
    }

    /// Whether its predictions average turned views (`None`: fitted
    /// without rotations), as [`PoseModel::views_at_prediction`].
    pub fn views_at_prediction(&self) -> Option<bool> {
        self.model.views_at_prediction()
    }

    /// Switch the mean over turned views at prediction on or off
    /// ([`PoseModel::set_turned_views`]), refused naming the model folder.
    pub fn set_turned_views(&mut self, on: bool) -> Result<()> {
        self.model
            .set_turned_views(on)
            .map_err(setting_refused(&self.source))
    }

    /// The network, for data or a rig whose reference pins are `pins`
    /// (named `what` in the error): refused when they are ordered otherwise.
    pub fn for_pins(&self, pins: &[[f64; 2]], what: &Path) -> Result<&PoseModel> {
        match pin_order_mismatch(&self.reference_pins, pins) {
            None => Ok(&self.model),
            Some(source) => Err(StoreError::PinOrder {
                path: what.to_path_buf(),
                source,
            }),
        }
    }

    /// The network, for a dataset (named `what`): see [`Self::for_pins`].
    pub fn for_data(&self, data: &TapData, what: &Path) -> Result<&PoseModel> {
        self.for_pins(&data.meta.reference_pins, what)
    }

    /// The pose model whatever the pin order, for a holder that checks
    /// the order itself (an image model's base:
    /// [`crate::StoredImageModel::check_pins`]).
    pub(crate) fn model_unchecked(&self) -> &PoseModel {
        &self.model
    }

    /// As [`Self::for_pins`], giving up the stored model.
    pub fn into_model_for(self, pins: &[[f64; 2]], what: &Path) -> Result<PoseModel> {
        self.for_pins(pins, what)?;
        Ok(self.model)
    }
}

/// The refusal of a setting by the model loaded from `source`, naming
/// its folder ([`StoreError::ModelSetting`]).
pub(crate) fn setting_refused(
    source: &Path,
) -> impl FnOnce(tactrace_learn::LearnError) -> StoreError + '_ {
    move |e| StoreError::ModelSetting {
        path: model_name(source),
        source: e,
    }
}

/// A model's folder for messages, or "the model" for one made in memory.
fn model_name(source: &Path) -> PathBuf {
    match source.as_os_str().is_empty() {
        true => PathBuf::from("the model"),
        false => source.to_path_buf(),
    }
}

fn read_pins(dir: &Path) -> Result<Vec<[f64; 2]>> {
    let path = dir.join(PINS);
    if !path.is_file() {
        return Err(StoreError::Format {
            path: dir.into(),
            reason: format!(
                "no {PINS}: the model was saved without its training data's reference pins \
                 (before tactrace checked pin order); train it again"
            ),
        });
    }
    let file: PinsFile =
        serde_json::from_str(&read_text(&path)?).map_err(|e| StoreError::Format {
            path: path.clone(),
            reason: e.to_string(),
        })?;
    Ok(file.reference_pins)
}

/// Write a trained model (with the reference pins of its training data and,
/// when known, the record of its training rows, with an ensemble's
/// per-member learning-rate halvings from `history`), its training history and
/// `extra` text files `(name, contents)` into a staging folder for `dir`;
/// the caller adds figures and commits it.
pub fn stage_model(
    dir: &Path,
    model: &StoredModel,
    history: &TrainingHistory,
    force: bool,
    extra: &[(&str, String)],
) -> Result<StagedDir> {
    let stage = StagedDir::new(dir, force)?;
    write_model_into(stage.path(), model, history, extra)?;
    Ok(stage)
}

/// The files of [`stage_model`] written into the folder `dir` (a staging
/// folder, or a folder inside one: an image model's base).
pub(crate) fn write_model_into(
    dir: &Path,
    model: &StoredModel,
    history: &TrainingHistory,
    extra: &[(&str, String)],
) -> Result<()> {
    let pins = PinsFile {
        reference_pins: model.reference_pins.clone(),
    };
    let pins = serde_json::to_string(&pins).expect("pins serialise");
    write_file(&dir.join(PINS), pins.as_bytes())?;
    let network = model.model.to_bytes().map_err(|e| network_error(dir, e))?;
    let training = model.training.clone().map(|t| TrainingRecord {
        member_lr_halvings: history.member_lr_halvings.clone(),
        ..t
    });
    let parts = CommonParts {
        network,
        training: training.as_ref(),
        history_csv: &history_csv(history),
        extra,
    };
    write_common(dir, parts)
}

/// The per-epoch history as CSV: one row per epoch and network.
pub fn history_csv(history: &TrainingHistory) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(["epoch", "net", "loss", "energy", "val_loss"])
        .expect("in memory");
    for e in &history.epochs {
        for net in &e.nets {
            w.write_record([
                e.epoch.to_string(),
                net.name.clone(),
                net.loss.to_string(),
                net.energy.to_string(),
                net.val_loss.map(|v| v.to_string()).unwrap_or_default(),
            ])
            .expect("in memory");
        }
    }
    w.into_inner().expect("in memory")
}
