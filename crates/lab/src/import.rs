//! Import a labelled collection of real TacTip frames
//! ([`LabelledCollection`]) into the dataset format, through the same pin
//! extraction as simulated taps.
use crate::error::{LabError, Result};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use tactrace_sensor::read_frame;
use tactrace_store::{
    DatasetMeta, LabelledCollection, LabelledRow, TapData, TapFields, TargetColumns,
};
use tactrace_vision::{BlobParams, PinExtractor};

/// One frame's displacement and whether pins were missing, or why it was
/// rejected.
pub(crate) type FrameOutcome = std::result::Result<(Vec<f32>, bool), String>;

/// Result of an import: the dataset and a summary.
pub struct Imported {
    pub data: TapData,
    /// Frames on which at least one pin was not matched.
    pub frames_with_missing_pins: usize,
    /// Frames skipped because too few pins were found (named with the reason).
    pub rejected: Vec<(String, String)>,
    /// What the caller should tell the user (a reference that looks
    /// pressed: [`crate::import_checks::pressed_reference`]).
    pub warnings: Vec<String>,
    /// How a twin's taps were made from the labelled rows, when several
    /// renders or the real calibration taps make them more than the rows.
    pub composition: Option<TwinComposition>,
}

/// Where the taps of a calibrated sensor's twin come from
/// (`twin --sensor`): `renders` simulated taps of each of the `rows`
/// labelled rows, then the sensor's `real_taps` real calibration taps
/// `real_tap_repeats` times.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TwinComposition {
    pub rows: usize,
    pub renders: usize,
    pub real_taps: usize,
    pub real_tap_repeats: usize,
}

/// How many of the first rows must all fail for too few pins before the
/// reference frame, not the frames, is blamed.
const REFERENCE_PROBE_ROWS: usize = 5;

/// Fail fast on a reference that is no undeformed frame of the sensor that
/// took the frames (noise, another sensor, other blob parameters): when the
/// first few frames all match too few of its pins, the reference is named
/// before the whole set is read.
pub(crate) fn check_reference(
    extractor: &PinExtractor,
    reference: &Path,
    first_frames: &[PathBuf],
) -> Result<()> {
    let mut last = None;
    for path in first_frames.iter().take(REFERENCE_PROBE_ROWS) {
        let frame = read_frame(path)?;
        match extractor.extract(&frame) {
            Ok(_) => return Ok(()),
            Err(e @ tactrace_vision::VisionError::TooFewPins { .. }) => last = Some((path, e)),
            Err(e) => return Err(e.into()),
        }
    }
    match last {
        Some((path, e)) => Err(LabError::Reference {
            path: reference.to_path_buf(),
            reason: format!(
                "not an undeformed frame of the sensor that took the frames: it gives {} pins, \
                 and the first {} frames (up to {}) match too few of them; give the \
                 sensor's frame taken without contact as --reference, or blob parameters \
                 that suit both (--params)",
                extractor.tracker.reference().len(),
                first_frames.len().min(REFERENCE_PROBE_ROWS),
                path.display()
            ),
            source: Box::new(e),
        }),
        None => Ok(()),
    }
}

/// Import the frames of `collection` (its rows, its blob detector, pins
/// ordered by its reference frame). `progress` is called once per frame
/// processed.
pub fn import(collection: &LabelledCollection, progress: &(dyn Fn() + Sync)) -> Result<Imported> {
    import_rows(collection, None, progress)
}

/// As [`import`], only the label rows at `keep` (indices of the CSV's data
/// rows, in that order) when given.
pub(crate) fn import_rows(
    collection: &LabelledCollection,
    keep: Option<&[usize]>,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    let spec = collection.spec();
    let outputs = spec.model_targets();
    // The edge task's datasets keep their names (`r_mm (pose_2)`).
    let names = match spec.edge_names() {
        Ok(edge) => edge.to_vec(),
        Err(_) => TargetColumns::display(&outputs),
    };
    let rows = keep_rows(collection.read_rows(TapFields::NONE)?, keep);
    let frames = collection.frames();
    if let Some(err) = rows
        .first()
        .and_then(|r| crate::import_checks::frames_folder(frames, &r.image))
    {
        return Err(err);
    }
    let reference = collection.reference().path();
    let blob = collection.blob();
    let extractor = reference_extractor(reference, blob)?;
    let first: Vec<PathBuf> = rows
        .iter()
        .take(REFERENCE_PROBE_ROWS)
        .map(|r| frames.join(&r.image))
        .collect();
    check_reference(&extractor, reference, &first)?;
    let outcomes: Vec<FrameOutcome> = rows
        .par_iter()
        .map(|row| {
            let out = extract_one(&extractor, &frames.join(&row.image));
            progress();
            out.map_err(|e| e.to_string())
        })
        .collect();
    // An unreadable file is an error of the whole import: nothing is lost silently.
    let unreadable = rows.iter().zip(&outcomes).find_map(|(row, o)| match o {
        Err(reason) if !reason.contains("pins") => Some((row, reason)),
        _ => None,
    });
    if let Some((row, reason)) = unreadable {
        return Err(LabError::Format {
            path: frames.join(&row.image),
            reason: reason.clone(),
        });
    }
    let meta = DatasetMeta {
        source: "real".into(),
        origin: frames.display().to_string(),
        seed: None,
        samples: 0,
        pins: extractor.tracker.reference().len(),
        targets: names,
        target_columns: TargetColumns::of(&outputs),
        frames_with_missing_pins: 0,
        reference_pins: extractor.tracker.reference().to_vec(),
        settings: serde_json::json!({ "import": collection }),
        tactrace_version: crate::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
    };
    let mut got = gather(&rows, outcomes, meta, frames)?;
    let d = &got.data;
    got.warnings.extend(crate::import_checks::pressed_reference(
        reference,
        &d.meta.reference_pins,
        &d.inputs,
        d.len(),
    ));
    Ok(got)
}

/// The rows at `keep` (all when `None`; indices past the end are ignored).
pub(crate) fn keep_rows(rows: Vec<LabelledRow>, keep: Option<&[usize]>) -> Vec<LabelledRow> {
    let Some(keep) = keep else {
        return rows;
    };
    let mut slots: Vec<Option<LabelledRow>> = rows.into_iter().map(Some).collect();
    keep.iter()
        .filter_map(|&i| slots.get_mut(i).and_then(Option::take))
        .collect()
}

/// The rows' outcomes (in row order) gathered into the dataset `meta`
/// describes; the sample, missing-pin and rejected counts of `meta` are
/// filled in here. Rejected rows keep their image name and reason. An error
/// naming `origin` when no row gave a sample.
pub(crate) fn gather(
    rows: &[LabelledRow],
    outcomes: Vec<FrameOutcome>,
    mut meta: DatasetMeta,
    origin: &Path,
) -> Result<Imported> {
    let mut inputs = Vec::with_capacity(rows.len() * 2 * meta.pins);
    let mut targets = Vec::with_capacity(rows.len() * 2);
    let (mut missing, mut rejected) = (0, Vec::new());
    meta.images.clear();
    for (row, outcome) in rows.iter().zip(outcomes) {
        match outcome {
            Ok((disp, had_missing)) => {
                inputs.extend(disp);
                targets.extend_from_slice(&row.targets);
                meta.images.push(row.image.clone());
                missing += usize::from(had_missing);
            }
            Err(reason) => rejected.push((row.image.clone(), reason)),
        }
    }
    meta.samples = targets.len() / meta.targets.len().max(1);
    if meta.samples == 0 {
        return Err(LabError::Format {
            path: origin.to_path_buf(),
            reason: "no frame gave enough pins".into(),
        });
    }
    meta.frames_with_missing_pins = missing;
    if let Some(settings) = meta.settings.as_object_mut() {
        settings.insert("rejected".into(), rejected.len().into());
    }
    Ok(Imported {
        data: TapData {
            inputs,
            targets,
            meta,
        },
        frames_with_missing_pins: missing,
        rejected,
        warnings: Vec::new(),
        composition: None,
    })
}

/// The pin extractor whose order is that of the undeformed frame at `path`.
pub(crate) fn reference_extractor(path: &Path, blob: &BlobParams) -> Result<PinExtractor> {
    let reference = read_frame(path)?;
    PinExtractor::from_reference_frame(&reference, blob.clone()).map_err(|e| LabError::Format {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

fn extract_one(extractor: &PinExtractor, path: &Path) -> Result<(Vec<f32>, bool)> {
    let frame = read_frame(path)?;
    let tracked = extractor.extract(&frame)?;
    Ok((
        tracked.displacement(extractor.tracker.reference()),
        tracked.missing > 0,
    ))
}
