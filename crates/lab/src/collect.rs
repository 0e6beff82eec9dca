//! Data collection on an edge, report ch. 4.1.
//!
//! 1. Align the sensor centre with the edge.
//! 2. Set r uniformly at random in [-r_range, r_range] mm along the outward
//!    edge normal and theta on a sweep from -theta_range to +theta_range deg
//!    over the run.
//! 3. Tap and capture.
//! 4. Extract the pins and their displacement from the undeformed frame.
use crate::error::{LabError, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tactrace_arm::Arm;
use tactrace_geometry::{Contour, Vec2};
use tactrace_sensor::{EdgeLabels, Frame, LabelConvention, TactileSensor};
use tactrace_servo::{pose_at_edge, tap, RigConfig, SimRig, TapConfig};
use tactrace_store::frame_file::png_bytes;
use tactrace_store::{DatasetMeta, SensorFolder, TapData};

/// Rows whose buffers are reserved up front; more grow as they come.
const PRESIZED_ROWS: usize = 1 << 16;
use tactrace_vision::{BlobParams, PinExtractor};

/// What to collect.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CollectConfig {
    pub samples: usize,
    pub seed: u64,
    /// Edge positions are uniform in [-r_range_mm, r_range_mm].
    pub r_range_mm: f64,
    /// Angles sweep from -theta_range_deg to +theta_range_deg.
    pub theta_range_deg: f64,
    /// Arc length of the edge point the sensor is aligned with, mm.
    pub edge_arc_mm: f64,
    /// Keep the PNG of every tap.
    pub save_frames: bool,
}

impl Default for CollectConfig {
    fn default() -> Self {
        Self {
            samples: 1000,
            seed: 1,
            r_range_mm: 5.0,
            theta_range_deg: 45.0,
            edge_arc_mm: 0.0,
            save_frames: false,
        }
    }
}

/// One collected sample: the target and (optionally) the frame.
pub struct Collected {
    pub data: TapData,
    /// (file name, PNG bytes) when `save_frames`.
    pub frames: Vec<(String, Vec<u8>)>,
}

/// Run the collection over `shape` with the simulated rig.
pub fn collect(
    rig_cfg: &RigConfig,
    shape: &Contour,
    cfg: &CollectConfig,
    origin: &str,
    progress: impl FnMut(usize),
) -> Result<Collected> {
    let (edge, normal) = shape.at_arc_length(cfg.edge_arc_mm);
    let start = pose_at_edge(
        edge,
        normal,
        0.0,
        -cfg.theta_range_deg,
        rig_cfg.tap.height_mm,
    );
    let mut rig = SimRig::new(rig_cfg, shape.clone(), start, cfg.seed)?;
    let reference = rig.reference_frame();
    let (arm, sensor) = rig.parts();
    let on = EdgeRig {
        arm,
        sensor,
        reference: &reference,
        blob: &rig_cfg.blob,
        tap: &rig_cfg.tap,
        edge,
        normal,
        labels: None,
    };
    let settings = serde_json::json!({ "rig": rig_cfg, "collect": cfg });
    collect_on(on, cfg, "simulated", origin, settings, progress)
}

/// As [`collect`] with a calibrated sensor (`--sensor`): its taps, pins
/// ordered by its real reference frame, labels drawn in its own convention
/// (r in +-`r_range_mm`, theta swept over +-`theta_range_deg` of its
/// labels) and placed at their loop pose (eq. L1), so the set looks like
/// the sensor's real collection. `rig_cfg.sensor` is not used.
pub fn collect_calibrated(
    rig_cfg: &RigConfig,
    sensor: &SensorFolder,
    shape: &Contour,
    cfg: &CollectConfig,
    origin: &str,
    progress: impl FnMut(usize),
) -> Result<Collected> {
    let (edge, normal) = shape.at_arc_length(cfg.edge_arc_mm);
    let spec = &sensor.spec;
    let convention = sensor.label_convention();
    let first = convention.to_pose(EdgeLabels {
        theta_deg: -cfg.theta_range_deg,
        ..EdgeLabels::default()
    });
    let start = pose_at_edge(
        edge,
        normal,
        first.r_mm,
        first.theta_deg,
        rig_cfg.tap.height_mm,
    );
    let mount = convention.mount_yaw_deg;
    let model = sensor.model()?;
    rig_cfg.validate()?;
    let mut rig = SimRig::with_model(rig_cfg, model, mount, shape.clone(), start, cfg.seed);
    let (arm, sensor_part) = rig.parts();
    let names = [
        format!("r_mm ({})", spec.labels.r),
        format!("theta_deg ({})", spec.labels.theta),
    ];
    let on = EdgeRig {
        arm,
        sensor: sensor_part,
        reference: &sensor.reference,
        blob: &spec.blob,
        tap: &rig_cfg.tap,
        edge,
        normal,
        labels: Some((convention, names)),
    };
    let settings = serde_json::json!({
        "rig": rig_cfg, "collect": cfg, "calibrated_sensor": sensor.source,
    });
    collect_on(
        on,
        cfg,
        "simulated (calibrated sensor)",
        origin,
        settings,
        progress,
    )
}

/// `--samples` must be positive.
pub fn check_samples(cfg: &CollectConfig) -> Result<()> {
    if cfg.samples == 0 {
        return Err(LabError::Config("--samples must be at least 1".into()));
    }
    let ranges_ok = cfg.r_range_mm.is_finite()
        && cfg.r_range_mm >= 0.0
        && cfg.theta_range_deg.is_finite()
        && cfg.theta_range_deg >= 0.0
        && cfg.edge_arc_mm.is_finite();
    if !ranges_ok {
        return Err(LabError::Config(
            "r_range_mm and theta_range_deg must be finite and >= 0, edge_arc_mm finite".into(),
        ));
    }
    Ok(())
}

/// An arm and sensor (simulated or real) at an edge: the undeformed
/// reference frame, the blob settings, the tap and the edge point with its
/// outward normal in the work frame.
pub struct EdgeRig<'a> {
    pub arm: &'a mut dyn Arm,
    pub sensor: &'a mut dyn TactileSensor,
    pub reference: &'a Frame,
    pub blob: &'a BlobParams,
    pub tap: &'a TapConfig,
    pub edge: Vec2,
    pub normal: Vec2,
    /// A sensor's label convention and its target names: labels are drawn
    /// in it and placed at their loop pose (eq. L1). `None`: the labels
    /// are the loop's edge pose.
    pub labels: Option<(LabelConvention, [String; 2])>,
}

/// The collection of report ch. 4.1 on any rig: the labels are the poses
/// commanded relative to the edge; `source` and `settings` go into the
/// dataset's metadata.
pub fn collect_on(
    on: EdgeRig,
    cfg: &CollectConfig,
    source: &str,
    origin: &str,
    settings: serde_json::Value,
    mut progress: impl FnMut(usize),
) -> Result<Collected> {
    check_samples(cfg)?;
    let EdgeRig {
        arm,
        sensor,
        reference,
        blob,
        tap: tap_cfg,
        edge,
        normal,
        labels,
    } = on;
    let extractor = PinExtractor::from_reference_frame(reference, blob.clone())?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let dim = 2 * extractor.tracker.reference().len();
    // Reserved for at most PRESIZED_ROWS: a huge --samples grows the
    // buffers as taps come instead of aborting on one giant allocation.
    let rows = cfg.samples.min(PRESIZED_ROWS);
    let mut inputs = Vec::with_capacity(rows * dim);
    let mut targets = Vec::with_capacity(rows * 2);
    let mut frames = Vec::new();
    let mut with_missing = 0;
    for i in 0..cfg.samples {
        let r = rng.random_range(-cfg.r_range_mm..=cfg.r_range_mm);
        let theta = sweep(i, cfg.samples, cfg.theta_range_deg);
        let depth = tap_cfg.depth_mm + rng.random_range(-1.0..=1.0) * tap_cfg.depth_jitter_mm;
        let at = LabelConvention::edge_pose_of(labels.as_ref().map(|(c, _)| c), r, theta);
        arm.move_to(pose_at_edge(edge, normal, at.0, at.1, tap_cfg.height_mm))?;
        let frame = tap(arm, sensor, depth)?;
        let tracked = extractor.extract(&frame)?;
        if tracked.missing > 0 {
            with_missing += 1;
        }
        inputs.extend(tracked.displacement(extractor.tracker.reference()));
        targets.extend([r as f32, theta as f32]);
        if cfg.save_frames {
            frames.push((format!("frame_{i:05}.png"), png_bytes(&frame, "frame")?));
        }
        progress(i + 1);
    }
    if cfg.save_frames {
        frames.push(("reference.png".into(), png_bytes(reference, "reference")?));
    }
    let meta = DatasetMeta {
        source: source.into(),
        origin: origin.into(),
        seed: Some(cfg.seed),
        samples: cfg.samples,
        pins: dim / 2,
        targets: labels.map_or(["r_mm".into(), "theta_deg".into()], |(_, n)| n),
        frames_with_missing_pins: with_missing,
        reference_pins: extractor.tracker.reference().to_vec(),
        settings,
        tactrace_version: crate::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
        tracking: tactrace_store::TrackTotals::frames(cfg.samples, with_missing),
    };
    Ok(Collected {
        data: TapData {
            inputs,
            targets,
            meta,
        },
        frames,
    })
}

/// theta for sample `i` of `n`, sweeping linearly from -range to +range.
fn sweep(i: usize, n: usize, range: f64) -> f64 {
    if n <= 1 {
        return 0.0;
    }
    -range + 2.0 * range * i as f64 / (n - 1) as f64
}
