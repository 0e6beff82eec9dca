//! [`Ur5Arm`]: a real UR5 behind the [`Arm`] trait, over plain TCP.
//!
//! Units and frames: poses handed in and out are the sensor tip in the work
//! frame, millimetres and degrees (extrinsic x-y-z), exactly as for
//! `SimArm`. The work frame is given as the base -> work transform
//! ([`Ur5Config::work_frame`]); the tool centre point as the flange -> tip
//! transform ([`Ur5Config::tcp`]). On the wire everything is metres and
//! rotation vectors in the robot base frame (see `script`).
//!
//! Blocking: [`Ur5Arm::connect`] blocks until both connections are open and
//! a first state packet arrived; [`Arm::move_to`] blocks until the measured
//! TCP pose is within tolerance of the target, the controller reports a
//! stop, the timeout passes or a stop is requested (then a `stopl` is
//! sent; see [`crate::StopFlag`]).
//!
//! Safety by types: the state is read only as a checked [`ArmState`], the
//! commanded pose is a [`FinitePose`], and each `movel` target is a
//! checked [`ToolPose`], so no NaN reaches the limiter or the controller.
use std::time::{Duration, Instant};

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};
use tactrace_arm::{Arm, ArmError, FinitePose};
use tactrace_geometry::Pose;

use super::link::{connect, CommandChannel, StateStream};
use super::realtime::check_can_move;
use super::script::{
    check_finite, movel_program, pose_error, pose_to_tool_vector, set_tcp_program, stopl_program,
    work_to_base,
};
use super::state::{ArmState, ToolPose};
use crate::{HwError, StopFlag, StopSignal};

/// Highest linear speed accepted, mm/s (a tactile rig never needs more).
pub const MAX_LINEAR_SPEED_MM_S: f64 = 250.0;
/// Highest linear acceleration accepted, mm/s^2.
pub const MAX_LINEAR_ACCEL_MM_S2: f64 = 2500.0;

/// Connection and motion settings of the UR5 driver.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ur5Config {
    /// Controller host name or IP address.
    pub host: String,
    /// URScript port (secondary interface), 30002.
    #[serde(default = "default_command_port")]
    pub command_port: u16,
    /// Where the arm's state is read: RTDE (default) or the real-time
    /// interface (the fallback for controllers without RTDE).
    #[serde(default)]
    pub state: StateInterface,
    /// Real-time state port, 30003 (used when `state = "realtime"`).
    #[serde(default = "default_state_port")]
    pub state_port: u16,
    /// RTDE port, 30004 (used when `state = "rtde"`).
    #[serde(default = "default_rtde_port")]
    pub rtde_port: u16,
    /// Dashboard server port, 29999 (`tactrace rig check`).
    #[serde(default = "default_dashboard_port")]
    pub dashboard_port: u16,
    /// Base -> work frame transform, mm and degrees.
    #[serde(default)]
    pub work_frame: Pose,
    /// Flange -> sensor tip (TCP) transform, mm and degrees.
    #[serde(default)]
    pub tcp: Pose,
    /// Linear speed of `movel`, mm/s (Bristol collection: 10).
    #[serde(default = "default_speed")]
    pub linear_speed_mm_s: f64,
    /// Linear acceleration of `movel`, mm/s^2.
    #[serde(default = "default_accel")]
    pub linear_accel_mm_s2: f64,
    /// Position tolerance for "target reached", mm.
    #[serde(default = "default_tolerance")]
    pub tolerance_mm: f64,
    /// Rotation tolerance for "target reached", degrees.
    #[serde(default = "default_tolerance")]
    pub tolerance_deg: f64,
    /// Longest wait for a connection, a first packet or a move, s.
    #[serde(default = "default_timeout")]
    pub timeout_s: f64,
}

fn default_command_port() -> u16 {
    30002
}
fn default_state_port() -> u16 {
    30003
}
fn default_rtde_port() -> u16 {
    30004
}
fn default_dashboard_port() -> u16 {
    super::dashboard::DASHBOARD_PORT
}

/// The controller interface the arm's state is read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StateInterface {
    /// RTDE, port 30004: named fields, protocol version 2 (CB3 3.4 and
    /// later, every e-series).
    #[default]
    Rtde,
    /// The real-time interface, port 30003: a fixed byte layout UR have
    /// deprecated since 3.5; kept as a fallback.
    Realtime,
}
fn default_speed() -> f64 {
    10.0
}
fn default_accel() -> f64 {
    100.0
}
fn default_tolerance() -> f64 {
    0.1
}
fn default_timeout() -> f64 {
    60.0
}

impl Ur5Config {
    /// Defaults for everything but the host.
    pub fn new(host: impl Into<String>) -> Self {
        Self {
            host: host.into(),
            command_port: default_command_port(),
            state: StateInterface::default(),
            state_port: default_state_port(),
            rtde_port: default_rtde_port(),
            dashboard_port: default_dashboard_port(),
            work_frame: Pose::default(),
            tcp: Pose::default(),
            linear_speed_mm_s: default_speed(),
            linear_accel_mm_s2: default_accel(),
            tolerance_mm: default_tolerance(),
            tolerance_deg: default_tolerance(),
            timeout_s: default_timeout(),
        }
    }

    /// Checks ranges: positive finite speeds, tolerances and timeout,
    /// speeds under the caps, finite frames, a host.
    pub fn validate(&self) -> Result<(), HwError> {
        if self.host.trim().is_empty() {
            return Err(config_err("host", "empty"));
        }
        check_range(
            "linear_speed_mm_s",
            self.linear_speed_mm_s,
            MAX_LINEAR_SPEED_MM_S,
        )?;
        check_range(
            "linear_accel_mm_s2",
            self.linear_accel_mm_s2,
            MAX_LINEAR_ACCEL_MM_S2,
        )?;
        check_range("tolerance_mm", self.tolerance_mm, 10.0)?;
        check_range("tolerance_deg", self.tolerance_deg, 10.0)?;
        check_range("timeout_s", self.timeout_s, 3600.0)?;
        check_frame("work_frame", self.work_frame)?;
        check_frame("tcp", self.tcp)
    }

    fn timeout(&self) -> Duration {
        Duration::from_secs_f64(self.timeout_s)
    }
}

fn config_err(field: &'static str, reason: &str) -> HwError {
    HwError::Config {
        field,
        reason: reason.to_string(),
    }
}

/// Largest offset of a configured frame (the work frame from the base,
/// the TCP from the flange), mm: far beyond any UR arm's reach.
const MAX_FRAME_OFFSET_MM: f64 = 10_000.0;

/// A frame of the configuration: finite, offsets within
/// [`MAX_FRAME_OFFSET_MM`], angles within +-360 degrees (so every pose
/// measured through it is finite).
fn check_frame(field: &'static str, pose: Pose) -> Result<(), HwError> {
    check_finite(pose).map_err(|e| config_err(field, &e.to_string()))?;
    let near = [pose.x, pose.y, pose.z]
        .iter()
        .all(|v| v.abs() <= MAX_FRAME_OFFSET_MM);
    let turns = [pose.rx, pose.ry, pose.rz].iter().all(|v| v.abs() <= 360.0);
    if near && turns {
        Ok(())
    } else {
        Err(config_err(
            field,
            &format!(
                "offsets must be within +-{MAX_FRAME_OFFSET_MM} mm and angles within +-360 deg"
            ),
        ))
    }
}

fn check_range(field: &'static str, value: f64, max: f64) -> Result<(), HwError> {
    if value.is_finite() && value > 0.0 && value <= max {
        Ok(())
    } else {
        Err(config_err(field, &format!("{value} is not in (0, {max}]")))
    }
}

/// A UR5 (CB3 or e-series) driven by URScript `movel` over TCP.
pub struct Ur5Arm {
    config: Ur5Config,
    commands: CommandChannel,
    states: StateStream,
    commanded: FinitePose,
    stop: StopFlag,
    /// A `stopl` was sent after the last `movel`.
    halted: bool,
}

/// Longest single wait on the state stream before the stop flag is
/// looked at again.
const STOP_POLL: Duration = Duration::from_millis(20);

/// The next state after `after`, waiting up to `timeout` in slices of
/// [`STOP_POLL`]; [`HwError::Interrupted`] as soon as `stop` is set.
fn wait_state(
    states: &StateStream,
    stop: &StopFlag,
    after: u64,
    timeout: Duration,
) -> Result<(u64, ArmState), HwError> {
    let deadline = Instant::now() + timeout;
    loop {
        if let Some(signal) = stop.requested() {
            return Err(HwError::Interrupted { signal });
        }
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(HwError::NoState {
                seconds: timeout.as_secs_f64(),
            });
        }
        match states.wait_newer(after, left.min(STOP_POLL)) {
            Err(HwError::NoState { .. }) => {}
            found => return found,
        }
    }
}

impl Ur5Arm {
    /// Connects to the controller, sets the TCP and reads the current pose.
    /// Blocks up to `timeout_s` for each connection and the first packet.
    pub fn connect(config: Ur5Config) -> Result<Self, HwError> {
        Self::connect_stoppable(config, StopFlag::new())
    }

    /// As [`Ur5Arm::connect`], with waits that end when `stop` is set: a
    /// move then sends `stopl` and returns [`HwError::Interrupted`].
    pub fn connect_stoppable(config: Ur5Config, stop: StopFlag) -> Result<Self, HwError> {
        config.validate()?;
        stop.check_idle()?;
        let timeout = config.timeout();
        let command_stream = connect(&config.host, config.command_port, timeout)?;
        let states = match config.state {
            StateInterface::Rtde => {
                StateStream::start_rtde(connect(&config.host, config.rtde_port, timeout)?, timeout)?
            }
            StateInterface::Realtime => {
                StateStream::start(connect(&config.host, config.state_port, timeout)?)?
            }
        };
        let mut commands = CommandChannel::start(command_stream)?;
        commands.send(&set_tcp_program(pose_to_tool_vector(config.tcp)))?;
        let (_, state) = wait_state(&states, &stop, 0, timeout).inspect_err(|_| {
            if stop.requested().is_some() {
                stop.mark_halted();
            }
        })?;
        let commanded = state.tool_actual().in_work_frame(config.work_frame)?;
        Ok(Self {
            config,
            commands,
            states,
            commanded,
            stop,
            halted: false,
        })
    }

    /// The settings in use.
    pub fn config(&self) -> &Ur5Config {
        &self.config
    }

    /// The stop flag this arm's waits poll.
    pub fn stop_flag(&self) -> &StopFlag {
        &self.stop
    }

    /// The newest measured TCP pose in the work frame (mm, deg). Does not
    /// block once a packet has arrived (the reader thread keeps the newest);
    /// fails if the state stream has failed.
    pub fn actual_pose(&self) -> Result<Pose, HwError> {
        let state = self.fresh_state()?;
        Ok(state
            .tool_actual()
            .in_work_frame(self.config.work_frame)?
            .pose())
    }

    /// The newest controller state, checked; blocks like
    /// [`Ur5Arm::actual_pose`].
    pub fn fresh_state(&self) -> Result<ArmState, HwError> {
        let after = self.states.seq().saturating_sub(1);
        wait_state(&self.states, &self.stop, after, self.config.timeout()).map(|(_, s)| s)
    }

    /// Sends `stopl` now (unless one was sent since the last `movel`);
    /// after a stop request, marks the flag halted once it is sent.
    pub fn halt(&mut self) -> Result<(), HwError> {
        if !self.halted {
            self.commands
                .send(&stopl_program(self.config.linear_accel_mm_s2 / 1000.0))?;
            self.halted = true;
        }
        if self.stop.requested().is_some() {
            self.stop.mark_halted();
        }
        Ok(())
    }

    /// The error of a move stopped by `signal`, after halting the arm.
    fn interrupted(&mut self, signal: StopSignal) -> HwError {
        match self.halt() {
            Ok(()) => HwError::Interrupted { signal },
            Err(e) => HwError::StopFailed {
                signal,
                source: Box::new(e),
            },
        }
    }

    /// Sends `movel` to the base-frame target and waits for arrival.
    fn move_blocking(&mut self, pose: FinitePose) -> Result<(), HwError> {
        if let Some(signal) = self.stop.requested() {
            return Err(self.interrupted(signal));
        }
        let result = self.send_move(pose);
        match result {
            Ok(()) => {
                self.commanded = pose;
                Ok(())
            }
            Err(HwError::Interrupted { signal }) => Err(self.interrupted(signal)),
            Err(e) => {
                // Best effort: stop a move that is still going.
                let _ = self.halt();
                Err(e)
            }
        }
    }

    /// Checks the state, writes the `movel` and waits for arrival.
    fn send_move(&mut self, pose: FinitePose) -> Result<(), HwError> {
        let state = self.fresh_state()?;
        check_can_move(&state)?;
        let base = work_to_base(self.config.work_frame, *pose);
        let target = ToolPose::from_isometry(&base, "commanded target")?;
        let program = movel_program(
            &target,
            pose_to_tool_vector(self.config.tcp),
            self.config.linear_accel_mm_s2 / 1000.0,
            self.config.linear_speed_mm_s / 1000.0,
        );
        self.halted = false;
        self.commands.send(&program)?;
        self.wait_arrival(&target.isometry(), *pose)
    }

    /// Polls the state stream until the TCP is within tolerance of `target`.
    fn wait_arrival(&self, target: &Isometry3<f64>, pose: Pose) -> Result<(), HwError> {
        let timeout = self.config.timeout();
        let start = Instant::now();
        let mut seq = self.states.seq();
        let mut errors = (f64::INFINITY, f64::INFINITY);
        loop {
            let remaining = timeout.saturating_sub(start.elapsed());
            if remaining.is_zero() {
                return Err(HwError::MoveTimeout {
                    seconds: self.config.timeout_s,
                    target: pose.to_string(),
                    position_error_mm: errors.0,
                    rotation_error_deg: errors.1,
                });
            }
            let (next, state) = match wait_state(&self.states, &self.stop, seq, remaining) {
                Ok(found) => found,
                Err(HwError::NoState { .. }) => continue,
                Err(e) => return Err(e),
            };
            seq = next;
            check_can_move(&state)?;
            errors = pose_error(&state.tool_actual().isometry(), target);
            if errors.0 <= self.config.tolerance_mm && errors.1 <= self.config.tolerance_deg {
                return Ok(());
            }
        }
    }
}

impl Arm for Ur5Arm {
    /// Linear move of the sensor tip to `pose` (work frame, mm/deg) at the
    /// configured speed. Blocks until the measured pose is within
    /// tolerance; on timeout, a safety stop or a stop request, sends
    /// `stopl` and returns `ArmError::Hardware` (the timeout message
    /// starts with "timeout"; a stop request is `HwError::Interrupted`).
    fn move_to(&mut self, pose: Pose) -> Result<(), ArmError> {
        let pose = FinitePose::new(pose)?;
        self.move_blocking(pose).map_err(ArmError::from)
    }

    /// The last target reached (within tolerance), or the measured pose at
    /// connection before any move; does not block.
    fn pose(&self) -> Pose {
        self.commanded.pose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_defaults_from_host_only() {
        let config: Ur5Config = serde_json::from_str(r#"{"host": "192.168.1.10"}"#).unwrap();
        assert_eq!(config, Ur5Config::new("192.168.1.10"));
        assert_eq!((config.command_port, config.state_port), (30002, 30003));
        assert_eq!(
            (config.state, config.rtde_port),
            (StateInterface::Rtde, 30004)
        );
        let fallback: Ur5Config =
            serde_json::from_str(r#"{"host": "h", "state": "realtime"}"#).unwrap();
        assert_eq!(fallback.state, StateInterface::Realtime);
        assert!(serde_json::from_str::<Ur5Config>(r#"{"host": "h", "state": "rt"}"#).is_err());
        assert_eq!(config.linear_speed_mm_s, 10.0);
        assert!(config.validate().is_ok());
    }

    #[test]
    fn config_rejects_unknown_fields_and_bad_ranges() {
        let unknown = serde_json::from_str::<Ur5Config>(r#"{"host": "h", "speed": 3}"#);
        assert!(unknown.is_err());
        let mut config = Ur5Config::new("h");
        config.linear_speed_mm_s = 1000.0;
        assert!(matches!(
            config.validate(),
            Err(HwError::Config {
                field: "linear_speed_mm_s",
                ..
            })
        ));
        config.linear_speed_mm_s = 10.0;
        config.tolerance_mm = f64::NAN;
        assert!(config.validate().is_err());
        config.tolerance_mm = 0.1;
        config.tcp.z = f64::INFINITY;
        assert!(matches!(
            config.validate(),
            Err(HwError::Config { field: "tcp", .. })
        ));
    }
}
