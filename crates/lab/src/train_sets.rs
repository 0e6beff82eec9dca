//! The datasets a model is trained (or validated) on: one folder, or
//! several given together (`train --train A --train B`: two collections
//! of one sensor, a simulator's taps beside real ones), read and joined
//! row for row in the order given, after every one is checked against
//! the first ([`tactrace_store::dataset_join`]). The model folder's
//! `training.json` records each of them
//! ([`tactrace_store::TrainingRecord::with_datasets`]).
use crate::error::{LabError, Result};
use crate::train::{training_split, TrainingSplit};
use std::path::{Path, PathBuf};
use tactrace_store::image_frames::read_image_frames;
use tactrace_store::{join_datasets, join_frames, read_dataset, DatasetId, ImageFrames, TapData};

/// Datasets read from their folders and joined in order.
#[derive(Debug, Clone)]
pub struct TrainingSets {
    /// The rows of every dataset, joined in the order given.
    pub data: TapData,
    /// Each dataset's folder and identity (content hash, rows, source).
    pub parts: Vec<(PathBuf, DatasetId)>,
}

impl TrainingSets {
    /// Read the datasets in `dirs` (at least one) and join them, refused
    /// before any training when one differs from the first in its pins,
    /// their reference order or its targets.
    pub fn read(dirs: &[PathBuf]) -> Result<Self> {
        let read: Vec<TapData> = dirs
            .iter()
            .map(|d| read_dataset(d))
            .collect::<Result<_, _>>()?;
        let pairs: Vec<(&Path, &TapData)> = dirs.iter().map(PathBuf::as_path).zip(&read).collect();
        let data = join_datasets(&pairs)?;
        let parts = pairs
            .iter()
            .map(|&(dir, d)| (dir.to_path_buf(), DatasetId::of(d, Some(dir))))
            .collect();
        Ok(Self { data, parts })
    }

    /// The folder messages name: the first dataset's.
    pub fn first_dir(&self) -> &Path {
        &self.parts[0].0
    }

    /// Whether more than one dataset was given.
    pub fn is_joined(&self) -> bool {
        self.parts.len() > 1
    }

    /// Every dataset's frames as images (`frames.npy`), joined as the
    /// rows are; refused when a dataset has none, or frames of another
    /// size or preprocessing than the first's.
    pub fn frames(&self) -> Result<ImageFrames> {
        let mut read = Vec::with_capacity(self.parts.len());
        for (dir, id) in &self.parts {
            let meta = tactrace_store::read_text(&dir.join("meta.json"))?;
            let frames = read_image_frames(dir, &meta, id.rows)?;
            read.push(frames.ok_or_else(|| crate::train_image::no_frames(dir))?);
        }
        let pairs: Vec<(&Path, &ImageFrames)> = (self.parts.iter())
            .map(|(dir, _)| dir.as_path())
            .zip(&read)
            .collect();
        Ok(join_frames(&pairs)?)
    }

    /// The training split of the joined rows ([`training_split`]): all of
    /// them, or with `held_out = Some((fraction, seed))` the rows kept
    /// after holding out that fraction of the joined rows; the record
    /// names each dataset when there are several.
    pub fn split(&self, held_out: Option<(f64, u64)>) -> Result<TrainingSplit> {
        let path = (!self.is_joined()).then(|| self.first_dir());
        let mut split = training_split(&self.data, path, held_out)?;
        let ids = self.parts.iter().map(|(_, id)| id.clone()).collect();
        split.record = split.record.with_datasets(ids);
        Ok(split)
    }

    /// The datasets' folders, for messages: `a, b`.
    pub fn names(&self) -> String {
        let names: Vec<String> = (self.parts.iter())
            .map(|(dir, _)| dir.display().to_string())
            .collect();
        names.join(", ")
    }
}

/// Error unless the validation rows `val` are ordered against the same
/// reference pins as the training rows (the folder of `val` is named).
pub fn check_val_pins(train: &TrainingSets, val: &TrainingSets) -> Result<()> {
    let (a, b) = (
        &train.data.meta.reference_pins,
        &val.data.meta.reference_pins,
    );
    match tactrace_store::pin_order_mismatch(a, b) {
        None => Ok(()),
        Some(source) => Err(LabError::Store(tactrace_store::StoreError::PinOrder {
            path: val.first_dir().to_path_buf(),
            source,
        })),
    }
}
