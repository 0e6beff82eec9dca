//! Several datasets as one training set (`train --train A --train B`):
//! two collections of one sensor, or a simulator's taps beside real ones.
//!
//! Rows are joined in the order the datasets are given, each dataset's
//! rows in its own order, so a dataset cut in two and joined again is the
//! same training set, row for row. Before anything is joined every
//! dataset is checked against the first, and refused by what differs
//! ([`DatasetMismatch`]): the pin count, the reference pins' order (a
//! displacement vector lists its pins in the reference's order,
//! ARCHITECTURE invariant 7), the targets (names, units, circularity),
//! and for the image models the frames (size and the sensor
//! preprocessing they went through).
use crate::dataset::{DatasetMeta, TapData, TrackTotals};
use crate::error::{Result, StoreError};
use crate::image_frames::{FramesInfo, ImageFrames};
use crate::pin_order::{pin_order_mismatch, PinOrderError};
use std::path::Path;
use tactrace_learn::ModelTarget;

/// What two datasets given to be trained on together disagree on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DatasetMismatch {
    /// Another number of pins (inputs a row).
    #[error(
        "their pin counts differ: {first} pins ({first_inputs} inputs a row) against \
         {other} pins ({other_inputs} inputs a row)"
    )]
    PinCount {
        first: usize,
        first_inputs: usize,
        other: usize,
        other_inputs: usize,
    },
    /// The same pin count, ordered against another reference.
    #[error("their reference pins differ")]
    PinOrder(#[source] PinOrderError),
    /// Other targets: names, units or circularity.
    #[error("their targets differ: {first} against {other}")]
    Targets { first: String, other: String },
    /// Frames of another size or preprocessing (image models).
    #[error("their frames differ: {first} against {other}")]
    Frames { first: String, other: String },
}

/// Error unless there is a part and every part is `alike` the first;
/// the refusal names the first's folder and the other's.
fn check_each<T>(
    parts: &[(&Path, &T)],
    alike: impl Fn(&T, &T) -> Result<(), DatasetMismatch>,
) -> Result<()> {
    let Some(&(first_path, first)) = parts.first() else {
        return Err(StoreError::Config {
            what: "the training sets".into(),
            reason: "no dataset given".into(),
        });
    };
    for &(path, other) in &parts[1..] {
        alike(first, other).map_err(|why| StoreError::Mismatch {
            first: first_path.to_path_buf(),
            other: path.to_path_buf(),
            mismatch: why,
        })?;
    }
    Ok(())
}

/// The datasets `parts` (each with the folder it was read from) as one,
/// rows in the order given; refused, naming the two folders and what
/// differs, unless every part has the first's pins, reference order and
/// targets. The joined `meta.json` keeps the first's pins and targets and
/// sums the counts ([`joined_meta`]).
pub fn join_datasets(parts: &[(&Path, &TapData)]) -> Result<TapData> {
    check_each(parts, check_alike)?;
    let mut inputs = Vec::new();
    let mut targets = Vec::new();
    for (_, data) in parts {
        inputs.extend_from_slice(&data.inputs);
        targets.extend_from_slice(&data.targets);
    }
    let metas: Vec<&DatasetMeta> = parts.iter().map(|(_, d)| &d.meta).collect();
    Ok(TapData {
        inputs,
        targets,
        meta: joined_meta(&metas),
    })
}

/// Why `other` cannot be trained on beside `first`, if it cannot.
pub fn check_alike(first: &TapData, other: &TapData) -> Result<(), DatasetMismatch> {
    let (a, b) = (&first.meta.reference_pins, &other.meta.reference_pins);
    if a.len() != b.len() || first.dim() != other.dim() {
        return Err(DatasetMismatch::PinCount {
            first: a.len(),
            first_inputs: first.dim(),
            other: b.len(),
            other_inputs: other.dim(),
        });
    }
    if let Some(why) = pin_order_mismatch(a, b) {
        return Err(DatasetMismatch::PinOrder(why));
    }
    let (ta, tb) = (targets_of(&first.meta), targets_of(&other.meta));
    if ta != tb {
        return Err(DatasetMismatch::Targets {
            first: ta,
            other: tb,
        });
    }
    Ok(())
}

/// A dataset's targets as one line: `r (mm), theta (deg, circular)`.
fn targets_of(meta: &DatasetMeta) -> String {
    let Ok(targets) = meta.model_targets() else {
        return meta.targets.join(", ");
    };
    let one = |t: &ModelTarget| {
        let circular = if t.circular { ", circular" } else { "" };
        format!("{} ({}{circular})", t.name, t.unit.as_str())
    };
    targets.iter().map(one).collect::<Vec<_>>().join(", ")
}

/// The `meta.json` of datasets joined in order: the first's pins, targets
/// and reference; counts summed; `source`, `seed`, `settings` and the
/// version kept when every part agrees (else "mixed", none, the list of
/// each part's settings, the versions joined); `origin` of each part
/// joined by " + "; image names kept when every part names every row.
pub fn joined_meta(parts: &[&DatasetMeta]) -> DatasetMeta {
    let first = parts[0];
    let all_same = |f: &dyn Fn(&DatasetMeta) -> String| parts.iter().all(|m| f(m) == f(first));
    let mut meta = first.clone();
    if !all_same(&|m| m.source.clone()) {
        meta.source = "mixed".into();
    }
    meta.origin = join_text(parts.iter().map(|m| m.origin.as_str()));
    if !parts.iter().all(|m| m.seed == first.seed) {
        meta.seed = None;
    }
    if !parts.iter().all(|m| m.settings == first.settings) {
        meta.settings = parts.iter().map(|m| m.settings.clone()).collect();
    }
    if !all_same(&|m| m.tactrace_version.clone()) {
        meta.tactrace_version = join_text(parts.iter().map(|m| m.tactrace_version.as_str()));
    }
    meta.samples = parts.iter().map(|m| m.samples).sum();
    meta.frames_with_missing_pins = parts.iter().map(|m| m.frames_with_missing_pins).sum();
    meta.images = if parts.iter().all(|m| m.images.len() == m.samples) {
        parts
            .iter()
            .flat_map(|m| m.images.iter().cloned())
            .collect()
    } else {
        Vec::new()
    };
    meta.tracking = summed_tracking(parts.iter().map(|m| m.tracking));
    meta
}

fn join_text<'a>(parts: impl Iterator<Item = &'a str>) -> String {
    parts.collect::<Vec<_>>().join(" + ")
}

/// Tracking counts summed; a pin count only when every part has it.
fn summed_tracking(parts: impl Iterator<Item = TrackTotals>) -> TrackTotals {
    let add = |a: Option<usize>, b: Option<usize>| a.zip(b).map(|(a, b)| a + b);
    parts
        .reduce(|a, b| TrackTotals {
            frames_total: a.frames_total + b.frames_total,
            frames_fully_tracked: a.frames_fully_tracked + b.frames_fully_tracked,
            pins_matched: add(a.pins_matched, b.pins_matched),
            pins_split: add(a.pins_split, b.pins_split),
            pins_filled: add(a.pins_filled, b.pins_filled),
        })
        .unwrap_or_default()
}

/// The frames of datasets joined in the same order as their rows
/// ([`join_datasets`]), refused unless every part's frames have the
/// first's size and preprocessing; the first's description is kept.
pub fn join_frames(parts: &[(&Path, &ImageFrames)]) -> Result<ImageFrames> {
    check_each(parts, |a, b| check_frames_alike(&a.info, &b.info))?;
    let first = parts[0].1;
    let pixels = parts
        .iter()
        .flat_map(|(_, f)| f.pixels.iter().copied())
        .collect();
    Ok(ImageFrames {
        info: first.info.clone(),
        pixels,
    })
}

/// Why frames made as `other` says cannot be trained on beside frames
/// made as `first` says: another size, or another sensor preprocessing.
pub fn check_frames_alike(first: &FramesInfo, other: &FramesInfo) -> Result<(), DatasetMismatch> {
    let key = |f: &FramesInfo| (f.height, f.width, f.preprocess.clone());
    if key(first) == key(other) {
        return Ok(());
    }
    let both = first.preprocess.is_some() && other.preprocess.is_some();
    let other_settings = both && first.preprocess != other.preprocess;
    Err(DatasetMismatch::Frames {
        first: frames_of(first, "a sensor's settings"),
        other: frames_of(
            other,
            if other_settings {
                "other settings"
            } else {
                "a sensor's settings"
            },
        ),
    })
}

/// How frames were made, in words: `64 x 64 px, no preprocessing
/// recorded`, or `preprocessed by SETTINGS`.
fn frames_of(f: &FramesInfo, settings: &str) -> String {
    let how = match f.preprocess {
        Some(_) => format!("preprocessed by {settings}"),
        None => "no preprocessing recorded".into(),
    };
    format!("{} x {} px, {how}", f.height, f.width)
}
