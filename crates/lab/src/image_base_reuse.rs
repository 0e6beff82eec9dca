//! `[base] from = "MODEL"` (docs/learning.md, "The residual on a pin
//! model"): a residual image model's base taken from the folder of a
//! residual model trained before instead of fitted again. Its pin model
//! (`base/`), its deal of the rows into folds and its training rows'
//! out-of-fold base predictions (`training.json`) are taken as they are,
//! so a network of another seed or configuration learns against the very
//! base the first one did, and costs none of the base's `folds + 1` pin
//! model fits.
//!
//! Taken only when it is the base this training would fit: the same
//! training rows in the same order (each row's hash, and the reference
//! pins its pin model reads), and the same `[base]` settings (`model`,
//! `folds`, `fit_on` and `[base.settings]`, as the folder's `config.toml`
//! records them); anything else is refused with what differs. The deal's
//! seed is the folder's, whatever this training's seed is.
use crate::error::{LabError, Result};
use crate::image_base::{split_base_table, BaseSettings};
use crate::train::data_targets;
use std::path::Path;
use tactrace_learn::{first_setting_difference, PoseModel};
use tactrace_store::training_record::row_hashes;
use tactrace_store::{BaseFolds, LoadedModel, StoredImageModel, TapData};

/// The base of the residual model folder `settings.from` for the training
/// rows `data` (flagged `in_first` as [`crate::image_base::fit_base`]
/// takes them): its pin model, the rows' out-of-fold predictions (`rows x
/// T`) and its record of the folds, marked as reused. Refused unless the
/// folder's base is the one `settings` would fit on these rows.
pub fn reuse_base(
    settings: &BaseSettings,
    data: &TapData,
    in_first: &[bool],
) -> Result<(PoseModel, Vec<f64>, BaseFolds)> {
    let from = settings.from.as_deref().unwrap_or_default();
    let dir = Path::new(from);
    let refuse = |why: String| LabError::Config(format!("[base] from = \"{from}\": {why}"));
    let stored = match LoadedModel::load(dir)? {
        LoadedModel::Image(m) if m.model().base().is_some() => m,
        _ => return Err(refuse("not a residual image model's folder".into())),
    };
    if let Some(setting) = differing_setting(settings, &source_settings(dir)?) {
        return Err(refuse(format!(
            "its base was fitted with other settings ({setting} differs): its [base] \
             table and `from` are the table to give"
        )));
    }
    let folds = source_folds(&stored).map_err(refuse)?;
    same_rows(&folds, &stored, data, in_first).map_err(refuse)?;
    stored.check_pins(&data.meta.reference_pins, dir)?;
    let pin_model = stored.model().base().expect("checked above").clone();
    let predictions = folds.predictions.clone();
    let record = BaseFolds {
        reused_from: Some(from.to_string()),
        ..folds
    };
    Ok((pin_model, predictions, record))
}

/// The `[base]` table the folder `dir`'s `config.toml` records.
fn source_settings(dir: &Path) -> Result<BaseSettings> {
    let path = dir.join("config.toml");
    let text = tactrace_store::fsutil::read_text(&path)?;
    let (_, base) = split_base_table(&text)?;
    base.ok_or_else(|| LabError::Format {
        path,
        reason: "no [base] table: not the configuration of a residual model".into(),
    })
}

/// The first of `given`'s settings (`from` aside) that is not `source`'s,
/// named as the configuration writes it; `None` when they are the same.
/// A `[base.settings]` key written otherwise but resolving alike (say the
/// default given explicitly) is the same.
pub fn differing_setting(given: &BaseSettings, source: &BaseSettings) -> Option<String> {
    if given.model != source.model {
        return Some("model".into());
    }
    if given.folds != source.folds {
        return Some("folds".into());
    }
    if given.fit_on != source.fit_on {
        return Some("fit_on".into());
    }
    if given.settings == source.settings {
        return None;
    }
    // Named by the resolved configurations where both resolve (so a key
    // spelt out at its default is no difference), else by the tables.
    let named = match (given.config(), source.config()) {
        (Ok(x), Ok(y)) => first_setting_difference(&x, &y),
        _ => first_setting_difference(&given.settings, &source.settings),
    };
    match named {
        Ok(None) => None,
        Ok(Some(d)) => Some(format!("[base.settings] {}", d.key)),
        Err(_) => Some("[base.settings]".into()),
    }
}

/// The folder's record of its base, with the predictions it was trained
/// against; the reason when it has none.
fn source_folds(stored: &StoredImageModel) -> std::result::Result<BaseFolds, String> {
    let record = stored.training().and_then(|t| t.base.as_ref());
    match record {
        None => Err("its training.json records no base".into()),
        Some(b) if b.predictions.is_empty() => Err(
            "its training.json keeps no base predictions (trained before they were kept): \
             train it again to reuse its base"
                .into(),
        ),
        Some(b) => Ok(b.clone()),
    }
}

/// Whether `data`'s rows are the folder's training rows, in order, with
/// its targets, and the first dataset's rows where its base was fitted on
/// those alone; the reason when they are not.
fn same_rows(
    folds: &BaseFolds,
    stored: &StoredImageModel,
    data: &TapData,
    in_first: &[bool],
) -> std::result::Result<(), String> {
    let record = stored.training().expect("its folds are in it");
    let (theirs, ours) = (&record.row_hashes, row_hashes(data));
    if theirs.len() != ours.len() {
        return Err(format!(
            "its base was fitted on {} training rows, these are {}",
            theirs.len(),
            ours.len()
        ));
    }
    if let Some(r) = (0..ours.len()).find(|&r| theirs[r] != ours[r]) {
        return Err(format!(
            "its base was fitted on other rows: training row {r} differs (another dataset, \
             split or order)"
        ));
    }
    let names: Vec<&str> = stored
        .model()
        .outputs()
        .iter()
        .map(|t| t.name.as_str())
        .collect();
    let targets = data_targets(data).map_err(|e| e.to_string())?;
    let given: Vec<&str> = targets.iter().map(|t| t.name.as_str()).collect();
    if names != given {
        return Err(format!(
            "it predicts {}, these rows' targets are {}",
            names.join(", "),
            given.join(", ")
        ));
    }
    let first = (0..in_first.len())
        .find(|&r| folds.first_dataset_only && (folds.fold_of_row[r] < folds.folds) != in_first[r]);
    match first {
        Some(r) => Err(format!(
            "training row {r} is of another dataset than when its base was fitted"
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base(text: &str) -> BaseSettings {
        split_base_table(text).unwrap().1.unwrap()
    }

    /// A key's default written out resolves alike and is no difference;
    /// a value that resolves otherwise is named, and so are the table's
    /// own keys; `from` itself is never compared.
    #[test]
    fn settings_differ_only_where_they_resolve_otherwise() {
        let source = base("[base]\nmodel = \"disdennn\"\n[base.settings]\nepochs = 30\n");
        let mut given = source.clone();
        given.from = Some("elsewhere".into());
        assert_eq!(differing_setting(&given, &source), None);
        let default = source.config().unwrap().seed;
        let explicit = base(&format!(
            "[base]\nmodel = \"disdennn\"\n[base.settings]\nepochs = 30\nseed = {default}\n"
        ));
        assert_eq!(differing_setting(&explicit, &source), None);
        let other = base("[base]\nmodel = \"disdennn\"\n[base.settings]\nepochs = 31\n");
        let named = differing_setting(&other, &source);
        assert_eq!(named.as_deref(), Some("[base.settings] epochs"));
        let folds = base("[base]\nmodel = \"disdennn\"\nfolds = 4\n[base.settings]\nepochs = 30\n");
        assert_eq!(differing_setting(&folds, &source).as_deref(), Some("folds"));
        // The key named is the one that resolves otherwise, not merely the
        // first written otherwise (`divergence_retries`, at its default).
        let retries = source.config().unwrap().divergence_retries;
        let both = base(&format!(
            "[base]\nmodel = \"disdennn\"\n[base.settings]\nepochs = 30\n\
             divergence_retries = {retries}\nseed = {}\n",
            default + 1
        ));
        let named = differing_setting(&both, &source);
        assert_eq!(named.as_deref(), Some("[base.settings] seed"));
    }
}
