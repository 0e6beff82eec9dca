//! A fake UR controller on the loopback interface, for tests without a robot.
//!
//! It listens on two ephemeral ports of 127.0.0.1 (command and state),
//! accepts one client on each, reads URScript lines, takes the target of
//! each `movel(p[...]` and streams the state, whose actual TCP pose moves
//! towards that target at a fixed speed: as real-time packets (CB3 3.5
//! layout) or, with [`StateInterface::Rtde`], as RTDE data packages of
//! the recipe the client sets up (the same [`RtdeSession`] the standalone
//! fake RTDE server uses). Every
//! loop is bounded: the server stops by itself after `lifetime`, when a
//! client leaves, or when dropped. Behaviours cover the failure paths a
//! driver must survive (a frozen arm, a malformed packet, a protective
//! stop, from the first move, the one to the start, or later); a
//! [`FakeStateFault`] makes the state report an impossible tool pose (far
//! beyond reach, a huge rotation, NaN), and `text_flood` floods an RTDE
//! client with text messages. Every URScript line received is kept
//! ([`FakeUrController::received_lines`]), so a test can check that no
//! `movel` was sent, or that a `stopl` was.
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use nalgebra::Isometry3;

use super::arm::{StateInterface, Ur5Config};
use super::realtime::{encode_packet, RobotState, SAFETY_MODE_NORMAL};
use super::rtde::{resting_state, FakeRtdeOptions, RtdeSession};
use super::script::{
    find_movel_target, isometry_to_tool_vector, pose_error, tool_vector_to_isometry,
};
use crate::HwError;

/// What the fake does when it receives a `movel`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FakeBehaviour {
    /// Move towards the target (the normal case).
    Follow,
    /// Never move: the driver must time out.
    IgnoreMoves,
    /// Send a packet with an impossible length: the driver must fail cleanly.
    MalformedOnMove,
    /// Switch to safety mode 3 (protective stop) without moving.
    ProtectiveStopOnMove,
    /// Close both connections (a cable pulled, a controller reboot).
    DisconnectOnMove,
}

/// An impossible tool pose the fake's state reports instead of the truth
/// (actual and target TCP pose alike).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FakeStateFault {
    /// The true pose (the normal case).
    #[default]
    None,
    /// The tool 1e306 m from the base.
    HugePosition,
    /// A rotation vector of 1e200 rad.
    HugeRotation,
    /// NaN in the position.
    NotFinite,
}

impl FakeStateFault {
    /// The tool vector sent instead of `truth`.
    fn tool_vector(self, truth: [f64; 6]) -> [f64; 6] {
        let [x, y, z, rx, ry, rz] = truth;
        match self {
            Self::None => truth,
            Self::HugePosition => [1e306, y, z, rx, ry, rz],
            Self::HugeRotation => [x, y, z, 1e200, ry, rz],
            Self::NotFinite => [f64::NAN, y, z, rx, ry, rz],
        }
    }
}

/// Settings of the fake controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FakeUrOptions {
    /// Initial TCP pose in the base frame (m, rotation vector rad).
    pub start: [f64; 6],
    /// Linear speed of the simulated TCP, mm/s.
    pub speed_mm_s: f64,
    /// Angular speed of the simulated TCP, deg/s.
    pub speed_deg_s: f64,
    /// Packet period (8 ms = 125 Hz like a CB3).
    pub period: Duration,
    /// The server stops by itself after this long.
    pub lifetime: Duration,
    /// Reaction to `movel`.
    pub behaviour: FakeBehaviour,
    /// This many `movel` are followed normally before `behaviour` takes
    /// effect (0: from the first): a fault in the middle of a run.
    pub normal_moves: usize,
    /// The state interface served (default: the real-time one).
    pub state: StateInterface,
    /// What the state says about the tool (default: the truth).
    pub state_fault: FakeStateFault,
    /// RTDE only: this many text messages are sent every period, a
    /// flooding controller (default 0).
    pub text_flood: usize,
}

impl Default for FakeUrOptions {
    fn default() -> Self {
        Self {
            start: [0.4, 0.0, 0.3, std::f64::consts::PI, 0.0, 0.0],
            speed_mm_s: 400.0,
            speed_deg_s: 180.0,
            period: Duration::from_millis(8),
            lifetime: Duration::from_secs(20),
            behaviour: FakeBehaviour::Follow,
            normal_moves: 0,
            state: StateInterface::Realtime,
            state_fault: FakeStateFault::None,
            text_flood: 0,
        }
    }
}

/// A running fake controller; stops and joins its thread on drop.
pub struct FakeUrController {
    command_port: u16,
    state_port: u16,
    state: StateInterface,
    lines: Arc<Mutex<Vec<String>>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeUrController {
    /// Binds two loopback ports and starts serving in a thread.
    pub fn start(options: FakeUrOptions) -> Result<Self, HwError> {
        let io_err = |source| HwError::Io {
            what: "fake controller".into(),
            source,
        };
        let command = TcpListener::bind("127.0.0.1:0").map_err(io_err)?;
        let state = TcpListener::bind("127.0.0.1:0").map_err(io_err)?;
        let command_port = command.local_addr().map_err(io_err)?.port();
        let state_port = state.local_addr().map_err(io_err)?.port();
        let lines = Arc::new(Mutex::new(Vec::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let server = Server {
            options,
            lines: lines.clone(),
            stop: stop.clone(),
            deadline: Instant::now() + options.lifetime,
        };
        let thread = std::thread::spawn(move || server.run(command, state));
        Ok(Self {
            command_port,
            state_port,
            state: options.state,
            lines,
            stop,
            thread: Some(thread),
        })
    }

    /// A driver configuration pointing at this fake (127.0.0.1).
    pub fn config(&self) -> Ur5Config {
        let mut config = Ur5Config::new("127.0.0.1");
        config.command_port = self.command_port;
        config.state = self.state;
        match self.state {
            StateInterface::Rtde => config.rtde_port = self.state_port,
            StateInterface::Realtime => config.state_port = self.state_port,
        }
        config
    }

    /// Every URScript line received so far.
    pub fn received_lines(&self) -> Vec<String> {
        self.lines.lock().map(|l| l.clone()).unwrap_or_default()
    }

    /// Whether the server has stopped (its client left, its lifetime
    /// passed, or a connection failed); once the client has left, every
    /// line it sent is in [`FakeUrController::received_lines`].
    pub fn finished(&self) -> bool {
        self.thread.as_ref().is_none_or(|t| t.is_finished())
    }
}

impl Drop for FakeUrController {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

struct Server {
    options: FakeUrOptions,
    lines: Arc<Mutex<Vec<String>>>,
    stop: Arc<AtomicBool>,
    deadline: Instant,
}

/// The simulated robot: where the TCP is and where it is going.
struct Motion {
    current: Isometry3<f64>,
    target: Option<Isometry3<f64>>,
    safety_mode: i32,
    malformed: bool,
    disconnected: bool,
    /// `movel` received so far.
    moves: usize,
}

impl Server {
    fn should_stop(&self) -> bool {
        self.stop.load(Ordering::Relaxed) || Instant::now() >= self.deadline
    }

    /// Serves the state connection once it comes, and the command
    /// connection whenever it comes (a state-only client such as
    /// `probe_state` never opens one).
    fn run(self, commands: TcpListener, state: TcpListener) {
        let Some(state) = self.accept(&state) else {
            return;
        };
        if commands.set_nonblocking(true).is_err() {
            return;
        }
        let mut command: Option<TcpStream> = None;
        let mut out = match self.options.state {
            StateInterface::Realtime => StateOut::Realtime(state),
            StateInterface::Rtde => {
                let version = FakeRtdeOptions::default().version;
                match RtdeSession::new(state, version, None) {
                    Ok(session) => StateOut::Rtde(Box::new(session)),
                    Err(_) => return,
                }
            }
        };
        let mut motion = Motion {
            current: tool_vector_to_isometry(self.options.start),
            target: None,
            safety_mode: SAFETY_MODE_NORMAL,
            malformed: false,
            disconnected: false,
            moves: 0,
        };
        let mut pending = String::new();
        let start = Instant::now();
        while !self.should_stop() {
            if command.is_none() {
                command = commands
                    .accept()
                    .ok()
                    .and_then(|(c, _)| c.set_nonblocking(true).ok().map(|()| c));
            }
            if let Some(stream) = command.as_mut() {
                if !self.read_commands(stream, &mut pending, &mut motion) {
                    return;
                }
            }
            if motion.disconnected {
                return;
            }
            let moving = self.step(&mut motion);
            let state = self.state(&motion, moving, start.elapsed().as_secs_f64());
            if !out.send(&state, motion.malformed, self.options.text_flood) {
                return;
            }
            std::thread::sleep(self.options.period);
        }
    }

    fn accept(&self, listener: &TcpListener) -> Option<TcpStream> {
        listener.set_nonblocking(true).ok()?;
        while !self.should_stop() {
            match listener.accept() {
                Ok((stream, _)) => {
                    stream.set_nonblocking(false).ok()?;
                    return Some(stream);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {
                    std::thread::sleep(Duration::from_millis(2));
                }
                Err(_) => return None,
            }
        }
        None
    }

    /// Reads whatever URScript arrived; false when the client has gone.
    fn read_commands(
        &self,
        stream: &mut TcpStream,
        pending: &mut String,
        motion: &mut Motion,
    ) -> bool {
        let mut chunk = [0u8; 4096];
        let open = loop {
            match stream.read(&mut chunk) {
                Ok(0) => break false,
                Ok(n) => pending.push_str(&String::from_utf8_lossy(&chunk[..n])),
                Err(e) if e.kind() == ErrorKind::WouldBlock => break true,
                Err(_) => break false,
            }
        };
        // Lines that came just before the client left count too.
        while let Some(end) = pending.find('\n') {
            let line: String = pending.drain(..=end).collect();
            self.handle_line(line.trim_end(), motion);
        }
        open
    }

    fn handle_line(&self, line: &str, motion: &mut Motion) {
        if let Ok(mut lines) = self.lines.lock() {
            lines.push(line.to_string());
        }
        if line.contains("stopl(") {
            motion.target = None;
        }
        let Some(target) = find_movel_target(line) else {
            return;
        };
        motion.moves += 1;
        let behaviour = if motion.moves <= self.options.normal_moves {
            FakeBehaviour::Follow
        } else {
            self.options.behaviour
        };
        match behaviour {
            FakeBehaviour::Follow => motion.target = Some(tool_vector_to_isometry(target)),
            FakeBehaviour::IgnoreMoves => {}
            FakeBehaviour::MalformedOnMove => motion.malformed = true,
            FakeBehaviour::ProtectiveStopOnMove => motion.safety_mode = 3,
            FakeBehaviour::DisconnectOnMove => motion.disconnected = true,
        }
    }

    /// Advances the TCP one period towards the target; true while moving.
    fn step(&self, motion: &mut Motion) -> bool {
        let Some(target) = motion.target else {
            return false;
        };
        let dt = self.options.period.as_secs_f64();
        let (dp, dr) = pose_error(&motion.current, &target);
        let steps = (dp / (self.options.speed_mm_s * dt)).max(dr / (self.options.speed_deg_s * dt));
        if steps <= 1.0 {
            motion.current = target;
            motion.target = None;
            return true;
        }
        let fraction = 1.0 / steps;
        let rotation = motion
            .current
            .rotation
            .try_slerp(&target.rotation, fraction, 1e-9)
            .unwrap_or(target.rotation);
        let translation = motion
            .current
            .translation
            .vector
            .lerp(&target.translation.vector, fraction);
        motion.current = Isometry3::from_parts(translation.into(), rotation);
        true
    }

    fn state(&self, motion: &Motion, moving: bool, time_s: f64) -> RobotState {
        let speed = if moving {
            self.options.speed_mm_s / 1000.0
        } else {
            0.0
        };
        let truth = isometry_to_tool_vector(&motion.current);
        let target = motion.target.map_or(truth, |t| isometry_to_tool_vector(&t));
        let fault = self.options.state_fault;
        let (tool, target) = (fault.tool_vector(truth), fault.tool_vector(target));
        RobotState {
            time_s,
            tool_actual: tool,
            tcp_speed: [speed, 0.0, 0.0, 0.0, 0.0, 0.0],
            tool_target: target,
            safety_mode: motion.safety_mode,
            program_state: Some(if moving { 2 } else { 1 }),
            ..resting_state()
        }
    }
}

/// Where the fake's state goes.
enum StateOut {
    Realtime(TcpStream),
    Rtde(Box<RtdeSession>),
}

impl StateOut {
    /// Sends one state (or a malformed packet), after `flood` text
    /// messages over RTDE; false once the client has gone.
    fn send(&mut self, state: &RobotState, malformed: bool, flood: usize) -> bool {
        match self {
            Self::Realtime(stream) => {
                let packet = if malformed {
                    // Declares 12 bytes: far below any real packet.
                    let mut bad = 12i32.to_be_bytes().to_vec();
                    bad.extend_from_slice(&[0u8; 8]);
                    bad
                } else {
                    encode_packet(state)
                };
                stream.write_all(&packet).is_ok()
            }
            Self::Rtde(session) => {
                if !session.poll() {
                    return false;
                }
                if flood > 0 && session.streaming() && session.send_text_flood(flood).is_err() {
                    return false;
                }
                if malformed && session.streaming() {
                    // A data package of recipe 1 holding 2 bytes.
                    return session.send_raw(&[0, 6, b'U', 1, 0, 0]).is_ok();
                }
                session.send_state(state).is_ok()
            }
        }
    }
}
