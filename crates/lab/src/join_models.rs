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
    let record = members_record(&models, dirs)?;
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
fn members_record(models: &[PoseModel], dirs: &[PathBuf]) -> Result<String> {
    let member = models
        .iter()
        .zip(dirs)
        .map(|(model, dir)| MemberRecord {
            model: dir.display().to_string(),
            seed: model.config().seed,
            epochs: model.epochs_before() + model.config().epochs,
            ensemble: model.config().ensemble,
        })
        .collect();
    let body = toml::to_string(&MembersRecord { member })
        .map_err(|e| LabError::Config(format!("ensemble: {MEMBERS_FILE} not written: {e}")))?;
    Ok(format!(
        "# the models joined into this ensemble (tactrace ensemble), in order: their \
         folders, seeds, epochs and members\n\n{body}"
    ))
}

/// The [`MEMBERS_FILE`] record, one `[[member]]` table a member.
#[derive(serde::Serialize)]
struct MembersRecord {
    member: Vec<MemberRecord>,
}

#[derive(serde::Serialize)]
struct MemberRecord {
    model: String,
    seed: u64,
    epochs: usize,
    ensemble: usize,
}
