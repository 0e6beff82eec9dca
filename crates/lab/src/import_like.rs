//! `import --like DATASET`: another split of a collection imported with
//! the same preprocessing (blob detector), reference and targets as an
//! imported dataset, read from the collection its `meta.json` records
//! (`settings.import`), so the two splits' pins and targets mean the same.
use crate::error::{LabError, Result};
use std::path::{Path, PathBuf};
use tactrace_store::collection::RowSelection;
use tactrace_store::{LabelledCollection, TapData};

/// The collection `like` (a dataset imported from frames, at `dir`) was
/// imported from, with its frames in `frames` and labels in `targets`,
/// every row (the rows of the other split are its own).
pub fn like_collection(
    like: &TapData,
    dir: &Path,
    frames: PathBuf,
    targets: PathBuf,
) -> Result<LabelledCollection> {
    let recorded = like
        .meta
        .settings
        .get("import")
        .cloned()
        .ok_or_else(|| LabError::Format {
            path: dir.join("meta.json"),
            reason: "records no import settings (settings.import): --like takes a dataset \
                     imported from frames by `tactrace import`"
                .into(),
        })?;
    let collection: LabelledCollection =
        serde_json::from_value(recorded).map_err(|e| LabError::Format {
            path: dir.join("meta.json"),
            reason: format!("settings.import: {e}"),
        })?;
    Ok(collection
        .with_frames(frames)
        .with_targets_file(targets)
        .with_rows(RowSelection::default()))
}

/// Error unless `got` (the new split) has `like`'s reference pins (in the
/// same order: [`tactrace_store::pin_order_mismatch`]) and targets, as an
/// import `--like` must.
pub fn check_like(got: &TapData, like: &TapData, dir: &Path) -> Result<()> {
    let same_targets = got.meta.targets == like.meta.targets
        && got.meta.target_columns == like.meta.target_columns;
    let moved =
        tactrace_store::pin_order_mismatch(&like.meta.reference_pins, &got.meta.reference_pins);
    if moved.is_some() || !same_targets {
        return Err(LabError::Format {
            path: dir.to_path_buf(),
            reason: "the new split's reference pins or targets differ from this dataset's \
                     (was its reference frame changed since?)"
                .into(),
        });
    }
    Ok(())
}
