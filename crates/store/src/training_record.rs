//! What a model was trained on: `training.json` of a model folder.
//!
//! A model folder records which rows of which dataset it was fitted on, so
//! that scoring it on its own training rows cannot go unnoticed: the
//! dataset's content hash and row count, the indices of the training rows,
//! the held-out split (`--val-fraction` / `--split-seed`) with the indices
//! of its rows, a hash of every training row, and for real frames their
//! image names. `validate` counts the rows it scores that the model has
//! seen by their row hashes, so a renamed copy of the dataset, or another
//! selection of the same rows, is caught as well as the dataset itself;
//! `follow --replay` compares its bank's image names with the training
//! frames'.
//!
//! The hashes depend on the numbers only, not on the files: SHA-256 of
//! little-endian bytes. A dataset's is of the row count and the row length
//! (two u64), then every input value, then every target value (f32, the
//! values of `inputs.npy` and `targets.npy` in row order), written
//! `sha256:` and 64 hex digits; a row's is of its inputs then its two
//! targets (f32), the first 8 bytes in 16 hex digits. A dataset written
//! again (by Python, say) hashes alike.
//!
//! A model trained on several datasets at once (`train --train A --train
//! B`) records their rows joined in order as `dataset` (no path) and each
//! dataset apart, in that order, in `datasets`; the row indices are of the
//! joined rows. A model of one dataset writes no `datasets`.
//!
//! Model folders written before tactrace kept this file load as before;
//! what they were trained on is then unknown.
use crate::dataset::TapData;
pub use crate::tap_split::SplitUnit;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::HashSet;

/// The file of a model folder holding its [`TrainingRecord`].
pub const TRAINING_FILE: &str = "training.json";

/// The layout version of `training.json`.
pub const TRAINING_FORMAT: u32 = 1;

/// The rows of one dataset a model was trained on (`training.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainingRecord {
    /// [`TRAINING_FORMAT`] when written.
    pub format: u32,
    /// The dataset the row indices are of (several datasets' rows joined,
    /// when `datasets` lists them).
    pub dataset: DatasetId,
    /// The datasets joined into `dataset`, in the order of their rows,
    /// when the model was trained on more than one; empty otherwise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub datasets: Vec<DatasetId>,
    /// The part of the dataset held out, when one was (`--val-fraction`).
    pub split: Option<HeldOut>,
    /// Indices of the rows the model was fitted on.
    pub train_rows: Vec<usize>,
    /// The hash of each training row, in the order of `train_rows`.
    pub row_hashes: Vec<String>,
    /// The image name of each training row, for a dataset of real frames
    /// (`source` "real" with image names); empty otherwise.
    #[serde(default)]
    pub images: Vec<String>,
    /// For an ensemble, how often each member's learning rates were
    /// halved after it diverged (a member restarts alone, the others keep
    /// their results); empty for a single model and in older folders.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub member_lr_halvings: Vec<usize>,
    /// A residual image model's base (`input = "pin_model_and_pixels"`):
    /// how its training rows' base predictions were made; absent for any
    /// other model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<BaseFolds>,
}

/// The out-of-fold base predictions of a residual image model's training
/// rows: the rows dealt into `folds` folds from `seed`, each fold's
/// predictions from a pin model fitted on the other folds; the stored pin
/// model (`base/`) fitted on every training row, or with
/// `first_dataset_only` on the first dataset's rows only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaseFolds {
    /// The pin model's kind ("pdennn", ...).
    pub model: String,
    /// Number of folds.
    pub folds: usize,
    /// The seed of the deal.
    pub seed: u64,
    /// Each training row's fold, in the order of `train_rows`; `folds`
    /// for a row the pin models were not fitted on (`first_dataset_only`),
    /// predicted by the stored pin model.
    pub fold_of_row: Vec<usize>,
    /// The pin model was fitted on the rows of the first dataset only
    /// (`[base] fit_on = "first_dataset"`): only they were dealt into the
    /// folds. False (and left out) otherwise.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub first_dataset_only: bool,
    /// Each training row's base prediction, the network's side input
    /// (rows in the order of `train_rows`, each the targets in their
    /// order and units): kept so that `[base] from` can reuse the base.
    /// Empty in folders written before it was kept.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub predictions: Vec<f64>,
    /// The model folder whose base (pin model, folds and predictions)
    /// was reused (`[base] from`), as given; absent for a base fitted
    /// by this training.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reused_from: Option<String>,
}

/// Which dataset: its content hash, size and where it was read from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DatasetId {
    /// The folder as given to `train` (for messages; `None` for arrays
    /// given from Python).
    pub path: Option<String>,
    /// `sha256:` and 64 hex digits (see the module docs).
    pub sha256: String,
    /// Number of rows.
    pub rows: usize,
    /// The dataset's `source` (meta.json): "simulated", "real", ...
    pub source: String,
}

impl DatasetId {
    /// The identity of `data`, read from `path`.
    pub fn of(data: &TapData, path: Option<&std::path::Path>) -> Self {
        Self {
            path: path.map(|p| p.display().to_string()),
            sha256: dataset_hash(data),
            rows: data.len(),
            source: data.meta.source.clone(),
        }
    }
}

/// A held-out part: the fraction and seed it was drawn with and its rows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldOut {
    /// `--val-fraction`.
    pub val_fraction: f64,
    /// `--split-seed`.
    pub split_seed: u64,
    /// Indices of the held-out rows.
    pub rows: Vec<usize>,
    /// Whether rows or whole taps were dealt (`"tap"` when the dataset
    /// repeats a tap, as a twin's renders; absent: by row, as every
    /// dataset where no tap repeats and every folder written before).
    #[serde(default, skip_serializing_if = "SplitUnit::is_row")]
    pub unit: SplitUnit,
}

impl TrainingRecord {
    /// The record of a model fitted on the rows `train_rows` of `data`
    /// (read from `path`), with the part `split` held out.
    pub fn new(
        data: &TapData,
        path: Option<&std::path::Path>,
        train_rows: Vec<usize>,
        split: Option<HeldOut>,
    ) -> Self {
        let d = data.dim();
        let row_hashes = train_rows
            .iter()
            .map(|&r| row_hash(&data.inputs[r * d..(r + 1) * d], data.target_row(r)))
            .collect();
        let real = data.meta.source == "real" && data.meta.images.len() == data.len();
        let images = if real {
            train_rows
                .iter()
                .map(|&r| data.meta.images[r].clone())
                .collect()
        } else {
            Vec::new()
        };
        Self {
            format: TRAINING_FORMAT,
            dataset: DatasetId::of(data, path),
            datasets: Vec::new(),
            split,
            train_rows,
            row_hashes,
            images,
            member_lr_halvings: Vec::new(),
            base: None,
        }
    }

    /// Whether each training row (in the order of `train_rows`) is a row
    /// of the first dataset given: every one for a model of one dataset.
    pub fn in_first_dataset(&self) -> Vec<bool> {
        let first = self.datasets.first().unwrap_or(&self.dataset).rows;
        self.train_rows.iter().map(|&r| r < first).collect()
    }

    /// The record of a model fitted on every row of `data`.
    pub fn all_rows(data: &TapData, path: Option<&std::path::Path>) -> Self {
        Self::new(data, path, (0..data.len()).collect(), None)
    }

    /// The record of a model trained on the datasets `parts` joined in
    /// order (the record's own dataset, without a path): `datasets` lists
    /// them. One part leaves the record as it is.
    pub fn with_datasets(mut self, parts: Vec<DatasetId>) -> Self {
        if parts.len() > 1 {
            self.dataset.path = None;
            self.datasets = parts;
        }
        self
    }

    /// How many rows of `data` are rows the model was fitted on (equal
    /// row hashes: the same numbers, whatever the folder is called).
    pub fn rows_seen(&self, data: &TapData) -> usize {
        let seen: HashSet<&str> = self.row_hashes.iter().map(String::as_str).collect();
        row_hashes(data)
            .iter()
            .filter(|h| seen.contains(h.as_str()))
            .count()
    }

    /// Whether the record knows which real frames the model saw: the
    /// training data were real frames with their image names, or
    /// simulated taps (no real frame seen). `None` otherwise.
    pub fn real_frames_seen(&self) -> Option<HashSet<&str>> {
        if !self.images.is_empty() {
            return Some(self.images.iter().map(String::as_str).collect());
        }
        self.dataset
            .source
            .starts_with("simulated")
            .then(HashSet::new)
    }

    /// Whether the record is consistent (indices in range, one hash per
    /// training row); the reason when it is not.
    pub fn check(&self) -> Result<(), String> {
        let n = self.dataset.rows;
        let held = self.split.as_ref().map_or(&[][..], |s| &s.rows[..]);
        if let Some(r) = self.train_rows.iter().chain(held).find(|&&r| r >= n) {
            return Err(format!("row {r} is past the dataset's {n} rows"));
        }
        if self.row_hashes.len() != self.train_rows.len() {
            return Err(format!(
                "{} row hashes for {} training rows",
                self.row_hashes.len(),
                self.train_rows.len()
            ));
        }
        let parts: usize = self.datasets.iter().map(|d| d.rows).sum();
        if !self.datasets.is_empty() && parts != n {
            return Err(format!(
                "the datasets listed hold {parts} rows, their joined rows {n}"
            ));
        }
        if let Some(b) = &self.base {
            let past = b.folds + usize::from(b.first_dataset_only);
            let bad = b.fold_of_row.iter().any(|&f| f >= past);
            if b.fold_of_row.len() != self.train_rows.len() || bad {
                return Err(format!(
                    "the base's folds: {} rows dealt into {} folds for {} training rows",
                    b.fold_of_row.len(),
                    b.folds,
                    self.train_rows.len()
                ));
            }
            let width = b.predictions.len() / self.train_rows.len().max(1);
            if width * self.train_rows.len() != b.predictions.len() {
                return Err(format!(
                    "the base's predictions: {} values for {} training rows",
                    b.predictions.len(),
                    self.train_rows.len()
                ));
            }
        }
        if !self.images.is_empty() && self.images.len() != self.train_rows.len() {
            return Err(format!(
                "{} image names for {} training rows",
                self.images.len(),
                self.train_rows.len()
            ));
        }
        Ok(())
    }
}

/// The content hash of a dataset (see the module docs).
pub fn dataset_hash(data: &TapData) -> String {
    let mut h = Sha256::new();
    h.update((data.len() as u64).to_le_bytes());
    h.update((data.dim() as u64).to_le_bytes());
    for v in data.inputs.iter().chain(&data.targets) {
        h.update(v.to_le_bytes());
    }
    format!("sha256:{}", hex(&h.finalize()))
}

/// The hash of one row: its inputs, then its targets (see the module docs).
pub fn row_hash(inputs: &[f32], targets: &[f32]) -> String {
    let mut h = Sha256::new();
    for v in inputs.iter().chain(targets) {
        h.update(v.to_le_bytes());
    }
    hex(&h.finalize()[..8])
}

/// The hash of every row of `data`, in order.
pub fn row_hashes(data: &TapData) -> Vec<String> {
    let d = data.dim();
    (0..data.len())
        .map(|r| row_hash(&data.inputs[r * d..(r + 1) * d], data.target_row(r)))
        .collect()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DatasetMeta;

    fn data(n: usize, source: &str, images: bool) -> TapData {
        let meta: DatasetMeta = serde_json::from_value(serde_json::json!({
            "source": source, "origin": "", "seed": null, "samples": n, "pins": 1,
            "targets": ["r", "theta"], "frames_with_missing_pins": 0,
            "reference_pins": [[0.0, 0.0]], "settings": null, "tactrace_version": "",
            "images": if images { (0..n).map(|k| format!("frame_{k}_0.png")).collect() }
                      else { Vec::<String>::new() },
        }))
        .expect("meta");
        TapData {
            inputs: (0..2 * n).map(|v| v as f32 * 0.5).collect(),
            targets: (0..2 * n).map(|v| -(v as f32)).collect(),
            meta,
        }
    }

    #[test]
    fn hashes_are_of_the_numbers_and_stable() {
        let d = data(3, "simulated", false);
        // SHA-256 of (3u64, 2u64, the six inputs, the six targets), as
        // Python's hashlib gives it: a change of the hashing is seen.
        assert_eq!(
            dataset_hash(&d),
            "sha256:4cbe0a98e555b7195cbbc8d95d124cd6f0c7316e4d7958b3a0e15e4d3c9ef4c1"
        );
        let mut other = d.clone();
        other.targets[5] += 1.0;
        assert_ne!(dataset_hash(&d), dataset_hash(&other));
        let rows = row_hashes(&d);
        assert_eq!(rows.len(), 3);
        assert_eq!(rows[1], row_hash(&[1.0, 1.5], &[-2.0, -3.0]));
        assert!(rows.iter().all(|h| h.len() == 16));
        assert_eq!(rows[1], "23dd36f8e3bbb4ad");
    }

    #[test]
    fn rows_seen_counts_training_rows_in_any_copy() {
        let d = data(10, "real", true);
        let rec = TrainingRecord::new(&d, None, vec![0, 2, 4, 6, 8], None);
        rec.check().unwrap();
        assert_eq!(rec.rows_seen(&d), 5);
        assert_eq!(rec.rows_seen(&d.subset(&[1, 3, 5])), 0);
        assert_eq!(
            rec.rows_seen(&d.subset(&[9, 8, 1, 0])),
            2,
            "reordered subset"
        );
        assert_eq!(rec.images[1], "frame_2_0.png");
        let seen = rec.real_frames_seen().unwrap();
        assert!(seen.contains("frame_4_0.png") && !seen.contains("frame_5_0.png"));
        let sim = TrainingRecord::all_rows(&data(4, "simulated", false), None);
        assert_eq!(sim.real_frames_seen().map(|s| s.len()), Some(0));
        let python = TrainingRecord::all_rows(&data(4, "python", false), None);
        assert!(python.real_frames_seen().is_none(), "unknown frames");
        let mut bad = rec.clone();
        bad.train_rows.push(10);
        assert!(bad
            .check()
            .unwrap_err()
            .contains("past the dataset's 10 rows"));
    }

    /// The rows of the first of two joined datasets are told apart in
    /// training order, and a base fitted on them alone may mark the
    /// other rows with the fold past the last (only then).
    #[test]
    fn a_base_of_the_first_dataset_marks_the_other_rows_past_its_folds() {
        let (a, b) = (data(4, "real", false), data(3, "simulated", false));
        let joined = crate::join_datasets(&[
            (std::path::Path::new("a"), &a),
            (std::path::Path::new("b"), &b),
        ])
        .unwrap();
        let ids = vec![DatasetId::of(&a, None), DatasetId::of(&b, None)];
        let rec = TrainingRecord::new(&joined, None, vec![6, 0, 3, 4], None).with_datasets(ids);
        assert_eq!(rec.in_first_dataset(), [false, true, true, false]);
        let one = TrainingRecord::all_rows(&a, None);
        assert!(one.in_first_dataset().iter().all(|&f| f));
        let mut with_base = rec.clone();
        with_base.base = Some(BaseFolds {
            model: "pdennn".into(),
            folds: 2,
            seed: 0,
            fold_of_row: vec![2, 0, 1, 2],
            first_dataset_only: true,
            predictions: vec![0.5; 8],
            reused_from: None,
        });
        with_base.check().unwrap();
        let text = serde_json::to_string(&with_base).unwrap();
        assert!(text.contains("\"first_dataset_only\":true"));
        let mut every_row = with_base.clone();
        every_row.base.as_mut().unwrap().first_dataset_only = false;
        assert!(every_row.check().unwrap_err().contains("the base's folds"));
        every_row.base.as_mut().unwrap().fold_of_row = vec![1, 0, 1, 0];
        every_row.check().unwrap();
        every_row.base.as_mut().unwrap().predictions.pop();
        assert!(every_row.check().unwrap_err().contains("predictions"));
        every_row.base.as_mut().unwrap().predictions.clear();
        every_row.check().unwrap();
        let text = serde_json::to_string(&every_row).unwrap();
        assert!(!text.contains("first_dataset_only"), "left out when false");
    }
}
