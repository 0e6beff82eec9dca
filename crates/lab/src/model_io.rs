//! Model directories: `model.json` (architecture, hyper-parameters,
//! standardisation, PCA), `weights.safetensors`, `history.csv` and the
//! loss/energy figure (report Fig. 4.5).
use crate::error::{LabError, Result};
use crate::fsutil::{read_text, StagedDir};
use std::path::{Path, PathBuf};
use tactrace_learn::{PoseModel, TrainingHistory};

const MODEL_JSON: &str = "model.json";
const WEIGHTS: &str = "weights.safetensors";

/// Save a trained model and its training history atomically into `dir`.
pub fn save_model(
    dir: &Path,
    model: &PoseModel,
    history: &TrainingHistory,
    force: bool,
) -> Result<PathBuf> {
    save_model_with(dir, model, history, force, &[])
}

/// As [`save_model`], with extra text files `(name, contents)` in the same
/// atomic commit (e.g. the hyper-parameter search's trials).
pub fn save_model_with(
    dir: &Path,
    model: &PoseModel,
    history: &TrainingHistory,
    force: bool,
    extra: &[(&str, String)],
) -> Result<PathBuf> {
    let stage = StagedDir::new(dir, force)?;
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
