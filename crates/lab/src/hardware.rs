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
use crate::collect::{check_samples, collect_on, CollectConfig, Collected, EdgeRig};
use crate::error::{LabError, Result};
use crate::follow::{
    follow_on_rig, perception_for, write_results, FollowOutcome, RunFolder, ServoSettings,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose, Workspace};
use tactrace_control::PbtsConfig;
use tactrace_geometry::{Contour, Vec2};
use tactrace_hw::{
    CameraSensor, CommandSource, CommandSourceConfig, FolderSource, FrameSource, PreprocessConfig,
    Ur5Arm, Ur5Config,
};
use tactrace_sensor::{Frame, TactileSensor};
use tactrace_servo::{pose_at_edge, LoopConfig, StepRecord, TapConfig};
use tactrace_store::StoredModel;
use tactrace_vision::BlobParams;

/// Where the real rig's frames come from: the `[camera]` table of a rig
/// file (not the simulated camera of `tactrace_sensor::CameraConfig`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum FrameSourceConfig {
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
    pub camera: FrameSourceConfig,
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
    pub follow: LoopConfig,
}

fn real_blob() -> BlobParams {
    BlobParams::preset("real256").expect("built-in preset")
}

impl HardwareConfig {
    /// Parse a rig file named `what`: the optional tables (preprocess, tap,
    /// blob, controller, follow) start from their defaults and the file
    /// overlays them key by key, as every configuration does; `arm`,
    /// `camera`, `workspace` and `start` must be given. Unknown keys are
    /// errors.
    pub fn from_toml(text: &str, what: &str) -> Result<Self> {
        #[derive(Serialize)]
        struct Defaults {
            preprocess: PreprocessConfig,
            tap: TapConfig,
            blob: BlobParams,
            controller: PbtsConfig,
            follow: LoopConfig,
        }
        let defaults = Defaults {
            preprocess: PreprocessConfig::default(),
            tap: TapConfig::default(),
            blob: real_blob(),
            controller: PbtsConfig::default(),
            follow: LoopConfig::default(),
        };
        let base = toml::Value::try_from(&defaults).map_err(|e| LabError::Config(e.to_string()))?;
        Ok(tactrace_store::config_file::overlay_value(
            base, text, what,
        )?)
    }

    /// The loop settings of this rig.
    pub fn servo_settings(&self) -> ServoSettings {
        ServoSettings {
            blob: self.blob.clone(),
            controller: self.controller.clone(),
            follow: self.follow.clone(),
            tap: self.tap,
        }
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
        self.arm.validate()?;
        self.preprocess.validate()?;
        self.workspace.validate()?;
        self.follow.validate()?;
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
        let preprocess = self.preprocess.validate()?;
        Ok(match &self.camera {
            FrameSourceConfig::Command(c) => boxed(CommandSource::from_config(c)?, preprocess),
            FrameSourceConfig::Folder { path, looping } => {
                boxed(FolderSource::new(path)?.looping(*looping), preprocess)
            }
        })
    }
}

fn boxed<S: FrameSource + 'static>(
    source: S,
    preprocess: tactrace_hw::Preprocess,
) -> Box<dyn TactileSensor> {
    Box::new(CameraSensor::new(source, preprocess))
}

/// Follow an edge on the real rig: connect, move to the start at tap
/// height, capture the undeformed reference frame there, check it against
/// the model's pins, then run the servo loop into the run folder `out`.
/// `shape`, if given, is the object's true contour in the work frame (and
/// its name) and is used only to score the finished run.
pub fn follow_hardware(
    cfg: &HardwareConfig,
    model: &StoredModel,
    shape: Option<(&str, &Contour)>,
    (out, force): (&Path, bool),
    progress: &mut dyn FnMut(&StepRecord),
) -> Result<FollowOutcome> {
    cfg.validate()?;
    tactrace_store::check_output_dir(out, force)?;
    let (mut arm, mut sensor, reference) = connect_at(cfg, cfg.start_pose())?;
    let settings = cfg.servo_settings();
    let perception = perception_for(&reference, model, &settings)?;
    let run = RunFolder::start(out, force, cfg)?;
    let (summary, records) = follow_on_rig(
        &mut arm,
        sensor.as_mut(),
        &perception,
        &settings,
        run.path(),
        progress,
    )?;
    let (metrics, l2_curve) = write_results(
        shape,
        &records,
        &summary,
        &cfg.follow,
        crate::follow::tactip_diameter_mm(),
        run.path(),
    )?;
    let dir = run.finish()?;
    Ok(FollowOutcome {
        summary,
        records,
        metrics,
        l2_curve,
        dir,
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
    let ur5 = Ur5Arm::connect(cfg.arm.clone())?;
    let mut arm = LimitedArm::new(ur5, cfg.workspace.clone(), LimitMode::Refuse);
    arm.move_to(first).map_err(|e| {
        LabError::Config(format!(
            "cannot move to the start (jog the arm to within the step limit of it first): {e}"
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
        labels: None,
    };
    let settings = serde_json::json!({ "hardware": cfg, "collect": collect });
    collect_on(on, collect, "real", origin, settings, progress)
}
