//! The contour-following experiment (report ch. 5.2-5.3): a simulated rig
//! over one shape, the servo loop, metrics and figures in a run directory.
//!
//! The trajectory is written step by step and flushed, so an interrupted run
//! keeps what it did; `metrics.json` is written last and marks completion.
use crate::error::{io_err, LabError, Result};
use crate::metrics::{evaluate, l2_curve, FollowMetrics};
use crate::pin_order::check_pin_order;
use crate::rig::{RigConfig, SimRig, TapConfig};
use crate::servo::{
    check_follow_config, follow, FollowConfig, FollowSummary, Perception, StepRecord, StepSink,
};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;
use tactrace_arm::{Arm, Pose};
use tactrace_control::{PbtsConfig, PbtsController};
use tactrace_geometry::{Contour, Vec2};
use tactrace_learn::PoseModel;
use tactrace_sensor::{Frame, TactileSensor};
use tactrace_vision::PinExtractor;

/// Where the run starts: on the edge point at `arc_mm`, offset along the
/// outward normal and rotated, at tap height (the report: "2 mm above the
/// surface, roughly aligned with an edge").
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StartConfig {
    /// Arc length of the start point along the contour, mm. `None` (the
    /// default): the middle of the flattest 20 mm of the contour, as an
    /// operator would align the sensor with an edge rather than a corner.
    pub arc_mm: Option<f64>,
    pub offset_mm: f64,
    pub angle_deg: f64,
    /// Refuse to start further than this from the edge, mm.
    pub max_start_distance_mm: f64,
}

impl Default for StartConfig {
    fn default() -> Self {
        Self {
            arc_mm: None,
            offset_mm: 0.0,
            angle_deg: 0.0,
            max_start_distance_mm: 6.0,
        }
    }
}

/// Everything a follow run needs besides the model and the shape.
#[derive(Debug, Clone, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct FollowRunConfig {
    pub rig: RigConfig,
    pub controller: PbtsConfig,
    pub follow: FollowConfig,
    pub start: StartConfig,
    /// Mean pin displacement (px) below which a tap counts as no contact.
    pub contact_threshold_px: f64,
}

impl FollowRunConfig {
    /// Defaults for the simulated rig.
    pub fn simulated() -> Self {
        Self {
            rig: RigConfig::simulated(),
            contact_threshold_px: 0.5,
            ..Self::default()
        }
    }
}

/// The outcome of a follow run.
pub struct FollowOutcome {
    pub summary: FollowSummary,
    pub metrics: FollowMetrics,
    pub records: Vec<StepRecord>,
    pub l2_curve: Vec<f64>,
}

/// Writes each step to `trajectory.csv` as it happens.
struct TrajectoryCsv(std::io::BufWriter<std::fs::File>, std::path::PathBuf);

impl StepSink for TrajectoryCsv {
    fn on_step(&mut self, r: &StepRecord) -> Result<()> {
        let p = &r.percept;
        writeln!(
            self.0,
            "{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{}",
            r.step,
            r.pose.x,
            r.pose.y,
            r.pose.rz,
            p.r_mm,
            p.theta_deg,
            p.mean_displacement_px,
            p.contact
        )
        .and_then(|_| self.0.flush())
        .map_err(io_err(&self.1))
    }
}

/// metrics.json of a follow run: every metric at the top level (the keys
/// scripts read: `mean_l2_mm`, `closed`, `steps`, ...) and how it ended.
#[derive(Serialize)]
struct MetricsDocument<'a> {
    #[serde(flatten)]
    metrics: &'a FollowMetrics,
    ending: crate::servo::Ending,
    message: &'a str,
}

/// A sink that calls a closure (progress bars).
pub struct FnSink<F: FnMut(&StepRecord)>(pub F);

impl<F: FnMut(&StepRecord)> StepSink for FnSink<F> {
    fn on_step(&mut self, r: &StepRecord) -> Result<()> {
        (self.0)(r);
        Ok(())
    }
}

/// The start pose for `cfg` on `shape`.
pub fn start_pose(shape: &Contour, cfg: &StartConfig, height_mm: f64) -> Result<Pose> {
    if cfg.offset_mm.abs() > cfg.max_start_distance_mm {
        return Err(LabError::Config(format!(
            "the start pose is {:.1} mm from the edge; the sensor cannot feel an edge further than {:.1} mm away",
            cfg.offset_mm.abs(),
            cfg.max_start_distance_mm
        )));
    }
    let arc = cfg.arc_mm.unwrap_or_else(|| flattest_arc_mm(shape, 20.0));
    let (edge, normal) = shape.at_arc_length(arc);
    Ok(crate::collect::pose_at_edge(
        edge,
        normal,
        cfg.offset_mm,
        cfg.angle_deg,
        height_mm,
    ))
}

/// Arc length (mm) of the middle of the stretch of length `window_mm` over
/// which the outward normal turns least: the place to set the sensor down.
pub fn flattest_arc_mm(shape: &Contour, window_mm: f64) -> f64 {
    let n = (shape.perimeter() / 0.5).ceil().max(8.0) as usize;
    let step = shape.perimeter() / n as f64;
    let heading: Vec<f64> = (0..n)
        .map(|i| {
            let (_, normal) = shape.at_arc_length(i as f64 * step);
            normal.y.atan2(normal.x)
        })
        .collect();
    let turn = |i: usize| {
        let d = heading[(i + 1) % n] - heading[i];
        (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    };
    let k = ((window_mm / step).round() as usize).clamp(1, n);
    let total = |start: usize| (0..k).map(|j| turn((start + j) % n).abs()).sum::<f64>();
    let best = (0..n)
        .min_by(|&a, &b| total(a).total_cmp(&total(b)))
        .unwrap_or(0);
    (best as f64 + k as f64 / 2.0) * step % shape.perimeter()
}

/// What the servo loop needs besides the arm, the sensor and the model.
pub struct LoopSettings<'a> {
    pub blob: &'a tactrace_vision::BlobParams,
    pub controller: &'a PbtsConfig,
    pub follow: &'a FollowConfig,
    pub tap: &'a TapConfig,
    /// Mean pin displacement (px) below which a tap counts as no contact.
    pub contact_threshold_px: f64,
    /// The reference pins of the model's training data (`pins.json`); the
    /// loop refuses a reference frame whose pins are ordered otherwise
    /// (`None`: not checked).
    pub model_pins: Option<&'a [[f64; 2]]>,
}

/// The servo loop on any arm and sensor, simulated or real: pins are
/// ordered against `reference` (the undeformed frame), each step goes to
/// `out/trajectory.csv` as it happens (flushed, so an interrupted run keeps
/// what it did) and to `progress`.
pub fn run_servo(
    arm: &mut dyn Arm,
    sensor: &mut dyn TactileSensor,
    reference: &Frame,
    model: PoseModel,
    settings: &LoopSettings,
    out: &Path,
    progress: &mut dyn FnMut(&StepRecord),
) -> Result<(FollowSummary, Vec<StepRecord>)> {
    check_follow_config(settings.follow)?;
    std::fs::create_dir_all(out).map_err(io_err(out))?;
    let extractor = PinExtractor::from_reference_frame(reference, settings.blob.clone())?;
    let rig_reference = Path::new("the rig's reference frame");
    check_pin_order(
        settings.model_pins,
        extractor.tracker.reference(),
        rig_reference,
    )?;
    if model.input_dim() != 2 * extractor.tracker.reference().len() {
        return Err(LabError::Config(format!(
            "the model expects {} inputs but the sensor gives {} (2 x pins)",
            model.input_dim(),
            2 * extractor.tracker.reference().len()
        )));
    }
    let perception = Perception {
        extractor,
        model,
        contact_threshold_px: settings.contact_threshold_px,
    };
    let mut controller = PbtsController::new(settings.controller.clone());
    let path = out.join("trajectory.csv");
    let mut file = std::fs::File::create(&path).map_err(io_err(&path))?;
    writeln!(
        file,
        "step,x_mm,y_mm,angle_deg,r_pred_mm,theta_pred_deg,mean_displacement_px,contact"
    )
    .map_err(io_err(&path))?;
    let mut csv = TrajectoryCsv(std::io::BufWriter::new(file), path);
    let mut records: Vec<StepRecord> = Vec::new();
    let mut bar = FnSink(|r: &StepRecord| progress(r));
    let summary = follow(
        arm,
        sensor,
        &perception,
        &mut controller,
        settings.follow,
        settings.tap,
        &mut [&mut csv, &mut records, &mut bar],
    )?;
    Ok((summary, records))
}

/// Run the experiment on `shape` with `model` (whose training data's
/// reference pins are `model_pins`, if known), writing into `out` (created).
pub fn run_follow(
    cfg: &FollowRunConfig,
    (model, model_pins): (PoseModel, Option<&[[f64; 2]]>),
    shape: &Contour,
    out: &Path,
    progress: &mut dyn FnMut(&StepRecord),
) -> Result<FollowOutcome> {
    check_follow_config(&cfg.follow)?;
    let start = start_pose(shape, &cfg.start, cfg.rig.tap.height_mm)?;
    cfg.rig.workspace.validate()?;
    cfg.rig.workspace.check_inside(start).map_err(|e| {
        LabError::Config(format!(
            "the arm cannot reach the start on this contour ({:.1}, {:.1}) mm: {e}",
            start.x, start.y
        ))
    })?;
    let mut rig = SimRig::new(&cfg.rig, shape.clone(), start, cfg.follow.seed)?;
    let settings = LoopSettings {
        blob: &cfg.rig.blob,
        controller: &cfg.controller,
        follow: &cfg.follow,
        tap: &cfg.rig.tap,
        contact_threshold_px: cfg.contact_threshold_px,
        model_pins,
    };
    let reference = rig.reference_frame();
    let (summary, records) = run_servo(
        &mut rig.arm,
        &mut rig.sensor,
        &reference,
        model,
        &settings,
        out,
        progress,
    )?;
    let (metrics, curve) = score_run(shape, &records, &summary, &cfg.follow, out)?;
    Ok(FollowOutcome {
        summary,
        metrics,
        records,
        l2_curve: curve,
    })
}

/// The metrics of a finished run against the true `shape` (report ch. 5.3
/// and beyond), written to `out/metrics.json`; returns them with the L2
/// error curve (1000 contour points).
pub fn score_run(
    shape: &Contour,
    records: &[StepRecord],
    summary: &FollowSummary,
    follow: &FollowConfig,
    out: &Path,
) -> Result<(FollowMetrics, Vec<f64>)> {
    let traj: Vec<Vec2> = records
        .iter()
        .map(|r| Vec2::new(r.pose.x, r.pose.y))
        .collect();
    let metrics = evaluate(
        shape,
        &traj,
        follow.close_radius_mm,
        follow.min_excursion_mm,
    );
    let curve = l2_curve(shape, &traj, 1000);
    let document = MetricsDocument {
        metrics: &metrics,
        ending: summary.ending,
        message: &summary.message,
    };
    let json = serde_json::to_string_pretty(&document).expect("metrics serialise");
    crate::fsutil::write_atomic(&out.join("metrics.json"), json.as_bytes())?;
    Ok((metrics, curve))
}
