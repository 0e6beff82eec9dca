//! Import a labelled collection of real TacTip frames
//! ([`LabelledCollection`]) into the dataset format, through the same pin
//! extraction as simulated taps.
use crate::error::{LabError, Result};
use crate::import_reader::{self, FrameRead, SmallFrame};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use tactrace_servo::ImageInput;
use tactrace_store::collection::{EstimatedRest, Reference};
use tactrace_store::{
    DatasetMeta, FramesInfo, ImageFrames, LabelledCollection, LabelledRow, TapData, TapFields,
    TargetColumns, TrackTotals,
};
use tactrace_vision::{BlobParams, PinReader, SightParams, TrackCounts, VisionError};

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
    /// The rest layout this import estimated from the taps (no
    /// `--reference`), with its residual.
    pub estimated_rest: Option<EstimatedRest>,
    /// Every kept row's frame as a small image (`import --frames-size`).
    pub images: Option<ImageFrames>,
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
fn check_reference(reader: &PinReader, reference: &Path, first_frames: &[PathBuf]) -> Result<()> {
    let mut last = None;
    for path in first_frames.iter().take(REFERENCE_PROBE_ROWS) {
        match import_reader::read_one(reader, path) {
            Ok(_) => return Ok(()),
            Err(LabError::Vision(e @ VisionError::TooFewPins { .. })) => last = Some((path, e)),
            Err(e) => return Err(e),
        }
    }
    match last {
        Some((path, e)) => Err(LabError::Reference {
            path: reference.to_path_buf(),
            reason: format!(
                "not an undeformed frame of the sensor that took the frames: it gives {} pins, \
                 and the first {} frames (up to {}) match too few of them; give the \
                 sensor's frame taken without contact as --reference, or blob parameters \
                 that suit both (--params) or a sensor file (--sensor)",
                reader.tracker().reference().len(),
                first_frames.len().min(REFERENCE_PROBE_ROWS),
                path.display()
            ),
            source: Box::new(e),
        }),
        None => Ok(()),
    }
}

/// Import the frames of `collection` (its rows, read by its sensor
/// settings or blob detector, pins ordered by its reference: an undeformed
/// frame, or a rest layout estimated from the taps). `progress` is called
/// once per frame processed.
pub fn import(collection: &LabelledCollection, progress: &(dyn Fn() + Sync)) -> Result<Imported> {
    import_rows(collection, None, progress)
}

/// [`import`], keeping every kept row's frame as the detector saw it,
/// area-averaged to `frames_size x frames_size` px, when `frames_size` is
/// given ([`Imported::images`], the dataset's `frames.npy`).
pub fn import_with_frames(
    collection: &LabelledCollection,
    frames_size: Option<usize>,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    import_rows_with(collection, None, frames_size, progress)
}

/// As [`import`], only the label rows at `keep` (indices of the CSV's data
/// rows, in that order) when given.
pub(crate) fn import_rows(
    collection: &LabelledCollection,
    keep: Option<&[usize]>,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    import_rows_with(collection, keep, None, progress)
}

/// [`import_rows`], with the frames as images when `frames_size` is given.
fn import_rows_with(
    collection: &LabelledCollection,
    keep: Option<&[usize]>,
    frames_size: Option<usize>,
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
    let paths: Vec<PathBuf> = rows.iter().map(|r| frames.join(&r.image)).collect();
    let opened = import_reader::open(collection, &paths)?;
    let reader = &opened.reader;
    let input = frames_size
        .map(|s| import_reader::image_input_of(reader, s))
        .transpose()?;
    if let Some(reference) = opened.reference.frame() {
        check_reference(
            reader,
            reference,
            &paths[..paths.len().min(REFERENCE_PROBE_ROWS)],
        )?;
    }
    let read: Vec<Result<FrameRead>> = paths
        .par_iter()
        .map(|path| {
            let out = import_reader::read_one_with_image(reader, path, input.as_ref());
            progress();
            out
        })
        .collect();
    // An unreadable file is an error of the whole import: nothing is lost silently.
    let mut outcomes: Vec<FrameOutcome> = Vec::with_capacity(read.len());
    let mut counts = Vec::with_capacity(read.len());
    let mut small = Vec::new();
    for (path, r) in paths.iter().zip(read) {
        match r {
            Ok((disp, c, frame)) => {
                outcomes.push(Ok((disp, !c.fully_tracked())));
                counts.push(c);
                small.extend(frame);
            }
            Err(e) if import_reader::too_few_pins(&e) => outcomes.push(Err(e.to_string())),
            Err(e) => {
                return Err(LabError::Format {
                    path: path.clone(),
                    reason: e.to_string(),
                })
            }
        }
    }
    let resolved = collection.clone().with_reference(opened.reference.clone());
    let meta = DatasetMeta {
        source: "real".into(),
        origin: frames.display().to_string(),
        seed: None,
        samples: 0,
        pins: reader.tracker().reference().len(),
        targets: names,
        target_columns: TargetColumns::of(&outputs),
        frames_with_missing_pins: 0,
        reference_pins: reader.tracker().reference().to_vec(),
        settings: serde_json::json!({ "import": resolved }),
        tactrace_version: crate::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
        tracking: TrackTotals::default(),
    };
    let mut got = gather(&rows, outcomes, meta, frames)?;
    got.data.meta.tracking = totals(paths.len(), &counts);
    got.estimated_rest = opened.estimated;
    got.images = input.and_then(|i| images_of(&i, small));
    let d = &got.data;
    got.warnings
        .extend(crate::import_checks::constant_targets(d));
    got.warnings
        .extend(crate::import_checks::wrapping_angles(d));
    got.warnings
        .extend(crate::import_checks::still_pins_warning(d));
    if let Some(reference) = opened.reference.frame() {
        got.warnings.extend(crate::import_checks::pressed_reference(
            reference,
            &d.meta.reference_pins,
            &d.inputs,
            d.len(),
        ));
    }
    Ok(got)
}

/// The kept rows' small frames as one stack (`None` when there is none).
/// They record `input`'s preprocessing, so image models trained on them
/// are fed frames made the same way.
pub(crate) fn images_of(input: &ImageInput, small: Vec<SmallFrame>) -> Option<ImageFrames> {
    let source = small.first()?.1;
    let pixels = small.into_iter().flat_map(|(p, _)| p).collect();
    let (h, w) = input.size();
    Some(ImageFrames {
        info: FramesInfo::new(h, w, source).with_preprocess(input.preprocess()),
        pixels,
    })
}

/// The tracking totals of `total` frames read, `counts` those of the frames
/// kept.
fn totals(total: usize, counts: &[TrackCounts]) -> TrackTotals {
    let sum = |f: fn(&TrackCounts) -> usize| Some(counts.iter().map(f).sum());
    TrackTotals {
        frames_total: total,
        frames_fully_tracked: counts.iter().filter(|c| c.fully_tracked()).count(),
        pins_matched: sum(|c| c.matched),
        pins_split: sum(|c| c.split),
        pins_filled: sum(|c| c.filled),
    }
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
    meta.tracking = TrackTotals::frames(rows.len(), missing + rejected.len());
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
        estimated_rest: None,
        images: None,
    })
}

/// The rest layout (and the sensor settings, when it had some) of a
/// dataset imported earlier, so that another split of the same sensor is
/// read against the same pins: `import --reference DATASET`.
pub fn recorded_reference(dir: &Path) -> Result<(EstimatedRest, Option<SightParams>)> {
    let r = recorded(dir)?;
    Ok((r.rest, r.sight))
}

/// What a dataset imported earlier records of how its frames were read
/// (`--reference DATASET` of `import`, `twin`, `calibrate`, `sim-fit`).
pub struct RecordedReference {
    /// Its rest pins (estimated from taps, or an undeformed frame's).
    pub rest: EstimatedRest,
    /// The sensor settings it was read with, when any.
    pub sight: Option<SightParams>,
    /// The blob detector it was read with.
    pub blob: Option<BlobParams>,
    /// The folder of its frames.
    pub frames: Option<PathBuf>,
}

/// The reading of the dataset `dir` (see [`RecordedReference`]).
pub fn recorded(dir: &Path) -> Result<RecordedReference> {
    let data = tactrace_store::read_dataset(dir)?;
    let meta = data.meta;
    let recorded: Option<LabelledCollection> = meta
        .settings
        .get("import")
        .and_then(|c| serde_json::from_value(c.clone()).ok());
    let sight = recorded.as_ref().and_then(|c| c.sight().cloned());
    let rest = match recorded.as_ref().map(LabelledCollection::reference) {
        Some(Reference::Estimated(e)) if e.pins == meta.reference_pins => e.clone(),
        _ => EstimatedRest {
            pins: meta.reference_pins,
            residual_px: 0.0,
            frames: 0,
        },
    };
    if rest.pins.len() < 3 {
        return Err(LabError::Format {
            path: dir.to_path_buf(),
            reason: "the dataset records no reference pins to read other frames against".into(),
        });
    }
    Ok(RecordedReference {
        rest,
        sight,
        blob: recorded.as_ref().map(|c| c.blob().clone()),
        frames: recorded.as_ref().map(|c| c.frames().to_path_buf()),
    })
}
