//! What every model folder holds, pin model or image model alike: the
//! network as `model.json` + `weights.safetensors`, `training.json`
//! (which rows of which dataset it was trained on; absent in older
//! folders), `history.csv` and the caller's text files (`config.toml`,
//! ...). [`crate::model_dir`] and [`crate::image_model_dir`] read and
//! write these parts here, one way, beside their own files, in a staging
//! folder that appears whole or not at all ([`crate::fsutil::StagedDir`]).
use crate::error::{write_err, Result, StoreError};
use crate::fsutil::read_text;
use crate::input_file::{read_bounded, MAX_BINARY_BYTES};
use crate::training_record::{TrainingRecord, TRAINING_FILE};
use std::path::Path;

/// The network's architecture, settings and fitted statistics.
pub(crate) const MODEL_JSON: &str = "model.json";
/// The network's weights.
pub(crate) const WEIGHTS: &str = "weights.safetensors";
/// The per-epoch training history.
const HISTORY_CSV: &str = "history.csv";

/// `model.json` (text) and `weights.safetensors` (bytes, bounded) of `dir`.
pub(crate) fn read_network(dir: &Path) -> Result<(String, Vec<u8>)> {
    let json = read_text(&dir.join(MODEL_JSON))?;
    let weights = read_bounded(&dir.join(WEIGHTS), MAX_BINARY_BYTES, "weights file")?;
    Ok((json, weights))
}

/// A network in `dir` that does not parse or serialise, as an error naming
/// the folder.
pub(crate) fn network_error(dir: &Path, reason: impl std::fmt::Display) -> StoreError {
    StoreError::Format {
        path: dir.into(),
        reason: reason.to_string(),
    }
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

/// The parts of a model folder both kinds write.
pub(crate) struct CommonParts<'a> {
    /// `model.json` and `weights.safetensors`, as the network serialised.
    pub network: (String, Vec<u8>),
    /// What it was trained on, when known.
    pub training: Option<&'a TrainingRecord>,
    /// `history.csv`'s bytes.
    pub history_csv: &'a [u8],
    /// The caller's text files, `(name, contents)`.
    pub extra: &'a [(&'a str, String)],
}

/// Write `parts` into the folder `dir` (a staging folder, or a folder
/// inside one).
pub(crate) fn write_common(dir: &Path, parts: CommonParts) -> Result<()> {
    if let Some(training) = parts.training {
        let text = serde_json::to_string(training).expect("record serialises");
        write_file(&dir.join(TRAINING_FILE), text.as_bytes())?;
    }
    for (name, text) in parts.extra {
        write_file(&dir.join(name), text.as_bytes())?;
    }
    let (json, weights) = &parts.network;
    write_file(&dir.join(MODEL_JSON), json.as_bytes())?;
    write_file(&dir.join(WEIGHTS), weights)?;
    write_file(&dir.join(HISTORY_CSV), parts.history_csv)
}

/// Write one file of a staging folder.
pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(write_err(path))
}
