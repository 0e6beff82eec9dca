//! `train --init` with a pin model: the starting model's folder read and
//! checked against the new fit before any work (docs/learning.md,
//! "Continuing a pin model").
use anyhow::Result;
use std::path::{Path, PathBuf};
use tactrace_lab::{train_continue as tc, LabError};
use tactrace_learn::{check_continuable, ModelConfig};
use tactrace_store::{LoadedModel, StoredModel, TrainingRecord};

/// The pin model `train --init` continues, with its folder.
pub(crate) fn start_model(dir: &Path) -> Result<(PathBuf, StoredModel)> {
    if let LoadedModel::Pins(m) = LoadedModel::load(dir)? {
        return Ok((dir.to_path_buf(), m));
    }
    let why = "an image model; a pin model continues only from a pin model";
    Err(LabError::Config(format!("--init {}: {why}", dir.display())).into())
}

/// Error unless `cfg` describes `start`'s nets, `record` gives the rows it
/// was trained on, and no search is asked for (a continued fit has its
/// configuration).
pub(crate) fn check_start(
    start: &StoredModel,
    cfg: &ModelConfig,
    record: &TrainingRecord,
    search: bool,
) -> Result<()> {
    if search {
        return Err(LabError::Config(
            "--search with --init: a continued fit trains the starting model's nets".into(),
        )
        .into());
    }
    let net = start.for_pins(start.reference_pins(), start.source())?;
    check_continuable(net.config(), cfg).map_err(LabError::from)?;
    tc::check_same_rows(start, record)?;
    Ok(())
}
