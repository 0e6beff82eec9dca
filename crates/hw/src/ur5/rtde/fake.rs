//! A fake RTDE controller: the server side of the protocol, for tests.
//!
//! [`RtdeSession`] serves one client on a connected socket without
//! blocking: it answers version, setup, start and pause requests, keeps
//! the input values it receives, and sends the current [`RobotState`] as
//! output data packages while started. [`FakeRtdeServer`] runs sessions in
//! a thread on 127.0.0.1 (an ephemeral port, or a given one such as 30004
//! for clients that hard-code it), one client after the other, with a
//! state the test sets. Every loop is bounded by a stop flag and a
//! lifetime.
//!
//! Behaviour matching real controllers that independent clients rely on:
//! empty names in a setup request (the trailing comma `ur_rtde` sends) are
//! ignored rather than answered `NOT_FOUND`; a recipe with an unknown
//! field is answered with recipe id 0 and `NOT_FOUND` in that field's
//! place.
use std::collections::BTreeMap;
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::client::ControllerVersion;
use super::protocol::{
    decode_values, encode_data, input_field_type, output_field_type, take_package, FieldType,
    Package, PackageType, TextMessage, Value,
};
use crate::ur5::realtime::{RobotState, ROBOT_MODE_RUNNING, SAFETY_MODE_NORMAL};
use crate::HwError;

/// The server side of one RTDE connection.
pub struct RtdeSession {
    stream: TcpStream,
    buffer: Vec<u8>,
    version: ControllerVersion,
    outputs: Option<Vec<(String, FieldType)>>,
    inputs: BTreeMap<u8, Vec<(String, FieldType)>>,
    received: BTreeMap<String, Value>,
    streaming: bool,
    greeting: Option<String>,
    flood_at_start: usize,
}

impl RtdeSession {
    /// Serves `stream` as a controller of `version`; `greeting`, if given,
    /// is sent as a text message just before the reply to start.
    pub fn new(
        stream: TcpStream,
        version: ControllerVersion,
        greeting: Option<String>,
    ) -> std::io::Result<Self> {
        stream.set_nonblocking(true)?;
        let _ = stream.set_nodelay(true);
        Ok(Self {
            stream,
            buffer: Vec::new(),
            version,
            outputs: None,
            inputs: BTreeMap::new(),
            received: BTreeMap::new(),
            streaming: false,
            greeting,
            flood_at_start: 0,
        })
    }

    /// Also sends `count` text messages (a flooding controller) with the
    /// greeting, before the reply to start.
    pub fn with_text_flood(mut self, count: usize) -> Self {
        self.flood_at_start = count;
        self
    }

    /// Sends `count` text messages of 255 characters now.
    pub fn send_text_flood(&mut self, count: usize) -> std::io::Result<()> {
        let message = TextMessage {
            message: "x".repeat(255),
            source: "fake RTDE flood".into(),
            level: 3,
        }
        .encode()
        .encode();
        let batch = 64.min(count.max(1));
        let bytes: Vec<u8> = message.repeat(batch);
        let mut sent = 0;
        while sent < count {
            let n = batch.min(count - sent);
            write_all_nonblocking(&mut self.stream, &bytes[..n * message.len()])?;
            sent += n;
        }
        Ok(())
    }

    /// Whether the client has started the output stream.
    pub fn streaming(&self) -> bool {
        self.streaming
    }

    /// Input values received so far, by field name.
    pub fn received_inputs(&self) -> &BTreeMap<String, Value> {
        &self.received
    }

    /// Reads and answers whatever arrived; false once the client has gone
    /// or broke the protocol.
    pub fn poll(&mut self) -> bool {
        let mut chunk = [0u8; 4096];
        loop {
            match self.stream.read(&mut chunk) {
                Ok(0) => return false,
                Ok(n) => self.buffer.extend_from_slice(&chunk[..n]),
                Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => return false,
            }
        }
        loop {
            match take_package(&mut self.buffer) {
                Ok(Some(package)) => {
                    if self.handle(package).is_err() {
                        return false;
                    }
                }
                Ok(None) => return true,
                Err(_) => return false,
            }
        }
    }

    /// Sends `state` as an output data package while streaming.
    pub fn send_state(&mut self, state: &RobotState) -> std::io::Result<()> {
        let Some(outputs) = &self.outputs else {
            return Ok(());
        };
        if !self.streaming {
            return Ok(());
        }
        let values: Vec<Value> = outputs
            .iter()
            .map(|(name, kind)| output_value(name, *kind, state))
            .collect();
        self.write(&encode_data(1, &values))
    }

    /// Sends raw bytes (a test's malformed package).
    pub fn send_raw(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        write_all_nonblocking(&mut self.stream, bytes)
    }

    fn write(&mut self, package: &Package) -> std::io::Result<()> {
        write_all_nonblocking(&mut self.stream, &package.encode())
    }

    fn handle(&mut self, package: Package) -> std::io::Result<()> {
        let Some(kind) = package.package_type() else {
            return Ok(());
        };
        let reply = match kind {
            PackageType::RequestProtocolVersion => {
                let asked = package
                    .payload
                    .get(..2)
                    .map(|b| u16::from_be_bytes([b[0], b[1]]));
                vec![u8::from(matches!(asked, Some(1 | 2)))]
            }
            PackageType::GetUrControlVersion => {
                let v = self.version;
                [v.major, v.minor, v.bugfix, v.build]
                    .iter()
                    .flat_map(|w| w.to_be_bytes())
                    .collect()
            }
            PackageType::SetupOutputs => self.setup_outputs(&package.payload),
            PackageType::SetupInputs => self.setup_inputs(&package.payload),
            PackageType::Start => {
                if let Some(text) = self.greeting.take() {
                    let message = TextMessage {
                        message: text,
                        source: "fake RTDE".into(),
                        level: 3,
                    };
                    self.write(&message.encode())?;
                }
                let flood = std::mem::take(&mut self.flood_at_start);
                if flood > 0 {
                    self.send_text_flood(flood)?;
                }
                self.streaming = self.outputs.is_some() || !self.inputs.is_empty();
                vec![u8::from(self.streaming)]
            }
            PackageType::Pause => {
                self.streaming = false;
                vec![1]
            }
            PackageType::DataPackage => {
                self.take_inputs(&package.payload);
                return Ok(());
            }
            PackageType::TextMessage => return Ok(()),
        };
        self.write(&Package::new(kind, reply))
    }

    fn setup_outputs(&mut self, payload: &[u8]) -> Vec<u8> {
        let names = payload.get(8..).unwrap_or_default();
        let (fields, reply) = recipe_reply(names, output_field_type);
        let accepted = fields.is_some();
        self.outputs = fields.or(self.outputs.take());
        with_id(u8::from(accepted), reply)
    }

    fn setup_inputs(&mut self, payload: &[u8]) -> Vec<u8> {
        let (fields, reply) = recipe_reply(payload, input_field_type);
        let id = match fields {
            Some(fields) => {
                let id = self.inputs.len() as u8 + 1;
                self.inputs.insert(id, fields);
                id
            }
            None => 0,
        };
        with_id(id, reply)
    }

    fn take_inputs(&mut self, payload: &[u8]) {
        let Some((id, bytes)) = payload.split_first() else {
            return;
        };
        let Some(fields) = self.inputs.get(id) else {
            return;
        };
        let types: Vec<_> = fields.iter().map(|(_, t)| *t).collect();
        if let Ok(values) = decode_values(&types, bytes) {
            for ((name, _), value) in fields.iter().zip(values) {
                self.received.insert(name.clone(), value);
            }
        }
    }
}

fn with_id(id: u8, types: String) -> Vec<u8> {
    let mut out = vec![id];
    out.extend_from_slice(types.as_bytes());
    out
}

/// The typed fields of a setup request (`None` when a name is unknown)
/// and the reply's type list. Empty names are skipped.
type Fields = Vec<(String, FieldType)>;
fn recipe_reply(names: &[u8], lookup: fn(&str) -> Option<FieldType>) -> (Option<Fields>, String) {
    let text = String::from_utf8_lossy(names);
    let mut fields = Vec::new();
    let mut types = Vec::new();
    let mut all_known = true;
    for name in text.split(',').filter(|n| !n.is_empty()) {
        match lookup(name) {
            Some(kind) => {
                fields.push((name.to_string(), kind));
                types.push(kind.name());
            }
            None => {
                all_known = false;
                types.push("NOT_FOUND");
            }
        }
    }
    let fields = (all_known && !fields.is_empty()).then_some(fields);
    (fields, types.join(","))
}

/// The value the fake sends for an output field: the modelled fields from
/// `state`, a plausible constant for a few status fields, zero otherwise.
fn output_value(name: &str, kind: FieldType, state: &RobotState) -> Value {
    match name {
        "timestamp" => Value::Double(state.time_s),
        "actual_q" | "target_q" => Value::Vector6d(state.joints_rad),
        "actual_TCP_pose" => Value::Vector6d(state.tool_actual),
        "actual_TCP_speed" | "target_TCP_speed" => Value::Vector6d(state.tcp_speed),
        "target_TCP_pose" => Value::Vector6d(state.tool_target),
        "robot_mode" => Value::Int32(state.robot_mode),
        "safety_mode" | "safety_status" => Value::Int32(state.safety_mode),
        "runtime_state" => Value::Uint32(state.program_state.unwrap_or(1).max(0) as u32),
        "speed_scaling" | "target_speed_fraction" => Value::Double(1.0),
        // Bit 0 "is power on" (the guide's robot_status_bits).
        "robot_status_bits" => Value::Uint32(u32::from(state.robot_mode == ROBOT_MODE_RUNNING)),
        // Bit 0 "is normal mode".
        "safety_status_bits" => Value::Uint32(u32::from(state.safety_mode == SAFETY_MODE_NORMAL)),
        _ => kind.zero(),
    }
}

/// Writes everything on a non-blocking socket, waiting briefly when full.
fn write_all_nonblocking(stream: &mut TcpStream, mut bytes: &[u8]) -> std::io::Result<()> {
    let deadline = Instant::now() + Duration::from_secs(2);
    while !bytes.is_empty() {
        match stream.write(bytes) {
            Ok(0) => return Err(ErrorKind::WriteZero.into()),
            Ok(n) => bytes = &bytes[n..],
            Err(e) if e.kind() == ErrorKind::WouldBlock && Instant::now() < deadline => {
                std::thread::sleep(Duration::from_millis(1));
            }
            Err(e) => return Err(e),
        }
    }
    Ok(())
}

/// Settings of a [`FakeRtdeServer`].
#[derive(Debug, Clone)]
pub struct FakeRtdeOptions {
    /// The version reported to `v` (default 5.11.0.0, an e-series).
    pub version: ControllerVersion,
    /// Time between data packages (default 2 ms, 500 Hz).
    pub period: Duration,
    /// The server stops by itself after this long.
    pub lifetime: Duration,
    /// A text message sent just before the reply to start.
    pub greeting: Option<String>,
    /// This many text messages are sent after the greeting (a flooding
    /// controller; 0 by default).
    pub text_flood: usize,
}

impl Default for FakeRtdeOptions {
    fn default() -> Self {
        Self {
            version: ControllerVersion {
                major: 5,
                minor: 11,
                bugfix: 0,
                build: 0,
            },
            period: Duration::from_millis(2),
            lifetime: Duration::from_secs(20),
            greeting: None,
            text_flood: 0,
        }
    }
}

/// A state RTDE tests start from: the arm at rest, running, normal safety.
pub fn resting_state() -> RobotState {
    RobotState {
        time_s: 0.0,
        joints_rad: [0.0, -1.57, 1.57, -1.57, -1.57, 0.0],
        tool_actual: [0.4, -0.1, 0.3, std::f64::consts::PI, 0.0, 0.0],
        tcp_speed: [0.0; 6],
        tool_target: [0.4, -0.1, 0.3, std::f64::consts::PI, 0.0, 0.0],
        robot_mode: ROBOT_MODE_RUNNING,
        safety_mode: SAFETY_MODE_NORMAL,
        program_state: Some(1),
    }
}

#[derive(Default)]
struct Shared {
    state: Option<RobotState>,
    inputs: BTreeMap<String, Value>,
    sessions: usize,
    drop_clients: bool,
}

/// A fake RTDE controller serving a state the test sets; stops and joins
/// its thread on drop.
pub struct FakeRtdeServer {
    port: u16,
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeRtdeServer {
    /// Serves on 127.0.0.1:`port` (0: an ephemeral port).
    pub fn start(port: u16, options: FakeRtdeOptions) -> Result<Self, HwError> {
        let what = format!("fake RTDE server on 127.0.0.1:{port}");
        let (listener, port) = crate::ur5::fake_listener(port, &what)?;
        let shared = Arc::new(Mutex::new(Shared {
            state: Some(resting_state()),
            ..Shared::default()
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let (s, f) = (shared.clone(), stop.clone());
        let thread = std::thread::spawn(move || serve(listener, options, &s, &f));
        Ok(Self {
            port,
            shared,
            stop,
            thread: Some(thread),
        })
    }

    /// The port it listens on.
    pub fn port(&self) -> u16 {
        self.port
    }

    /// Sets the state sent from now on.
    pub fn set_state(&self, state: RobotState) {
        self.lock().state = Some(state);
    }

    /// Input values received from clients, by field name.
    pub fn received_inputs(&self) -> BTreeMap<String, Value> {
        self.lock().inputs.clone()
    }

    /// Clients served so far (counting the current one).
    pub fn sessions(&self) -> usize {
        self.lock().sessions
    }

    /// Closes the current client's connection (a lost link).
    pub fn drop_clients(&self) {
        self.lock().drop_clients = true;
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Shared> {
        self.shared.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl Drop for FakeRtdeServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn serve(
    listener: TcpListener,
    options: FakeRtdeOptions,
    shared: &Mutex<Shared>,
    stop: &AtomicBool,
) {
    let deadline = Instant::now() + options.lifetime;
    let done = || stop.load(Ordering::Relaxed) || Instant::now() >= deadline;
    let lock = || shared.lock().unwrap_or_else(|p| p.into_inner());
    while !done() {
        let stream = match listener.accept() {
            Ok((stream, _)) => stream,
            Err(e) if e.kind() == ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(2));
                continue;
            }
            Err(_) => return,
        };
        let Ok(session) = RtdeSession::new(stream, options.version, options.greeting.clone())
        else {
            continue;
        };
        let mut session = session.with_text_flood(options.text_flood);
        {
            let mut s = lock();
            s.sessions += 1;
            s.drop_clients = false;
        }
        let start = Instant::now();
        while !done() && session.poll() {
            let (state, drop_now) = {
                let s = lock();
                (s.state, s.drop_clients)
            };
            if drop_now {
                break;
            }
            if let Some(mut state) = state {
                state.time_s = start.elapsed().as_secs_f64();
                if session.send_state(&state).is_err() {
                    break;
                }
            }
            lock().inputs.extend(session.received_inputs().clone());
            std::thread::sleep(options.period);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trailing_comma_is_not_a_field_and_unknown_names_refuse_the_recipe() {
        let (fields, reply) = recipe_reply(b"timestamp,actual_TCP_pose,", output_field_type);
        assert_eq!(reply, "DOUBLE,VECTOR6D");
        assert_eq!(fields.unwrap().len(), 2);
        let (fields, reply) = recipe_reply(b"timestamp,tcp", output_field_type);
        assert_eq!((fields, reply.as_str()), (None, "DOUBLE,NOT_FOUND"));
    }
}
