//! The contour-following experiment on a real rig (report ch. 5.2): a UR5
//! arm and a TacTip camera from `tactrace-hw`, behind the same `Arm` and
//! `TactileSensor` traits and the same servo loop as the simulation.
//!
//! The arm is always wrapped in a [`LimitedArm`] that refuses any move
//! outside the configured workspace box or larger than its step limits, so
//! a bad prediction stops the run instead of moving the robot. The
//! configuration must name the workspace and the start pose explicitly:
//! there is no safe default for a real robot. docs/hardware.md explains
//! the set-up.
use crate::collect::{check_samples, collect_on, pose_at_edge, CollectConfig, Collected, EdgeRig};
use crate::error::{LabError, Result};
use crate::follow::{run_servo, score_run, LoopSettings};
use crate::metrics::FollowMetrics;
use crate::rig::TapConfig;
use crate::servo::{FollowConfig, FollowSummary, StepRecord};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose, Workspace};
use tactrace_control::PbtsConfig;
use tactrace_geometry::{Contour, Vec2};
use tactrace_hw::{
    CameraSensor, CommandSource, CommandSourceConfig, FolderSource, FrameSource, PreprocessConfig,
    Ur5Arm, Ur5Config,
};
use tactrace_learn::PoseModel;
use tactrace_sensor::{Frame, TactileSensor};
use tactrace_vision::BlobParams;

/// Where the frames come from.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum CameraConfig {
    /// An external capture program per frame (`[camera.command]`).
    Command(CommandSourceConfig),
    /// Replay the images of a folder in natural order (`[camera.folder]`):
    /// dry runs and tests without a camera.
    Folder {
        path: PathBuf,
        #[serde(default)]
        looping: bool,
    },
}

/// The start pose in the work frame: the sensor above a point of the edge,
/// roughly aligned with it (report ch. 5.2).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HardwareStart {
    pub x_mm: f64,
    pub y_mm: f64,
    /// Rotation of the sensor about the vertical, degrees.
    #[serde(default)]
    pub angle_deg: f64,
}

/// A real rig: one TOML file with these tables. `arm`, `camera`,
/// `workspace` and `start` are required.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HardwareConfig {
    pub arm: Ur5Config,
    pub camera: CameraConfig,
    #[serde(default)]
    pub preprocess: PreprocessConfig,
    pub workspace: Workspace,
    pub start: HardwareStart,
    #[serde(default)]
    pub tap: TapConfig,
    /// Blob detection (default: the `real256` preset for 256 x 256
    /// preprocessed frames).
    #[serde(default = "real_blob")]
    pub blob: BlobParams,
    #[serde(default)]
    pub controller: PbtsConfig,
    #[serde(default)]
    pub follow: FollowConfig,
    /// Mean pin displacement (px) below which a tap counts as no contact.
    #[serde(default = "default_contact")]
    pub contact_threshold_px: f64,
}

fn real_blob() -> BlobParams {
    BlobParams::preset("real256").expect("built-in preset")
}

fn default_contact() -> f64 {
    0.5
}

impl HardwareConfig {
    /// Parse a rig file (unknown keys are errors).
    pub fn from_toml(text: &str, what: &str) -> Result<Self> {
        toml::from_str(text).map_err(|e| LabError::Config(format!("{what}: {e}")))
    }

    /// The start pose at tap height.
    pub fn start_pose(&self) -> Pose {
        Pose {
            x: self.start.x_mm,
            y: self.start.y_mm,
            z: self.tap.height_mm,
            rz: self.start.angle_deg,
            ..Pose::default()
        }
    }

    /// Everything that can be checked without touching the hardware.
    pub fn validate(&self) -> Result<()> {
        self.arm
            .validate()
            .map_err(|e| LabError::Config(format!("arm: {e}")))?;
        self.preprocess
            .validate()
            .map_err(|e| LabError::Config(format!("preprocess: {e}")))?;
        self.workspace.validate()?;
        crate::servo::check_follow_config(&self.follow)?;
        let start = self.start_pose();
        self.workspace.check_inside(start).map_err(|e| {
            LabError::Config(format!(
                "the start ({:.1}, {:.1}) mm at tap height is outside the workspace: {e}",
                start.x, start.y
            ))
        })?;
        let low = Pose {
            z: self.tap.height_mm - self.tap.depth_mm - self.tap.depth_jitter_mm,
            ..start
        };
        self.workspace.check_inside(low).map_err(|e| {
            LabError::Config(format!(
                "the deepest tap (z = {:.2} mm) is outside the workspace: {e}",
                low.z
            ))
        })?;
        Ok(())
    }

    fn camera(&self) -> Result<Box<dyn TactileSensor>> {
        let preprocess = self
            .preprocess
            .validate()
            .map_err(|e| LabError::Config(format!("preprocess: {e}")))?;
        let camera_err = |e: tactrace_hw::HwError| LabError::Config(format!("camera: {e}"));
        Ok(match &self.camera {
            CameraConfig::Command(c) => boxed(
                CommandSource::from_config(c).map_err(camera_err)?,
                preprocess,
            ),
            CameraConfig::Folder { path, looping } => boxed(
                FolderSource::new(path)
                    .map_err(camera_err)?
                    .looping(*looping),
                preprocess,
            ),
        })
    }
}

fn boxed<S: FrameSource + 'static>(
    source: S,
    preprocess: tactrace_hw::Preprocess,
) -> Box<dyn TactileSensor> {
    Box::new(CameraSensor::new(source, preprocess))
}

/// The outcome of a run on the rig; metrics only when the true contour
/// was given.
pub struct HardwareOutcome {
    pub summary: FollowSummary,
    pub records: Vec<StepRecord>,
    pub metrics: Option<(FollowMetrics, Vec<f64>)>,
}

/// Follow an edge on the real rig: connect, move to the start at tap
/// height, capture the undeformed reference frame there, then run the
/// servo loop. `shape`, if given, is the object's true contour in the
/// work frame and is used only to score the finished run.
pub fn run_follow_hardware(
    cfg: &HardwareConfig,
    (model, model_pins): (PoseModel, Option<&[[f64; 2]]>),
    shape: Option<&Contour>,
    out: &Path,
    progress: &mut dyn FnMut(&StepRecord),
) -> Result<HardwareOutcome> {
    cfg.validate()?;
    let (mut arm, mut sensor, reference) = connect_at(cfg, cfg.start_pose())?;
    let settings = LoopSettings {
        blob: &cfg.blob,
        controller: &cfg.controller,
        follow: &cfg.follow,
        tap: &cfg.tap,
        contact_threshold_px: cfg.contact_threshold_px,
        model_pins,
    };
    let (summary, records) = run_servo(
        &mut arm,
        sensor.as_mut(),
        &reference,
        model,
        &settings,
        out,
        progress,
    )?;
    let metrics = match shape {
        Some(s) => Some(score_run(s, &records, &summary, &cfg.follow, out)?),
        None => {
            let doc = serde_json::json!({
                "steps": summary.steps,
                "ending": summary.ending,
                "message": summary.message,
            });
            let json = serde_json::to_string_pretty(&doc).expect("metrics serialise");
            crate::fsutil::write_atomic(&out.join("metrics.json"), json.as_bytes())?;
            None
        }
    };
    Ok(HardwareOutcome {
        summary,
        records,
        metrics,
    })
}

/// Open the camera, connect the arm behind the limiter, move to `first`
/// (tap height, sensor in the air) and capture the undeformed reference
/// frame there.
fn connect_at(
    cfg: &HardwareConfig,
    first: Pose,
) -> Result<(LimitedArm<Ur5Arm>, Box<dyn TactileSensor>, Frame)> {
    let mut sensor = cfg.camera()?;
    let ur5 = Ur5Arm::connect(cfg.arm.clone()).map_err(|e| LabError::Servo(e.to_string()))?;
    let mut arm = LimitedArm::new(ur5, cfg.workspace.clone(), LimitMode::Refuse);
    arm.move_to(first).map_err(|e| {
        LabError::Servo(format!(
            "moving to the start (jog the arm to within the step limit of it first): {e}"
        ))
    })?;
    let reference = sensor.capture()?;
    Ok((arm, sensor, reference))
}

/// The edge of a collection on the rig: `[start]` is a point of the edge
/// and `angle_deg` the direction of its outward normal (the sensor's yaw at
/// theta = 0).
pub fn collection_edge(cfg: &HardwareConfig) -> (Vec2, Vec2) {
    let a = cfg.start.angle_deg.to_radians();
    (
        Vec2::new(cfg.start.x_mm, cfg.start.y_mm),
        Vec2::new(a.cos(), a.sin()),
    )
}

/// Collect taps at the edge on the real rig (report ch. 4.1), exactly as
/// the simulated collection does; refuses to start when any collection pose
/// or the deepest tap lies outside the workspace.
pub fn collect_hardware(
    cfg: &HardwareConfig,
    collect: &CollectConfig,
    origin: &str,
    progress: impl FnMut(usize),
) -> Result<Collected> {
    check_samples(collect)?;
    cfg.validate()?;
    let (edge, normal) = collection_edge(cfg);
    let t = &cfg.tap;
    for r in [-collect.r_range_mm, collect.r_range_mm] {
        for z in [t.height_mm, t.height_mm - t.depth_mm - t.depth_jitter_mm] {
            let pose = Pose {
                z,
                ..pose_at_edge(edge, normal, r, 0.0, t.height_mm)
            };
            cfg.workspace.check_inside(pose).map_err(|e| {
                LabError::Config(format!(
                    "collection pose r = {r:.1} mm, z = {z:.2} mm is outside the workspace: {e}"
                ))
            })?;
        }
    }
    let first = pose_at_edge(edge, normal, 0.0, -collect.theta_range_deg, t.height_mm);
    let (mut arm, mut sensor, reference) = connect_at(cfg, first)?;
    let on = EdgeRig {
        arm: &mut arm,
        sensor: sensor.as_mut(),
        reference: &reference,
        blob: &cfg.blob,
        tap: &cfg.tap,
        edge,
        normal,
    };
    let settings = serde_json::json!({ "hardware": cfg, "collect": collect });
    collect_on(on, collect, "real", origin, settings, progress)
}
