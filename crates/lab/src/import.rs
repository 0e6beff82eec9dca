//! Import real TacTip frames (Bristol layout) into the dataset format,
//! through the same pin extraction as simulated taps.
use crate::error::{LabError, Result};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use tactrace_sensor::read_frame;
use tactrace_store::{DatasetMeta, TapData};
use tactrace_vision::{BlobParams, PinExtractor};

/// One frame's displacement and whether pins were missing, or why it was
/// rejected.
pub(crate) type FrameOutcome = std::result::Result<(Vec<f32>, bool), String>;

/// Where the real frames and their labels are.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ImportConfig {
    pub frames: PathBuf,
    pub targets: PathBuf,
    pub reference: PathBuf,
    pub image_column: String,
    pub r_column: String,
    pub theta_column: String,
    /// Import at most this many rows (all when `None`).
    pub limit: Option<usize>,
}

impl ImportConfig {
    /// The Bristol edge set's layout in `dir` (frames/, targets.csv,
    /// frames/init_0.png; r = pose_2, theta = pose_6), every row.
    pub fn bristol(dir: &Path) -> Self {
        ImportConfig {
            frames: dir.join("frames"),
            targets: dir.join("targets.csv"),
            reference: dir.join("frames/init_0.png"),
            image_column: "image_name".into(),
            r_column: "pose_2".into(),
            theta_column: "pose_6".into(),
            limit: None,
        }
    }
}

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

/// One labelled row of the targets CSV.
pub(crate) struct Row {
    /// Index among the CSV's data rows (0 = the first after the header).
    pub index: usize,
    pub image: String,
    pub r: f32,
    pub theta: f32,
    /// The values of the `extra` columns asked of [`read_rows`], in order.
    pub extra: Vec<f32>,
}

/// The label columns of a targets CSV, by header name.
pub(crate) struct LabelColumns<'a> {
    pub image: &'a str,
    pub r: &'a str,
    pub theta: &'a str,
    /// Further numeric columns, returned in [`Row::extra`].
    pub extra: &'a [&'a str],
}

impl<'a> LabelColumns<'a> {
    pub fn of(cfg: &'a ImportConfig) -> Self {
        LabelColumns {
            image: &cfg.image_column,
            r: &cfg.r_column,
            theta: &cfg.theta_column,
            extra: &[],
        }
    }
}

/// Read the labels of the first `limit` rows (all when `None`).
pub(crate) fn read_rows(
    path: &Path,
    cols: &LabelColumns,
    limit: Option<usize>,
) -> Result<Vec<Row>> {
    let path = &path.to_path_buf();
    let fmt = |reason: String| LabError::Format {
        path: path.clone(),
        reason,
    };
    // A regular file only: a FIFO would block the import for ever.
    let (file, _) = tactrace_store::open_regular(path)?;
    let mut rdr = csv::Reader::from_reader(std::io::BufReader::new(file));
    let headers = rdr.headers().map_err(|e| fmt(e.to_string()))?.clone();
    let names: Vec<&str> = [cols.image, cols.r, cols.theta]
        .into_iter()
        .chain(cols.extra.iter().copied())
        .collect();
    let at = crate::labels::column_indices(&headers, &names).map_err(fmt)?;
    let (ci, cr, ct) = (at[0], at[1], at[2]);
    let extra_cols = &at[3..];
    let mut rows = Vec::new();
    for (k, rec) in rdr.records().enumerate() {
        let rec = rec.map_err(|e| fmt(e.to_string()))?;
        let num = |c: usize| -> Result<f32> {
            let v: f32 = rec.get(c).unwrap_or("").trim().parse().map_err(|_| {
                fmt(format!(
                    "row {}: `{}` is not a number",
                    k + 2,
                    rec.get(c).unwrap_or("")
                ))
            })?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(fmt(format!("row {}: non-finite value", k + 2)))
            }
        };
        rows.push(Row {
            index: k,
            image: rec.get(ci).unwrap_or("").trim().to_string(),
            r: num(cr)?,
            theta: num(ct)?,
            extra: extra_cols.iter().map(|&c| num(c)).collect::<Result<_>>()?,
        });
        if limit.is_some_and(|l| rows.len() >= l) {
            break;
        }
    }
    if rows.is_empty() {
        return Err(fmt("no data rows".into()));
    }
    Ok(rows)
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

/// Import real frames. `progress` is called once per frame processed.
pub fn import(
    cfg: &ImportConfig,
    blob: &BlobParams,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    import_rows(cfg, blob, None, progress)
}

/// As [`import`], only the label rows at `keep` (indices of the CSV's data
/// rows, in that order) when given.
pub(crate) fn import_rows(
    cfg: &ImportConfig,
    blob: &BlobParams,
    keep: Option<&[usize]>,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    let rows = keep_rows(
        read_rows(&cfg.targets, &LabelColumns::of(cfg), cfg.limit)?,
        keep,
    );
    if let Some(err) = rows
        .first()
        .and_then(|r| crate::import_checks::frames_folder(&cfg.frames, &r.image))
    {
        return Err(err);
    }
    let extractor = reference_extractor(&cfg.reference, blob)?;
    let first: Vec<PathBuf> = rows
        .iter()
        .take(REFERENCE_PROBE_ROWS)
        .map(|r| cfg.frames.join(&r.image))
        .collect();
    check_reference(&extractor, &cfg.reference, &first)?;
    let outcomes: Vec<FrameOutcome> = rows
        .par_iter()
        .map(|row| {
            let out = extract_one(&extractor, &cfg.frames.join(&row.image));
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
            path: cfg.frames.join(&row.image),
            reason: reason.clone(),
        });
    }
    let meta = DatasetMeta {
        source: "real".into(),
        origin: cfg.frames.display().to_string(),
        seed: None,
        samples: 0,
        pins: extractor.tracker.reference().len(),
        targets: target_names(&cfg.r_column, &cfg.theta_column),
        frames_with_missing_pins: 0,
        reference_pins: extractor.tracker.reference().to_vec(),
        settings: serde_json::json!({ "import": cfg, "blob": blob }),
        tactrace_version: crate::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
    };
    let mut got = gather(&rows, outcomes, meta, &cfg.frames)?;
    let d = &got.data;
    got.warnings.extend(crate::import_checks::pressed_reference(
        &cfg.reference,
        &d.meta.reference_pins,
        &d.inputs,
        d.len(),
    ));
    Ok(got)
}

/// The rows at `keep` (all when `None`; indices past the end are ignored).
pub(crate) fn keep_rows(rows: Vec<Row>, keep: Option<&[usize]>) -> Vec<Row> {
    let Some(keep) = keep else {
        return rows;
    };
    let mut slots: Vec<Option<Row>> = rows.into_iter().map(Some).collect();
    keep.iter()
        .filter_map(|&i| slots.get_mut(i).and_then(Option::take))
        .collect()
}

/// The dataset's target descriptions for the label columns used.
pub(crate) fn target_names(r_column: &str, theta_column: &str) -> [String; 2] {
    [
        format!("r_mm ({r_column})"),
        format!("theta_deg ({theta_column})"),
    ]
}

/// The rows' outcomes (in row order) gathered into the dataset `meta`
/// describes; the sample, missing-pin and rejected counts of `meta` are
/// filled in here. Rejected rows keep their image name and reason. An error
/// naming `origin` when no row gave a sample.
pub(crate) fn gather(
    rows: &[Row],
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
                targets.extend([row.r, row.theta]);
                meta.images.push(row.image.clone());
                missing += usize::from(had_missing);
            }
            Err(reason) => rejected.push((row.image.clone(), reason)),
        }
    }
    meta.samples = targets.len() / 2;
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
