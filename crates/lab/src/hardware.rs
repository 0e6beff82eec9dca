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
use tactrace_hw::ur5::realtime::{check_can_move, safety_mode_name};
use tactrace_hw::{
    open_v4l2, probe_state, CameraSensor, CommandSource, CommandSourceConfig, Dashboard,
    FolderSource, FrameSource, PreprocessConfig, StateInterface, Ur5Arm, Ur5Config, V4l2Config,
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
    /// A V4L2 camera kept open for the whole run (`[camera.v4l2]`).
    V4l2(V4l2Config),
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
        if let FrameSourceConfig::V4l2(c) = &self.camera {
            c.validate()?;
        }
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
            FrameSourceConfig::V4l2(c) => boxed(open_v4l2(c)?, preprocess),
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
    let _out = tactrace_store::check_output_dir(out, force)?;
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

/// One line of `tactrace rig check`: a part of the rig, whether it is
/// ready, and what was seen (or what to do).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RigCheckItem {
    /// `dashboard`, `safety`, `state`, `camera` or `reference`.
    pub name: &'static str,
    /// Whether this part is ready for a run.
    pub ready: bool,
    /// What was found, or what to do about it.
    pub detail: String,
}

/// The outcome of [`rig_check`]: one item per part, and notes that do not
/// make the rig unready.
#[derive(Debug, Clone, Default)]
pub struct RigCheck {
    /// The parts checked, in order.
    pub items: Vec<RigCheckItem>,
    /// Warnings for the operator.
    pub notes: Vec<String>,
}

impl RigCheck {
    /// Whether every part is ready.
    pub fn ready(&self) -> bool {
        self.items.iter().all(|i| i.ready)
    }

    fn push(&mut self, name: &'static str, ready: bool, detail: impl Into<String>) {
        self.items.push(RigCheckItem {
            name,
            ready,
            detail: detail.into(),
        });
    }
}

/// Longest wait of any rig check connection or read, s.
const CHECK_TIMEOUT_S: f64 = 5.0;

/// Checks, before anything moves, whether the rig is ready: the arm
/// (dashboard server: robot mode, PolyScope version, remote control), its
/// safety state, the state interface (RTDE or real-time: one state read,
/// no command sent), the camera (one frame grabbed and preprocessed) and
/// the sensor reference (pins found in that frame; with `model`, the
/// model's pins in the same order; else with `pins`, that many). Only a
/// bad rig file is an error.
pub fn rig_check(
    cfg: &HardwareConfig,
    model: Option<&StoredModel>,
    pins: Option<usize>,
) -> Result<RigCheck> {
    cfg.validate()?;
    let mut arm = cfg.arm.clone();
    arm.timeout_s = arm.timeout_s.min(CHECK_TIMEOUT_S);
    let mut check = RigCheck::default();
    let dashboard_safety = check_dashboard(&arm, &mut check);
    check_state(cfg, &arm, dashboard_safety, &mut check);
    let frame = match cfg.camera().and_then(|mut c| Ok(c.capture()?)) {
        Ok(frame) => {
            let detail = format!(
                "one frame grabbed and preprocessed ({} x {} px)",
                frame.width(),
                frame.height()
            );
            check.push("camera", true, detail);
            Some(frame)
        }
        Err(e) => {
            check.push("camera", false, format!("no frame: {e}"));
            None
        }
    };
    match frame {
        Some(frame) => check_reference(cfg, &frame, (model, pins), &mut check),
        None => check.push("reference", false, "not checked: no camera frame"),
    }
    Ok(check)
}

/// The dashboard rows; returns the safety status it read, if any.
fn check_dashboard(arm: &Ur5Config, check: &mut RigCheck) -> Option<String> {
    let timeout = std::time::Duration::from_secs_f64(arm.timeout_s);
    let mut d = match Dashboard::connect(&arm.host, arm.dashboard_port, timeout) {
        Ok(d) => d,
        Err(e) => {
            let detail = format!(
                "dashboard server {}:{} unreachable ({e}): is the controller on and the \
                 dashboard server enabled (Settings > Security > Services)?",
                arm.host, arm.dashboard_port
            );
            check.push("dashboard", false, detail);
            return None;
        }
    };
    let version = d.polyscope_version().ok();
    let mode = d.robot_mode();
    let remote = d.is_in_remote_control().ok().flatten();
    let mut detail = match &version {
        Some(v) => format!("PolyScope {}.{}", v.major, v.minor),
        None => "PolyScope version unknown".to_string(),
    };
    let running = matches!(&mode, Ok(m) if m == "RUNNING");
    match &mode {
        Ok(m) => detail.push_str(&format!(", robot mode {m}")),
        Err(e) => detail.push_str(&format!(", robot mode unreadable ({e})")),
    }
    if !running {
        detail.push_str(": power on and release the brakes on the pendant");
    }
    match remote {
        Some(true) => detail.push_str(", remote control"),
        Some(false) => {
            detail.push_str(", local control");
            check.notes.push(
                "the robot is in local control: if remote control is enabled on this \
                 PolyScope 5 robot (Settings > System > Remote Control), switch the pendant \
                 to remote control, or the URScript tactrace sends to port 30002 is refused"
                    .into(),
            );
        }
        None => {}
    }
    check.push("dashboard", running, detail);
    match d.safety_status() {
        Ok(status) => {
            let ready = matches!(status.as_str(), "NORMAL" | "REDUCED");
            let detail = match status.as_str() {
                "PROTECTIVE_STOP" => format!(
                    "{status}: remove its cause, then unlock it on the pendant (or, in \
                     remote control, send `unlock protective stop` to the dashboard)"
                ),
                s if !ready => format!("{s}: clear it on the pendant"),
                s => s.to_string(),
            };
            check.push("safety", ready, detail);
            Some(status)
        }
        Err(e) => {
            check.push("safety", false, format!("unreadable: {e}"));
            None
        }
    }
}

/// The state row: one state read without commanding; the safety row from
/// it when the dashboard could not give one.
fn check_state(
    cfg: &HardwareConfig,
    arm: &Ur5Config,
    dashboard_safety: Option<String>,
    check: &mut RigCheck,
) {
    let (interface, port) = match arm.state {
        StateInterface::Rtde => ("RTDE", arm.rtde_port),
        StateInterface::Realtime => ("real-time", arm.state_port),
    };
    let probe = match probe_state(arm) {
        Ok(p) => p,
        Err(e) => {
            let detail = format!("{interface} {}:{port}: {e}", arm.host);
            check.push("state", false, detail);
            if dashboard_safety.is_none() {
                check.push(
                    "safety",
                    false,
                    "unknown: neither dashboard nor state readable",
                );
            }
            return;
        }
    };
    // `+ 0.0` prints -0.0 as 0.0.
    let p = probe.tcp_work;
    let (rx, ry, rz) = (p.rx + 0.0, p.ry + 0.0, p.rz + 0.0);
    let start = cfg.start_pose();
    let away = ((p.x - start.x).powi(2) + (p.y - start.y).powi(2) + (p.z - start.z).powi(2)).sqrt();
    let controller = probe
        .controller
        .map(|v| format!(" (controller {}.{}.{})", v.major, v.minor, v.bugfix))
        .unwrap_or_default();
    let can_move = check_can_move(&probe.state);
    let mut detail = format!(
        "{interface}{controller}: tool at ({:.1}, {:.1}, {:.1}) mm, ({:.1}, {:.1}, {:.1}) deg \
         in the work frame, {away:.1} mm from the start",
        p.x, p.y, p.z, rx, ry, rz
    );
    if let Err(e) = &can_move {
        detail.push_str(&format!("; {e}"));
    }
    check.push("state", can_move.is_ok(), detail);
    if dashboard_safety.is_none() {
        let (name, halted) = safety_mode_name(probe.state.safety_mode);
        check.push("safety", !halted, format!("{name} (from the state stream)"));
    }
}

/// The reference row: pins in the frame, and the model's pins.
fn check_reference(
    cfg: &HardwareConfig,
    frame: &Frame,
    (model, expected): (Option<&StoredModel>, Option<usize>),
    check: &mut RigCheck,
) {
    let pins = match tactrace_vision::PinExtractor::from_reference_frame(frame, cfg.blob.clone()) {
        Ok(extractor) => extractor.tracker.reference().to_vec(),
        Err(e) => {
            let detail =
                format!("no usable reference frame ({e}): check the crop and the blob settings");
            check.push("reference", false, detail);
            return;
        }
    };
    let Some(model) = model else {
        let (ready, detail) = match expected {
            Some(n) if pins.len() == n => (true, format!("{n} pins found, as expected")),
            Some(n) => (
                false,
                format!(
                    "{} pins found, {n} expected: check the crop, the exposure and the \
                     blob settings",
                    pins.len()
                ),
            ),
            None => (
                !pins.is_empty(),
                format!(
                    "{} pins found (give --pins or --model to check the count)",
                    pins.len()
                ),
            ),
        };
        check.push("reference", ready, detail);
        return;
    };
    let model_pins = model.reference_pins().len();
    match model.for_pins(&pins, Path::new("the rig's reference frame")) {
        Ok(_) => check.push(
            "reference",
            true,
            format!("{} pins, in the order the model was trained on", pins.len()),
        ),
        Err(e) => check.push(
            "reference",
            false,
            format!("{} pins found, the model has {model_pins}: {e}", pins.len()),
        ),
    }
}
