//! Continuing a pin model's training (`train --init` with a pin model):
//! the model of a folder trained further, by a new schedule, on the rows
//! it was trained on (`tactrace_learn::PoseModel::continue_on_pins`).
use crate::error::{LabError, Result};
use crate::train::{check_same_targets, data_targets};
use std::path::Path;
use tactrace_learn::{EpochReport, ModelConfig, PoseModel, TrainingHistory};
use tactrace_store::{StoredModel, TapData, TrainingRecord};

/// `start` trained further on `data` (read from `what`) by `cfg`, each
/// net's loss on `val` recorded per epoch (never fitted on); `progress`
/// is called with the epochs done. Refused for pins ordered otherwise
/// than `start`'s, other targets, or a configuration of other nets.
pub fn continue_training(
    start: &StoredModel,
    what: &Path,
    cfg: &ModelConfig,
    data: &TapData,
    val: Option<&TapData>,
    progress: &mut dyn FnMut(usize),
) -> Result<(PoseModel, TrainingHistory)> {
    let net = start.for_data(data, what)?;
    check_same_targets(net.outputs(), &data_targets(data)?)?;
    let ds = data.to_learn()?;
    let vs = val.map(TapData::to_learn).transpose()?;
    let mut cb = |r: &EpochReport| progress(r.epoch + 1);
    let pins = Some(data.meta.reference_pins.as_slice());
    Ok(net.continue_on_pins(cfg, &ds, vs.as_ref(), pins, &mut cb)?)
}

/// Error unless `record`'s rows (what a continued fit trains on) are the
/// rows `start`'s folder records it was trained on: the continued model's
/// folder records them as the rows it has seen, which stays true only so.
/// A folder without the record (written before it existed) is taken as is.
pub fn check_same_rows(start: &StoredModel, record: &TrainingRecord) -> Result<()> {
    let Some(was) = start.training() else {
        return Ok(());
    };
    if was.dataset.sha256 == record.dataset.sha256 && was.train_rows == record.train_rows {
        return Ok(());
    }
    Err(LabError::Config(format!(
        "--init's model was trained on {} rows of {}; --train gives {} rows of {}: a pin \
         model continues on the rows it was trained on (the same dataset and split)",
        was.train_rows.len(),
        was.dataset.path.as_deref().unwrap_or("a dataset"),
        record.train_rows.len(),
        record.dataset.path.as_deref().unwrap_or("a dataset"),
    )))
}

/// `init.toml` of a pin model continued from `start` (folder `dir`): the
/// folder as given to --init, its epochs and the epochs before them, and
/// its configuration.
pub fn init_record(dir: &Path, start: &StoredModel) -> Result<String> {
    let net = start.for_pins(start.reference_pins(), dir)?;
    let mut record = toml::Table::new();
    record.insert("model".into(), dir.display().to_string().into());
    let epochs = net.epochs_before() + net.config().epochs;
    record.insert("epochs".into(), toml::Value::Integer(epochs as i64));
    let text = |e: toml::ser::Error| LabError::Config(e.to_string());
    record.insert(
        "config".into(),
        toml::Value::try_from(net.config()).map_err(text)?,
    );
    Ok(format!(
        "# the model this one continued (train --init): the epochs its nets had \
         trained, its configuration\n{}",
        toml::to_string(&record).map_err(text)?
    ))
}
