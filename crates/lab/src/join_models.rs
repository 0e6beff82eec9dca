//! `tactrace ensemble`: pin models trained apart on the same rows (other
//! seeds, or the snapshots of one run continued by `train --init`) joined
//! into one model folder, an ensemble whose prediction averages theirs
//! (`tactrace_learn::PoseModel::join`), so `validate`, `predict`,
//! `follow` and Python take it as any model. Refused before anything is
//! written when the members' pins are ordered otherwise, they were trained
//! on other rows, or their nets see or answer otherwise.
use crate::error::{LabError, Result};
use std::path::{Path, PathBuf};
use tactrace_learn::{PoseModel, TrainingHistory};
use tactrace_store::{stage_model, StoredModel, TrainingRecord};

/// The file of a joined folder recording its members.
pub const MEMBERS_FILE: &str = "members.toml";

/// The models in `dirs` (pin model folders, at least one) joined into one
/// ensemble, with the text of its [`MEMBERS_FILE`]: each member's folder,
/// seed, epochs and member count.
pub fn join_models(dirs: &[PathBuf]) -> Result<(StoredModel, String)> {
    let mut stored = Vec::with_capacity(dirs.len());
    for dir in dirs {
        stored.push(StoredModel::load(dir)?);
    }
    let Some(first) = stored.first() else {
        return Err(LabError::Config("ensemble: no --member given".into()));
    };
    let training = same_training(&stored, dirs)?;
    let pins = first.reference_pins().to_vec();
    let mut models = Vec::with_capacity(stored.len());
    for (model, dir) in stored.into_iter().zip(dirs) {
        // Refused, naming the member, when its pins are ordered otherwise.
        models.push(model.into_model_for(&pins, dir)?);
    }
    let joined = PoseModel::join(&models)?;
    let record = members_record(&models, dirs);
    let mut out = StoredModel::new(joined, pins);
    if let Some(t) = training {
        out = out.with_training(t);
    }
    Ok((out, record))
}

/// Write the joined `model` and its members' `record` into `dir` (staged,
/// then renamed into place: it appears only when complete; `force`
/// replaces an existing folder).
pub fn save_joined(dir: &Path, model: &StoredModel, record: &str, force: bool) -> Result<PathBuf> {
    let history = TrainingHistory {
        member_lr_halvings: model
            .for_pins(model.reference_pins(), dir)?
            .member_lr_halvings(),
        ..TrainingHistory::default()
    };
    let extra = [(MEMBERS_FILE, record.to_string())];
    let stage = stage_model(dir, model, &history, force, &extra)?;
    Ok(stage.commit()?)
}

/// The training record the members share (the same dataset, by its
/// content hash, and the same rows of it), or none when no member's
/// folder records one; refused when they differ or only some record it.
fn same_training(stored: &[StoredModel], dirs: &[PathBuf]) -> Result<Option<TrainingRecord>> {
    let first = stored.first().and_then(StoredModel::training);
    for (model, dir) in stored.iter().zip(dirs).skip(1) {
        let same = match (first, model.training()) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                a.dataset.sha256 == b.dataset.sha256 && a.train_rows == b.train_rows
            }
            _ => false,
        };
        if !same {
            return Err(LabError::Config(format!(
                "ensemble: {} was trained on other rows than {} (or only one of them records \
                 its rows): members are joined only when trained on the same rows, so that \
                 the ensemble's record of the rows it has seen stays true",
                dir.display(),
                dirs[0].display()
            )));
        }
    }
    Ok(first.cloned())
}

/// [`MEMBERS_FILE`]: every member's folder (as given), seed, epochs its
/// nets trained (with those of any model it continued) and members.
fn members_record(models: &[PoseModel], dirs: &[PathBuf]) -> String {
    let mut text = String::from(
        "# the models joined into this ensemble (tactrace ensemble), in order: their \
         folders, seeds, epochs and members\n",
    );
    for (model, dir) in models.iter().zip(dirs) {
        let cfg = model.config();
        let folder = toml::Value::String(dir.display().to_string());
        text.push_str(&format!(
            "\n[[member]]\nmodel = {folder}\nseed = {}\nepochs = {}\nensemble = {}\n",
            seed_text(cfg.seed),
            model.epochs_before() + cfg.epochs,
            cfg.ensemble
        ));
    }
    text
}

/// A seed as TOML: an integer when TOML can hold it, else a string.
fn seed_text(seed: u64) -> String {
    match i64::try_from(seed) {
        Ok(s) => s.to_string(),
        Err(_) => format!("\"{seed}\""),
    }
}
