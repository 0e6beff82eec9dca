//! The real rig (report ch. 5.2): a UR5 arm and a TacTip camera from
//! `tactrace-hw`, behind the same `Arm` and `TactileSensor` traits and the
//! same servo loop as the simulation. Its rig file ([`HardwareConfig`]) is
//! the real world of a follow run ([`crate::world::World::Hardware`], run
//! by [`crate::follow::run`]); the collection on the rig is here.
//!
//! The arm is always wrapped in a [`LimitedArm`] that refuses any move
//! outside the configured workspace box or larger than its step limits, so
//! a bad prediction stops the run instead of moving the robot. The
//! configuration must name the workspace and the start pose explicitly:
//! there is no safe default for a real robot. docs/hardware.md explains
//! the set-up.
//!
//! A run stops on a [`StopFlag`] (SIGINT/SIGTERM in the binary): the
//! driver sends `stopl`, a follow run keeps its steps in `OUT.partial`,
//! and the error is [`LabError::Interrupted`]. A failure on the way to the
//! start is [`LabError::StartMove`]: the limiter's refusal (too far from
//! the start) apart from a fault of the arm. `tactrace rig check` is in
//! [`rig_check`] (module `check`).
mod check;
mod sight;

pub use check::{rig_check, RigCheck, RigCheckItem};
pub use sight::RigSight;
pub use tactrace_hw::{StopFlag, StopSignal};

use crate::collect::{check_samples, collect_on, CollectConfig, Collected, EdgeRig};
use crate::error::{LabError, Result};
use crate::follow::ServoSettings;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose, Workspace};
use tactrace_control::PbtsConfig;
use tactrace_geometry::Vec2;
use tactrace_hw::{
    open_v4l2, CameraSensor, CommandSource, CommandSourceConfig, FolderSource, FrameSource,
    HwError, PreprocessConfig, Ur5Arm, Ur5Config, V4l2Config,
};
use tactrace_sensor::{Frame, TactileSensor};
use tactrace_servo::{pose_at_edge, LoopConfig, TapConfig};
use tactrace_vision::BlobParams;

/// Where the real rig's frames come from: the `[camera]` table of a rig
/// file (not the simulated camera of `tactrace_sensor::CameraConfig`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum FrameSourceConfig {
    /// A V4L2 camera kept open for the whole run (`[camera.v4l2]`).
    V4l2(V4l2Config),
    /// An external capture program per frame (`[camera.command]`).
    Command(CommandSourceConfig),
    /// Replay the images of a folder in natural order (`[camera.folder]`):
    /// dry runs and tests without a camera. With `preprocessed = true` the
    /// images are taken as already preprocessed frames (a dataset's
    /// `frames/`) and the rig's preprocessing is not applied to them.
    Folder {
        path: PathBuf,
        #[serde(default)]
        looping: bool,
        #[serde(default)]
        preprocessed: bool,
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
    /// The sensor file (`tactrace sensor inspect --out`) saying how to
    /// read the camera's images: its preprocessing and detector
    /// replace `preprocess` and `blob`, which must then be left out
    /// ([`HardwareConfig::sight`]). A relative path is taken from the rig
    /// file's folder ([`HardwareConfig::read`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor: Option<PathBuf>,
    /// The camera preprocessing of older rig files (without `sensor`);
    /// left out of a written file when it is the default, so that a run
    /// folder's copy of a rig with a sensor file reads back.
    #[serde(default, skip_serializing_if = "is_default_preprocess")]
    pub preprocess: PreprocessConfig,
    pub workspace: Workspace,
    pub start: HardwareStart,
    #[serde(default)]
    pub tap: TapConfig,
    /// Blob detection without `sensor` (default: the `real256` preset for
    /// 256 x 256 preprocessed frames).
    #[serde(default = "real_blob", skip_serializing_if = "is_real_blob")]
    pub blob: BlobParams,
    #[serde(default)]
    pub controller: PbtsConfig,
    #[serde(default)]
    pub follow: LoopConfig,
}

pub(crate) fn real_blob() -> BlobParams {
    BlobParams::preset("real256").expect("built-in preset")
}

fn is_real_blob(blob: &BlobParams) -> bool {
    *blob == real_blob()
}

fn is_default_preprocess(p: &PreprocessConfig) -> bool {
    *p == PreprocessConfig::default()
}

impl HardwareConfig {
    /// Parse a rig file named `what`: the optional tables (preprocess, tap,
    /// blob, controller, follow) start from their defaults and the file
    /// overlays them key by key, as every configuration does; `arm`,
    /// `camera`, `workspace` and `start` must be given. Unknown keys are
    /// errors, and so is a `sensor` file given with a `[preprocess]` or
    /// `[blob]` table. A relative `sensor` is kept as written
    /// ([`HardwareConfig::read`] resolves it).
    pub fn from_toml(text: &str, what: &str) -> Result<Self> {
        sight::check_one_way(text, what)?;
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

    /// The loop settings of this rig, checked (a sensor file is read for
    /// its detector).
    pub fn servo_settings(&self) -> Result<ServoSettings> {
        ServoSettings::of_detector(
            self.sight()?.detect,
            self.controller.clone(),
            self.follow.clone(),
            self.tap,
        )
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
        if let FrameSourceConfig::V4l2(c) = &self.camera {
            c.validate()?;
        }
        self.sight()?;
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

    /// The camera as a tactile sensor: its source through the rig's
    /// preprocessing ([`HardwareConfig::sight`]; a sensor file's only for
    /// images of the size it was made for).
    pub fn camera(&self) -> Result<Box<dyn TactileSensor>> {
        let sight = self.sight()?;
        let seen = (sight.preprocess, sight.frame_size);
        Ok(match &self.camera {
            FrameSourceConfig::V4l2(c) => boxed(open_v4l2(c)?, seen)?,
            FrameSourceConfig::Command(c) => boxed(CommandSource::from_config(c)?, seen)?,
            FrameSourceConfig::Folder {
                path,
                looping,
                preprocessed,
            } => {
                let seen = match preprocessed {
                    true => (PreprocessConfig::grayscale_only().validate()?, None),
                    false => seen,
                };
                boxed(FolderSource::new(path)?.looping(*looping), seen)?
            }
        })
    }
}

fn boxed<S: FrameSource + 'static>(
    source: S,
    (preprocess, size): (tactrace_hw::Preprocess, Option<[u32; 2]>),
) -> Result<Box<dyn TactileSensor>> {
    let sensor = CameraSensor::new(source, preprocess);
    Ok(match size {
        Some(size) => Box::new(sensor.for_size(size)?),
        None => Box::new(sensor),
    })
}

/// Sends `stopl` after a stop request: [`LabError::Hardware`] with
/// [`HwError::StopFailed`] when it cannot be sent.
fn halt(arm: &mut LimitedArm<Ur5Arm>, signal: StopSignal) -> Result<()> {
    arm.inner_mut().halt().map_err(|e| {
        LabError::Hardware(HwError::StopFailed {
            signal,
            source: Box::new(e),
        })
    })
}

/// The error of a run stopped by `signal`: the arm, if connected, sent
/// `stopl` first (if that fails, the run's error says so instead).
pub(crate) fn stopped(
    signal: StopSignal,
    stop: &StopFlag,
    arm: Option<&mut LimitedArm<Ur5Arm>>,
) -> LabError {
    let arm_stopped = arm.is_some();
    match arm.map_or(Ok(()), |a| halt(a, signal)) {
        Ok(()) => {
            stop.mark_halted();
            LabError::Interrupted {
                signal,
                arm_stopped,
                kept: None,
            }
        }
        Err(e) => e,
    }
}

/// `err`, or the error of an interrupted run when a stop was asked.
fn unless_interrupted(
    err: LabError,
    stop: &StopFlag,
    arm: Option<&mut LimitedArm<Ur5Arm>>,
) -> LabError {
    match stop.requested() {
        Some(signal) => stopped(signal, stop, arm),
        None => err,
    }
}

/// Open the camera, connect the arm behind the limiter, move to `first`
/// (tap height, sensor in the air) and capture the undeformed reference
/// frame there. A move refused or failed on the way is
/// [`LabError::StartMove`] (a stop request: [`LabError::Interrupted`]).
pub(crate) fn connect_at(
    cfg: &HardwareConfig,
    first: Pose,
    stop: &StopFlag,
) -> Result<(LimitedArm<Ur5Arm>, Box<dyn TactileSensor>, Frame)> {
    let mut sensor = cfg.camera()?;
    let ur5 = Ur5Arm::connect_stoppable(cfg.arm.clone(), stop.clone())
        .map_err(|e| unless_interrupted(e.into(), stop, None))?;
    let mut arm = LimitedArm::new(ur5, cfg.workspace.clone(), LimitMode::Refuse);
    if let Err(source) = arm.move_to(first) {
        return Err(unless_interrupted(
            LabError::StartMove { source },
            stop,
            Some(&mut arm),
        ));
    }
    let reference = sensor
        .capture()
        .map_err(|e| unless_interrupted(e.into(), stop, Some(&mut arm)))?;
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
/// or the deepest tap lies outside the workspace. When `stop` is set the
/// arm is sent `stopl` and the collection ends with
/// [`LabError::Interrupted`] (no dataset is made of the taps so far).
pub fn collect_hardware(
    cfg: &HardwareConfig,
    collect: &CollectConfig,
    origin: &str,
    stop: &StopFlag,
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
    let detect = cfg.sight()?.detect;
    let (mut arm, mut sensor, reference) = connect_at(cfg, first, stop)?;
    let on = EdgeRig {
        arm: &mut arm,
        sensor: sensor.as_mut(),
        reference: &reference,
        detect: &detect,
        tap: &cfg.tap,
        edge,
        normal,
        labels: None,
    };
    let settings = serde_json::json!({ "hardware": cfg, "collect": collect });
    let collected = collect_on(on, collect, "real", origin, settings, progress);
    match stop.requested() {
        Some(signal) => Err(stopped(signal, stop, Some(&mut arm))),
        None => collected,
    }
}

/// The V4L2 capture devices of this machine (`tactrace camera list`).
pub fn list_cameras() -> Result<Vec<tactrace_hw::CameraInfo>> {
    Ok(tactrace_hw::list_cameras()?)
}

/// One raw grey frame from a V4L2 camera (`tactrace camera grab`): the
/// rig file's `[camera.v4l2]` settings when given, with `device`
/// replacing its device; no preprocessing.
pub fn grab_camera_frame(device: &str, rig: Option<&HardwareConfig>) -> Result<image::GrayImage> {
    let mut config = match rig.map(|r| &r.camera) {
        Some(FrameSourceConfig::V4l2(c)) => c.clone(),
        _ => V4l2Config::new(device),
    };
    config.device = device.to_string();
    let mut source = open_v4l2(&config)?;
    Ok(source.grab()?.to_luma8())
}
