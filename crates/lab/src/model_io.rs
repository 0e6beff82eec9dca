//! Model directories: `model.json` (architecture, hyper-parameters,
//! standardisation, PCA), `weights.safetensors`, `pins.json` (the reference
//! pins of the training data, whose order the inputs follow; see
//! [`crate::pin_order`]), `history.csv` and the loss/energy figure (report
//! Fig. 4.5).
use crate::error::{LabError, Result};
use crate::fsutil::{read_text, StagedDir};
use std::path::{Path, PathBuf};
use tactrace_learn::{PoseModel, TrainingHistory};

const MODEL_JSON: &str = "model.json";
const WEIGHTS: &str = "weights.safetensors";
const PINS: &str = "pins.json";

/// `pins.json`: the training data's reference pins (px, their order).
#[derive(serde::Serialize, serde::Deserialize)]
struct PinsFile {
    reference_pins: Vec<[f64; 2]>,
}

/// Save a trained model, the reference pins of its training data and its
/// training history atomically into `dir`.
pub fn save_model(
    dir: &Path,
    model: &PoseModel,
    reference_pins: &[[f64; 2]],
    history: &TrainingHistory,
    force: bool,
) -> Result<PathBuf> {
    save_model_with(dir, model, reference_pins, history, force, &[])
}

/// As [`save_model`], with extra text files `(name, contents)` in the same
/// atomic commit (e.g. the hyper-parameter search's trials).
pub fn save_model_with(
    dir: &Path,
    model: &PoseModel,
    reference_pins: &[[f64; 2]],
    history: &TrainingHistory,
    force: bool,
    extra: &[(&str, String)],
) -> Result<PathBuf> {
    let stage = StagedDir::new(dir, force)?;
    let pins = PinsFile {
        reference_pins: reference_pins.to_vec(),
    };
    let pins = serde_json::to_string(&pins).expect("pins serialise");
    write(&stage.path().join(PINS), pins.as_bytes())?;
    for (name, text) in extra {
        write(&stage.path().join(name), text.as_bytes())?;
    }
    let (json, weights) = model.to_bytes()?;
    write(&stage.path().join(MODEL_JSON), json.as_bytes())?;
    write(&stage.path().join(WEIGHTS), &weights)?;
    write(
        &stage.path().join("history.csv"),
        history_csv(history).as_bytes(),
    )?;
    crate::figures::training_curves(&stage.path().join("loss_energy"), history)?;
    stage.commit()
}

/// Load a model saved by [`save_model`], with errors naming the file.
pub fn load_model(dir: &Path) -> Result<PoseModel> {
    let json_path = dir.join(MODEL_JSON);
    if !json_path.exists() {
        return Err(LabError::Format {
            path: dir.into(),
            reason: format!(
                "not a model directory: no {MODEL_JSON} (train one with `tactrace train`)"
            ),
        });
    }
    let json = read_text(&json_path)?;
    let weights_path = dir.join(WEIGHTS);
    let weights = std::fs::read(&weights_path).map_err(crate::error::io_err(&weights_path))?;
    PoseModel::from_bytes(&json, &weights).map_err(|e| LabError::Format {
        path: dir.into(),
        reason: e.to_string(),
    })
}

/// The reference pins saved with the model in `dir`, or `None` for a model
/// saved before they were (its data cannot be checked).
pub fn load_reference_pins(dir: &Path) -> Result<Option<Vec<[f64; 2]>>> {
    let path = dir.join(PINS);
    if !path.exists() {
        return Ok(None);
    }
    let file: PinsFile =
        serde_json::from_str(&read_text(&path)?).map_err(|e| LabError::Format {
            path: path.clone(),
            reason: e.to_string(),
        })?;
    Ok(Some(file.reference_pins))
}

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(crate::error::io_err(path))
}

/// The per-epoch history as CSV: one row per epoch and network.
pub fn history_csv(history: &TrainingHistory) -> String {
    let mut out = String::from("epoch,net,loss,energy,val_loss\n");
    for e in &history.epochs {
        for net in &e.nets {
            out.push_str(&format!(
                "{},{},{},{},{}\n",
                e.epoch,
                net.name,
                net.loss,
                net.energy,
                net.val_loss.map(|v| v.to_string()).unwrap_or_default()
            ));
        }
    }
    out
}
