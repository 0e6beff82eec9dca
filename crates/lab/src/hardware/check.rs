//! `tactrace rig check`: is the rig ready before anything moves? The
//! dashboard (robot mode, version, remote control), the safety state, one
//! state read without commanding (checked as the driver checks it, and the
//! move to the start judged by the same limiter rule `follow` applies),
//! the camera and the sensor reference.
use super::HardwareConfig;
use crate::error::Result;
use std::path::Path;
use tactrace_arm::FinitePose;
use tactrace_hw::ur5::realtime::{check_can_move, safety_mode_name};
use tactrace_hw::{probe_state, Dashboard, StateInterface, Ur5Config};
use tactrace_sensor::Frame;
use tactrace_store::StoredModel;

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
    let detect = cfg.sight()?.detect.check()?;
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
        Some(frame) => check_reference(&detect, &frame, (model, pins), &mut check),
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
    let away = p.distance(start);
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
    // The rule `follow` applies to its first move, from here to the start.
    let reach = FinitePose::new(start).and_then(|s| cfg.workspace.check_move(p, s));
    if let Err(e) = &reach {
        detail.push_str(&format!(
            "; follow would refuse the move to the start ({e}): jog the arm to within \
             {} mm and {} deg of it",
            cfg.workspace.max_step_mm, cfg.workspace.max_step_deg
        ));
    }
    check.push("state", can_move.is_ok() && reach.is_ok(), detail);
    if dashboard_safety.is_none() {
        let (name, halted) = safety_mode_name(probe.state.safety_mode);
        check.push("safety", !halted, format!("{name} (from the state stream)"));
    }
}

/// The reference row: pins in the frame, and the model's pins.
fn check_reference(
    detect: &tactrace_vision::Detector,
    frame: &Frame,
    (model, expected): (Option<&StoredModel>, Option<usize>),
    check: &mut RigCheck,
) {
    let pins = match tactrace_vision::PinExtractor::with_detector(frame, detect.clone()) {
        Ok(extractor) => extractor.tracker.reference().to_vec(),
        Err(e) => {
            let detail = format!(
                "no usable reference frame ({e}): check the crop and the detector settings"
            );
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
                     detector settings",
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
