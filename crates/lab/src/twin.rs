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
    gather, read_rows, reference_extractor, target_names, FrameOutcome, Imported, LabelColumns, Row,
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use tactrace_sensor::{EdgeTap, Shear, TacTipConfig, TacTipModel};
use tactrace_store::DatasetMeta;
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
    let mut extra: Vec<&str> = cfg.dz_column.iter().map(String::as_str).collect();
    extra.extend(cfg.shear_columns.iter().flatten().map(String::as_str));
    let cols = LabelColumns {
        image: &cfg.image_column,
        r: &cfg.r_column,
        theta: &cfg.theta_column,
        extra: &extra,
    };
    let rows = read_rows(&cfg.targets, &cols, cfg.limit)?;
    let extractor = reference_extractor(&cfg.reference, blob)?;
    let rest = extractor.tracker.reference().to_vec();
    let model = TacTipModel::with_rest_pins(sensor.clone(), rest.clone()).map_err(|e| {
        LabError::Reference {
            path: cfg.reference.clone(),
            reason: "not an undeformed frame of the simulated sensor's layout; give the \
                     sensor's frame taken without contact as --reference, or blob parameters \
                     that find its pins (--params)"
                .into(),
            source: Box::new(e),
        }
    })?;
    let outcomes: Vec<FrameOutcome> = rows
        .par_iter()
        .enumerate()
        .map(|(k, row)| {
            let out = simulate_row(&model, &extractor, cfg, row, k as u64);
            progress();
            out
        })
        .collect();
    let meta = DatasetMeta {
        source: "simulated twin".into(),
        origin: cfg.targets.display().to_string(),
        seed: Some(cfg.seed),
        samples: 0,
        pins: rest.len(),
        targets: target_names(&cfg.r_column, &cfg.theta_column),
        frames_with_missing_pins: 0,
        reference_pins: rest,
        settings: serde_json::json!({ "twin": cfg, "sensor": sensor, "blob": blob }),
        tactrace_version: crate::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
    };
    gather(&rows, outcomes, meta, &cfg.targets)
}

/// The labelled tap of one row (extra values: dz, then the shear columns).
fn edge_tap(cfg: &TwinConfig, row: &Row) -> EdgeTap {
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
    k: u64,
) -> FrameOutcome {
    let pins = model.edge_tap_pins(&edge_tap(cfg, row));
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    rng.set_stream(k);
    let frame = model.render(&pins, Some(&mut rng));
    let tracked = extractor.extract(&frame).map_err(|e| e.to_string())?;
    Ok((
        tracked.displacement(extractor.tracker.reference()),
        tracked.missing > 0,
    ))
}
