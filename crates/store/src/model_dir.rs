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
use crate::error::{write_err, Result, StoreError};
use crate::fsutil::{read_text, StagedDir};
use crate::input_file::{read_bounded, MAX_BINARY_BYTES};
use crate::pin_order::pin_order_mismatch;
use crate::training_record::{TrainingRecord, TRAINING_FILE};
use std::path::{Path, PathBuf};
use tactrace_learn::{PoseModel, TrainingHistory};

const MODEL_JSON: &str = "model.json";
const WEIGHTS: &str = "weights.safetensors";
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
        let json = read_text(&json_path)?;
        let weights_path = dir.join(WEIGHTS);
        let weights = read_bounded(&weights_path, MAX_BINARY_BYTES, "weights file")?;
        let model = PoseModel::from_bytes(&json, &weights).map_err(|e| StoreError::Format {
            path: dir.into(),
            reason: e.to_string(),
        })?;
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

    /// As [`Self::for_pins`], giving up the stored model.
    pub fn into_model_for(self, pins: &[[f64; 2]], what: &Path) -> Result<PoseModel> {
        self.for_pins(pins, what)?;
        Ok(self.model)
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

/// `training.json` of `dir`, if there is one (older folders have none).
pub(crate) fn read_training(dir: &Path) -> Result<Option<TrainingRecord>> {
    let path = dir.join(TRAINING_FILE);
    if !path.exists() {
        return Ok(None);
    }
    let bad = |reason: String| StoreError::Format {
        path: path.clone(),
        reason,
    };
    let record: TrainingRecord =
        serde_json::from_str(&read_text(&path)?).map_err(|e| bad(e.to_string()))?;
    record.check().map_err(bad)?;
    Ok(Some(record))
}

/// Write a trained model (with the reference pins of its training data and,
/// when known, the record of its training rows), its training history and
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
    let pins = PinsFile {
        reference_pins: model.reference_pins.clone(),
    };
    let pins = serde_json::to_string(&pins).expect("pins serialise");
    write(&stage.path().join(PINS), pins.as_bytes())?;
    if let Some(training) = &model.training {
        let text = serde_json::to_string(training).expect("record serialises");
        write(&stage.path().join(TRAINING_FILE), text.as_bytes())?;
    }
    for (name, text) in extra {
        write(&stage.path().join(name), text.as_bytes())?;
    }
    let (json, weights) = model.model.to_bytes().map_err(|e| StoreError::Format {
        path: dir.into(),
        reason: e.to_string(),
    })?;
    write(&stage.path().join(MODEL_JSON), json.as_bytes())?;
    write(&stage.path().join(WEIGHTS), &weights)?;
    write(&stage.path().join("history.csv"), &history_csv(history))?;
    Ok(stage)
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(write_err(path))
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
