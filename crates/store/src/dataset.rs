//! The on-disk dataset: readable from Python as well as from tactrace.
//!
//! A dataset directory holds
//! - `inputs.npy`: N x 2P float32 pin displacements in pixels (all x, then all y);
//! - `targets.npy`: N x T float32, the T targets in `meta.json`'s order and
//!   units (`target_names`, `target_units`, `target_circular`, and
//!   `target_roles` when a role is marked); for the edge
//!   task (and every dataset written before targets were named) T = 2, the
//!   edge position r (mm) and angle theta (deg);
//! - `meta.json`: how it was made ([`DatasetMeta`]): the layout of the
//!   inputs, the reference pins they are ordered by, and for imported or
//!   twinned real sets the image name of every row;
//! - optionally `frames/` with one PNG a sample and `reference.png`;
//! - optionally `frames.npy`, every row's frame as a small grey image
//!   for the image models ([`crate::image_frames`]).
use crate::error::{write_err, Result, StoreError};
use crate::fsutil::StagedDir;
use crate::image_frames::{ImageFrames, FRAMES_NPY};
use ndarray::Array2;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_learn::{ModelTarget, Role, Unit};

/// Provenance of a dataset, written as `meta.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DatasetMeta {
    /// "simulated" or "real".
    pub source: String,
    /// Shape tapped (simulated) or the frames folder (real).
    pub origin: String,
    /// Seed of every random choice (simulated runs).
    pub seed: Option<u64>,
    pub samples: usize,
    pub pins: usize,
    /// Target column names and units, one per column of `targets.npy`
    /// (for display: `r_mm (pose_2)`, `pose_3 (mm)`).
    pub targets: Vec<String>,
    /// The targets' label columns, units and circular flags (absent in
    /// datasets of the edge task written before: r mm, theta deg).
    #[serde(flatten)]
    pub target_columns: TargetColumns,
    /// Frames on which some pin was not matched (filled from its neighbours).
    pub frames_with_missing_pins: usize,
    /// Reference (undeformed) pin centres, px.
    pub reference_pins: Vec<[f64; 2]>,
    /// Sensor and detector settings as resolved for the run.
    pub settings: serde_json::Value,
    pub tactrace_version: String,
    /// How `inputs.npy` is laid out (written for readers; not checked).
    #[serde(default = "input_layout")]
    pub input_layout: String,
    /// The image name of every row (real and twinned sets), for joining
    /// datasets of the same frames; empty for simulated collections.
    #[serde(default)]
    pub images: Vec<String>,
    /// How the frames' pins were tracked (`frames_total`,
    /// `frames_fully_tracked`, pin totals), at the top level of meta.json.
    #[serde(flatten)]
    pub tracking: TrackTotals,
}

/// Per-dataset tracking counts: how many frames were read, how many had
/// every pin found (none filled in from its neighbours), and, where known,
/// the pins matched to a detection of their own, split from a cluster of
/// touching pins, and filled in, summed over the frames kept.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TrackTotals {
    /// Frames read (kept and rejected).
    #[serde(default)]
    pub frames_total: usize,
    /// Frames kept with no pin filled in.
    #[serde(default)]
    pub frames_fully_tracked: usize,
    /// Pins matched to a detected pin of their own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pins_matched: Option<usize>,
    /// Pins matched to a centre split from a cluster of touching pins.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pins_split: Option<usize>,
    /// Pins filled in from their neighbours' field (missing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pins_filled: Option<usize>,
}

impl TrackTotals {
    /// Frame counts only: `total` frames, `missing` of them with some pin
    /// filled in.
    pub fn frames(total: usize, missing: usize) -> Self {
        Self {
            frames_total: total,
            frames_fully_tracked: total.saturating_sub(missing),
            ..Self::default()
        }
    }
}

/// What each column of `targets.npy` is: its label column, unit and
/// whether it is circular (three lists of T, written into `meta.json` as
/// `target_names`, `target_units`, `target_circular`). Empty in datasets
/// of the edge task written before targets were named.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TargetColumns {
    /// The label columns.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub target_names: Vec<String>,
    /// Their units.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub target_units: Vec<Unit>,
    /// Whether each is circular (an angle over the full circle).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub target_circular: Vec<bool>,
    /// Each one's role in an edge task (`position`, `angle` or null);
    /// written only when a role is marked.
    #[serde(default, skip_serializing_if = "no_role")]
    pub target_roles: Vec<Option<Role>>,
}

/// The targets' roles; empty when none is marked, as a file without
/// `target_roles` reads.
fn roles(targets: &[ModelTarget]) -> Vec<Option<Role>> {
    let roles: Vec<_> = targets.iter().map(|t| t.role).collect();
    if no_role(&roles) {
        Vec::new()
    } else {
        roles
    }
}

/// Whether no role is marked (so `target_roles` is left out).
fn no_role(roles: &[Option<Role>]) -> bool {
    roles.iter().all(Option::is_none)
}

impl TargetColumns {
    /// The columns of `targets`, in order.
    pub fn of(targets: &[ModelTarget]) -> Self {
        Self {
            target_names: targets.iter().map(|t| t.name.clone()).collect(),
            target_units: targets.iter().map(|t| t.unit).collect(),
            target_circular: targets.iter().map(|t| t.circular).collect(),
            target_roles: roles(targets),
        }
    }

    /// The display names of `targets` (`pose_3 (mm)`), for `meta.targets`.
    pub fn display(targets: &[ModelTarget]) -> Vec<String> {
        targets
            .iter()
            .map(|t| format!("{} ({})", t.name, t.unit.as_str()))
            .collect()
    }
}

impl DatasetMeta {
    /// The targets of the dataset's columns, in order: as `meta.json`
    /// names them, or for a dataset written before targets were named,
    /// the edge task's r (mm) and theta (deg), named by the label column
    /// its display name gives (`r_mm (pose_2)` -> `pose_2`) or as shown.
    pub fn model_targets(&self) -> std::result::Result<Vec<ModelTarget>, String> {
        let c = &self.target_columns;
        if c.target_names.is_empty() {
            if self.targets.len() != 2 {
                return Err(format!(
                    "{} targets without target_names: name each target (target_names, \
                     target_units)",
                    self.targets.len()
                ));
            }
            let name = |s: &str| match (s.find('('), s.rfind(')')) {
                (Some(a), Some(b)) if a < b => s[a + 1..b].trim().to_string(),
                _ => s.to_string(),
            };
            return Ok(vec![
                ModelTarget::new(name(&self.targets[0]), Unit::Mm),
                ModelTarget::new(name(&self.targets[1]), Unit::Deg),
            ]);
        }
        let t = c.target_names.len();
        let circular_ok = c.target_circular.is_empty() || c.target_circular.len() == t;
        let roles_ok = c.target_roles.is_empty() || c.target_roles.len() == t;
        if c.target_units.len() != t || !circular_ok || !roles_ok || self.targets.len() != t {
            return Err(format!(
                "{t} target_names, {} target_units, {} target_circular, {} target_roles and \
                 {} targets: each lists every target",
                c.target_units.len(),
                c.target_circular.len(),
                c.target_roles.len(),
                self.targets.len()
            ));
        }
        let out: Vec<ModelTarget> = (0..t)
            .map(|k| ModelTarget {
                name: c.target_names[k].clone(),
                unit: c.target_units[k],
                circular: c.target_circular.get(k).copied().unwrap_or(false),
                role: c.target_roles.get(k).copied().flatten(),
            })
            .collect();
        tactrace_learn::check_targets(&out).map_err(|e| e.to_string())?;
        Ok(out)
    }
}

/// The layout of `inputs.npy`, as written into `meta.json`.
pub const INPUT_LAYOUT: &str =
    "N x 2P float32, pixels: the P pin x-displacements, then the P y-displacements, pins in reference_pins order";

fn input_layout() -> String {
    INPUT_LAYOUT.to_string()
}

/// A dataset in memory.
#[derive(Debug, Clone)]
pub struct TapData {
    /// N x 2P displacements, row-major.
    pub inputs: Vec<f32>,
    /// N x T targets (the meta's targets, in order; the edge task's r mm
    /// and theta deg), row-major.
    pub targets: Vec<f32>,
    pub meta: DatasetMeta,
}

impl TapData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.meta.samples
    }
    /// True when there is no sample.
    pub fn is_empty(&self) -> bool {
        self.meta.samples == 0
    }
    /// Input dimension (2P).
    pub fn dim(&self) -> usize {
        self.inputs
            .len()
            .checked_div(self.meta.samples)
            .unwrap_or(0)
    }
    /// Targets per sample (T).
    pub fn n_targets(&self) -> usize {
        self.targets
            .len()
            .checked_div(self.meta.samples)
            .unwrap_or(self.meta.targets.len())
    }

    /// Targets of sample `i`.
    pub fn target_row(&self, i: usize) -> &[f32] {
        let t = self.n_targets();
        &self.targets[i * t..(i + 1) * t]
    }

    /// Split into (first, second) with `frac` of the samples in the first,
    /// after a seeded shuffle; metadata is copied with the counts updated.
    pub fn split(&self, frac: f64, seed: u64) -> (TapData, TapData) {
        let (first, second) = self.split_rows(frac, seed);
        (self.subset(&first), self.subset(&second))
    }

    /// The row indices of the two parts of [`Self::split`], in its order.
    pub fn split_rows(&self, frac: f64, seed: u64) -> (Vec<usize>, Vec<usize>) {
        use rand::seq::SliceRandom;
        use rand::SeedableRng;
        let mut idx: Vec<usize> = (0..self.len()).collect();
        idx.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
        let cut = ((self.len() as f64 * frac).round() as usize).min(self.len());
        let second = idx.split_off(cut);
        (idx, second)
    }

    /// Row of each sample by its frame's image name (imports and twins of
    /// the same labels are joined on it); empty for simulated collections.
    pub fn image_rows(&self) -> std::collections::HashMap<&str, usize> {
        self.meta
            .images
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i))
            .collect()
    }

    /// The samples at `rows`, in that order.
    pub fn subset(&self, rows: &[usize]) -> TapData {
        let (d, t) = (self.dim(), self.n_targets());
        let mut inputs = Vec::with_capacity(rows.len() * d);
        let mut targets = Vec::with_capacity(rows.len() * t);
        for &r in rows {
            inputs.extend_from_slice(&self.inputs[r * d..(r + 1) * d]);
            targets.extend_from_slice(self.target_row(r));
        }
        let mut meta = self.meta.clone();
        meta.samples = rows.len();
        if self.meta.images.len() == self.len() {
            meta.images = rows.iter().map(|&r| self.meta.images[r].clone()).collect();
        }
        TapData {
            inputs,
            targets,
            meta,
        }
    }

    /// As the learning crate's dataset (checks finiteness and shapes).
    pub fn to_learn(&self) -> Result<tactrace_learn::Dataset, tactrace_learn::LearnError> {
        tactrace_learn::Dataset::new(
            self.inputs.clone(),
            self.targets.clone(),
            self.len(),
            self.dim(),
            self.n_targets(),
        )
    }
}

/// Write a dataset atomically into `dir`, with optional frames (name, PNG bytes).
pub fn write_dataset(
    dir: &Path,
    data: &TapData,
    frames: &[(String, Vec<u8>)],
    force: bool,
) -> Result<PathBuf> {
    write_dataset_with(dir, data, frames, None, force)
}

/// [`write_dataset`], with the rows' frames as images (`frames.npy`,
/// described in `meta.json`'s `image_frames`) when `images` is given.
pub fn write_dataset_with(
    dir: &Path,
    data: &TapData,
    frames: &[(String, Vec<u8>)],
    images: Option<&ImageFrames>,
    force: bool,
) -> Result<PathBuf> {
    let n = data.len();
    let dim = data.dim();
    let stage = StagedDir::new(dir, force)?;
    let inputs =
        Array2::from_shape_vec((n, dim), data.inputs.clone()).map_err(|e| StoreError::Format {
            path: dir.join("inputs.npy"),
            reason: format!("inputs shape: {e}"),
        })?;
    let targets =
        Array2::from_shape_vec((n, data.n_targets()), data.targets.clone()).map_err(|e| {
            StoreError::Format {
                path: dir.join("targets.npy"),
                reason: format!("targets shape: {e}"),
            }
        })?;
    let p = stage.path().join("inputs.npy");
    ndarray_npy::write_npy(&p, &inputs).map_err(|e| StoreError::Write {
        path: p.clone(),
        source: std::io::Error::other(e),
    })?;
    let p = stage.path().join("targets.npy");
    ndarray_npy::write_npy(&p, &targets).map_err(|e| StoreError::Write {
        path: p.clone(),
        source: std::io::Error::other(e),
    })?;
    if !frames.is_empty() {
        let fdir = stage.path().join("frames");
        std::fs::create_dir_all(&fdir).map_err(write_err(&fdir))?;
        for (name, bytes) in frames {
            let p = fdir.join(name);
            std::fs::write(&p, bytes).map_err(write_err(&p))?;
        }
    }
    let mut meta = serde_json::to_value(&data.meta).expect("meta serialises");
    if let Some(images) = images {
        if images.count() != n {
            return Err(StoreError::Format {
                path: dir.join(FRAMES_NPY),
                reason: format!("{} frames for {n} rows", images.count()),
            });
        }
        crate::image_frames::write_frames(stage.path(), images)?;
        if let Some(object) = meta.as_object_mut() {
            let info = serde_json::to_value(&images.info).expect("info serialises");
            object.insert("image_frames".into(), info);
        }
    }
    let meta = serde_json::to_string_pretty(&meta).expect("meta serialises");
    let p = stage.path().join("meta.json");
    std::fs::write(&p, meta).map_err(write_err(&p))?;
    stage.commit()
}

/// Read a dataset directory written by [`write_dataset`] (or by hand in Python).
pub fn read_dataset(dir: &Path) -> Result<TapData> {
    let meta_path = dir.join("meta.json");
    if !dir.is_dir() || !meta_path.exists() {
        use crate::folder_kind::{wrong_folder, DATASET_EXPECTED};
        return Err(StoreError::Format {
            path: dir.into(),
            reason: wrong_folder(dir, "dataset", "meta.json", DATASET_EXPECTED),
        });
    }
    let meta_text = crate::fsutil::read_text(&meta_path)?;
    let meta: DatasetMeta = serde_json::from_str(&meta_text).map_err(|e| StoreError::Format {
        path: meta_path.clone(),
        reason: e.to_string(),
    })?;
    let inputs: Array2<f32> = read_npy(&dir.join("inputs.npy"))?;
    let targets: Array2<f32> = read_npy(&dir.join("targets.npy"))?;
    let (n, dim) = inputs.dim();
    let t = meta.targets.len();
    if let Err(reason) = meta.model_targets() {
        return Err(StoreError::Format {
            path: meta_path,
            reason,
        });
    }
    if targets.dim() != (n, t) {
        return Err(StoreError::Format {
            path: dir.join("targets.npy"),
            reason: format!(
                "expected {n} x {t} targets to match inputs.npy and meta.json, found {} x {}",
                targets.dim().0,
                targets.dim().1
            ),
        });
    }
    if n == 0 || dim == 0 {
        return Err(StoreError::Format {
            path: dir.join("inputs.npy"),
            reason: "empty dataset".into(),
        });
    }
    if !meta.images.is_empty() && meta.images.len() != n {
        return Err(StoreError::Format {
            path: meta_path,
            reason: format!("meta lists {} images for {n} samples", meta.images.len()),
        });
    }
    if meta.samples != n {
        return Err(StoreError::Format {
            path: meta_path,
            reason: format!("meta says {} samples, inputs.npy has {n}", meta.samples),
        });
    }
    Ok(TapData {
        inputs: inputs.iter().copied().collect(),
        targets: targets.iter().copied().collect(),
        meta,
    })
}

/// The frames as images of the dataset `data` read from `dir`, when its
/// `meta.json` records some (`image_frames`); checked against its rows.
pub fn read_dataset_frames(dir: &Path, data: &TapData) -> Result<Option<ImageFrames>> {
    let text = crate::fsutil::read_text(&dir.join("meta.json"))?;
    crate::image_frames::read_image_frames(dir, &text, data.len())
}

/// What the dataset folder `dir` records of its frames as images
/// (`meta.json`'s `image_frames`), without reading them.
pub fn read_dataset_frames_info(dir: &Path) -> Result<Option<crate::FramesInfo>> {
    let p = dir.join("meta.json");
    crate::image_frames::frames_info(&crate::fsutil::read_text(&p)?, &p)
}

fn read_npy(path: &Path) -> Result<Array2<f32>> {
    crate::npy_file::read_f32_matrix(path)
}
