//! A simulated twin of a real labelled data set: every real tap's labels
//! (edge position, angle and, when given, vertical offset and shear) are
//! replayed on the simulated TacTip over a straight edge (the labels mapped
//! onto the model by its calibration, docs/sensor-model.md), and the
//! rendered frames go through the same detection and ordering as the real
//! ones, against the real reference frame. Twin and real set then share
//! labels, pin order and rest layout, so a model trained on one can be
//! validated on the other: the simulator judged by what it predicts about
//! real frames (docs/results.md, "Simulated to real").
use crate::error::{LabError, Result};
use crate::import::{
    gather, keep_rows, read_rows, reference_extractor, target_names, FrameOutcome, Imported,
    LabelColumns, Row, TwinComposition,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use tactrace_calib::real_tap_repeats;
use tactrace_sensor::{EdgeTap, Shear, TacTipConfig, TacTipModel};
use tactrace_store::{pin_order_mismatch, DatasetMeta, SensorFolder, StoreError, TapData};
use tactrace_vision::{BlobParams, PinExtractor};

/// Which labels to replay, and the seed of the rendering noise.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TwinConfig {
    /// CSV of labels, one row per real frame.
    pub targets: PathBuf,
    /// The real undeformed frame: its pins are the twin's rest layout and
    /// define the pin order.
    pub reference: PathBuf,
    pub image_column: String,
    pub r_column: String,
    pub theta_column: String,
    /// Vertical offset of the tap, mm (`None`: every tap at the nominal depth).
    pub dz_column: Option<String>,
    /// Shear perturbation columns: x and y (mm, work frame) and rotation
    /// (deg) (`None`: taps without shear).
    pub shear_columns: Option<[String; 3]>,
    /// Replay at most this many rows (all when `None`).
    pub limit: Option<usize>,
    /// Seed of the pin jitter and image noise (row `k` draws from stream `k`).
    pub seed: u64,
}

impl TwinConfig {
    /// The Bristol edge set's layout in `dir` (targets.csv, frames/init_0.png;
    /// r = pose_2, theta = pose_6, offset pose_3, shear move_1, move_2, move_6).
    pub fn bristol(dir: &Path, seed: u64) -> Self {
        TwinConfig {
            targets: dir.join("targets.csv"),
            reference: dir.join("frames/init_0.png"),
            image_column: "image_name".into(),
            r_column: "pose_2".into(),
            theta_column: "pose_6".into(),
            dz_column: Some("pose_3".into()),
            shear_columns: Some(["move_1".into(), "move_2".into(), "move_6".into()]),
            limit: None,
            seed,
        }
    }

    /// How to import the real frames of these labels from `frames` (the
    /// same labels file, reference, columns and row limit).
    pub fn import_config(&self, frames: PathBuf) -> crate::import::ImportConfig {
        crate::import::ImportConfig {
            frames,
            targets: self.targets.clone(),
            reference: self.reference.clone(),
            image_column: self.image_column.clone(),
            r_column: self.r_column.clone(),
            theta_column: self.theta_column.clone(),
            limit: self.limit,
        }
    }

    /// The same columns with another labels file and reference frame.
    pub fn with_paths(self, targets: PathBuf, reference: PathBuf) -> Self {
        TwinConfig {
            targets,
            reference,
            ..self
        }
    }
}

/// Simulate every labelled row of `cfg.targets` with the sensor `sensor`;
/// `progress` is called once per frame.
pub fn simulate_twin(
    cfg: &TwinConfig,
    sensor: &TacTipConfig,
    blob: &BlobParams,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    simulate_twin_rows(cfg, sensor, blob, None, progress)
}

/// As [`simulate_twin`], only the label rows at `keep` when given.
pub(crate) fn simulate_twin_rows(
    cfg: &TwinConfig,
    sensor: &TacTipConfig,
    blob: &BlobParams,
    keep: Option<&[usize]>,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    let rows = keep_rows(twin_rows(cfg)?, keep);
    let extractor = reference_extractor(&cfg.reference, blob)?;
    let rest = extractor.tracker.reference().to_vec();
    let model = twin_model(cfg, sensor, &rest)?;
    let outcomes = simulate_rows(&model, &extractor, cfg, &rows, cfg.seed, progress);
    let settings = serde_json::json!({ "twin": cfg, "sensor": sensor, "blob": blob });
    gather(
        &rows,
        outcomes,
        twin_meta(cfg, rest, settings),
        &cfg.targets,
    )
}

/// As [`simulate_twin`] with a calibrated sensor (`tactrace calibrate`):
/// its parameters, its field correction and its training recipe (several
/// renders of every row, seeds `cfg.seed`, `cfg.seed + 1`, ..., and the
/// real calibration taps repeated to about a third of the set, unless
/// `real_taps` is false). The reference frame must list its pins like the
/// sensor's.
pub fn simulate_twin_calibrated(
    cfg: &TwinConfig,
    sensor: &SensorFolder,
    real_taps: bool,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    let spec = &sensor.spec;
    let rows = twin_rows(cfg)?;
    let extractor = reference_extractor(&cfg.reference, &spec.blob)?;
    let rest = extractor.tracker.reference().to_vec();
    if let Some(source) = pin_order_mismatch(&spec.reference_pins, &rest) {
        return Err(StoreError::PinOrder {
            path: cfg.reference.clone(),
            source,
        }
        .into());
    }
    let model =
        twin_model(cfg, &spec.sensor, &rest)?.with_correction(sensor.field_correction()?)?;
    let renders = spec.training.renders.max(1);
    let repeats = if real_taps && spec.training.add_real_taps {
        real_tap_repeats(rows.len(), sensor.real_labels.len())
    } else {
        0
    };
    let settings = serde_json::json!({
        "twin": cfg, "sensor": sensor.source, "recipe": spec.training,
        "renders": renders, "real_tap_repeats": repeats,
    });
    let mut all = Vec::new();
    for r in 0..renders as u64 {
        let outcomes = simulate_rows(&model, &extractor, cfg, &rows, cfg.seed + r, progress);
        let meta = twin_meta(cfg, rest.clone(), settings.clone());
        all.push(gather(&rows, outcomes, meta, &cfg.targets)?);
    }
    let mut out = concatenate(all);
    out.data.meta.source = "simulated twin (calibrated sensor)".into();
    for k in 0..repeats {
        append_real_taps(&mut out.data, sensor, k);
    }
    out.data.meta.samples = out.data.targets.len() / 2;
    out.composition = Some(TwinComposition {
        rows: rows.len(),
        renders,
        real_taps: sensor.real_labels.len(),
        real_tap_repeats: repeats,
    });
    Ok(out)
}

/// The simulated sensor `sensor` with the reference frame's pins `rest` as
/// its rest layout; a reference that does not fit the layout is named.
fn twin_model(cfg: &TwinConfig, sensor: &TacTipConfig, rest: &[[f64; 2]]) -> Result<TacTipModel> {
    TacTipModel::with_rest_pins(sensor.clone(), rest.to_vec()).map_err(|e| LabError::Reference {
        path: cfg.reference.clone(),
        reason: "not an undeformed frame of the simulated sensor's layout; give the \
                 sensor's frame taken without contact as --reference, or blob parameters \
                 that find its pins (--params)"
            .into(),
        source: Box::new(e),
    })
}

/// The labelled rows of `cfg.targets` with their depth and shear columns.
pub(crate) fn twin_rows(cfg: &TwinConfig) -> Result<Vec<Row>> {
    let mut extra: Vec<&str> = cfg.dz_column.iter().map(String::as_str).collect();
    extra.extend(cfg.shear_columns.iter().flatten().map(String::as_str));
    let cols = LabelColumns {
        image: &cfg.image_column,
        r: &cfg.r_column,
        theta: &cfg.theta_column,
        extra: &extra,
    };
    read_rows(&cfg.targets, &cols, cfg.limit)
}

fn twin_meta(cfg: &TwinConfig, rest: Vec<[f64; 2]>, settings: serde_json::Value) -> DatasetMeta {
    DatasetMeta {
        source: "simulated twin".into(),
        origin: cfg.targets.display().to_string(),
        seed: Some(cfg.seed),
        samples: 0,
        pins: rest.len(),
        targets: target_names(&cfg.r_column, &cfg.theta_column),
        frames_with_missing_pins: 0,
        reference_pins: rest,
        settings,
        tactrace_version: crate::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
    }
}

/// Render, detect and order every row with the rendering seed `seed`
/// (row `k` of the labels file draws from stream `k`, whichever rows are
/// simulated).
fn simulate_rows(
    model: &TacTipModel,
    extractor: &PinExtractor,
    cfg: &TwinConfig,
    rows: &[Row],
    seed: u64,
    progress: &(dyn Fn() + Sync),
) -> Vec<FrameOutcome> {
    rows.par_iter()
        .map(|row| {
            let out = simulate_row(model, extractor, cfg, row, (seed, row.index as u64));
            progress();
            out
        })
        .collect()
}

/// The imports of several renders as one set (rows in render order).
fn concatenate(parts: Vec<Imported>) -> Imported {
    let mut parts = parts.into_iter();
    let mut first = parts.next().expect("at least one render");
    for p in parts {
        first.data.inputs.extend(p.data.inputs);
        first.data.targets.extend(p.data.targets);
        first.data.meta.images.extend(p.data.meta.images);
        first.data.meta.frames_with_missing_pins += p.data.meta.frames_with_missing_pins;
        first.frames_with_missing_pins += p.frames_with_missing_pins;
        first.rejected.extend(p.rejected);
    }
    first
}

/// The sensor's real calibration taps, once more (round `k`).
fn append_real_taps(data: &mut TapData, sensor: &SensorFolder, k: usize) {
    data.inputs.extend_from_slice(&sensor.real_fields);
    for (i, l) in sensor.real_labels.iter().enumerate() {
        data.targets.extend(l);
        data.meta.images.push(format!("calibration-tap-{i}#{k}"));
    }
}

/// The labelled tap of one row (extra values: dz, then the shear columns).
pub(crate) fn edge_tap(cfg: &TwinConfig, row: &Row) -> EdgeTap {
    let mut extra = row.extra.iter().map(|&v| v as f64);
    let dz_mm = if cfg.dz_column.is_some() {
        extra.next().unwrap_or(0.0)
    } else {
        0.0
    };
    let shear = cfg.shear_columns.as_ref().map(|_| Shear {
        dx_mm: extra.next().unwrap_or(0.0),
        dy_mm: extra.next().unwrap_or(0.0),
        drz_deg: extra.next().unwrap_or(0.0),
    });
    EdgeTap {
        r_mm: row.r as f64,
        theta_deg: row.theta as f64,
        dz_mm,
        shear,
    }
}

/// Render, detect and order one row's tap: its displacement vector and
/// whether pins were missing, or why the frame was rejected.
fn simulate_row(
    model: &TacTipModel,
    extractor: &PinExtractor,
    cfg: &TwinConfig,
    row: &Row,
    (seed, k): (u64, u64),
) -> FrameOutcome {
    let pins = model.seen_pins(model.edge_tap_pins(&edge_tap(cfg, row)));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(k);
    let frame = model.render(&pins, Some(&mut rng));
    let tracked = extractor.extract(&frame).map_err(|e| e.to_string())?;
    Ok((
        tracked.displacement(extractor.tracker.reference()),
        tracked.missing > 0,
    ))
}
