//! [`RtdeClient`]: the client side of the RTDE handshake and data stream.
//!
//! Blocking: every request waits for its reply up to the client's timeout;
//! text messages arriving meanwhile are kept ([`RtdeClient::messages`]).
//! [`RtdeClient::poll_data`] waits at most the socket's read timeout.
//!
//! Bounded: the newest [`MAX_TEXT_MESSAGES`] text messages are kept and
//! the older ones only counted, and the unparsed bytes never exceed one
//! package (the header's `uint16` size) plus one read, so a controller
//! that floods the connection cannot make the client grow.
use std::collections::VecDeque;
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use super::protocol::{
    decode_values, encode_data, rtde_err, take_package, FieldType, Package, PackageType,
    TextMessage, Value, PROTOCOL_VERSION,
};
use crate::ur5::realtime::RobotState;
use crate::HwError;

/// The output fields tactrace reads, in recipe order.
pub const STATE_FIELDS: [&str; 8] = [
    "timestamp",
    "actual_q",
    "actual_TCP_pose",
    "actual_TCP_speed",
    "target_TCP_pose",
    "robot_mode",
    "safety_mode",
    "runtime_state",
];

const STATE_TYPES: [FieldType; 8] = [
    FieldType::Double,
    FieldType::Vector6d,
    FieldType::Vector6d,
    FieldType::Vector6d,
    FieldType::Vector6d,
    FieldType::Int32,
    FieldType::Int32,
    FieldType::Uint32,
];

/// Text messages kept by a client: the newest ones.
pub const MAX_TEXT_MESSAGES: usize = 64;

/// The controller's software version (URControl), as `v` reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ControllerVersion {
    /// 3 for CB3, 5 for e-series (PolyScope 5), 10 for PolyScope X.
    pub major: u32,
    /// Minor version.
    pub minor: u32,
    /// Bug-fix version.
    pub bugfix: u32,
    /// Build number.
    pub build: u32,
}

impl ControllerVersion {
    /// The fastest output frequency of this controller: 125 Hz on CB3,
    /// 500 Hz on e-series and later.
    pub fn max_frequency_hz(&self) -> f64 {
        if self.major >= 5 {
            500.0
        } else {
            125.0
        }
    }
}

/// A recipe the controller accepted: its id, names and types.
#[derive(Debug, Clone, PartialEq)]
pub struct Recipe {
    /// The id data packages of this recipe carry.
    pub id: u8,
    /// Field names, in order.
    pub names: Vec<String>,
    /// Field types, in order.
    pub types: Vec<FieldType>,
}

/// An RTDE connection after version negotiation.
pub struct RtdeClient {
    stream: TcpStream,
    buffer: Vec<u8>,
    timeout: Duration,
    version: ControllerVersion,
    outputs: Option<Recipe>,
    messages: VecDeque<TextMessage>,
    dropped_messages: u64,
}

impl RtdeClient {
    /// Negotiates protocol version 2 and reads the controller version on
    /// an open connection; each reply is awaited up to `timeout`.
    pub fn handshake(stream: TcpStream, timeout: Duration) -> Result<Self, HwError> {
        stream
            .set_read_timeout(Some(Duration::from_millis(50)))
            .map_err(|source| io_err("RTDE socket", source))?;
        let mut client = Self {
            stream,
            buffer: Vec::new(),
            timeout,
            version: ControllerVersion {
                major: 0,
                minor: 0,
                bugfix: 0,
                build: 0,
            },
            outputs: None,
            messages: VecDeque::new(),
            dropped_messages: 0,
        };
        let reply = client.request(
            PackageType::RequestProtocolVersion,
            PROTOCOL_VERSION.to_be_bytes().to_vec(),
        )?;
        if reply.first() != Some(&1) {
            return Err(rtde_err(format!(
                "the controller refused protocol version {PROTOCOL_VERSION}"
            )));
        }
        let reply = client.request(PackageType::GetUrControlVersion, Vec::new())?;
        let word = |i: usize| {
            reply
                .get(4 * i..4 * i + 4)
                .and_then(|b| b.try_into().ok())
                .map(u32::from_be_bytes)
                .ok_or_else(|| rtde_err("controller version reply is too short"))
        };
        client.version = ControllerVersion {
            major: word(0)?,
            minor: word(1)?,
            bugfix: word(2)?,
            build: word(3)?,
        };
        Ok(client)
    }

    /// The controller's version.
    pub fn version(&self) -> ControllerVersion {
        self.version
    }

    /// The newest text messages received (at most
    /// [`MAX_TEXT_MESSAGES`], oldest first).
    pub fn messages(&self) -> &VecDeque<TextMessage> {
        &self.messages
    }

    /// Text messages received and not kept (older than the kept ones).
    pub fn dropped_messages(&self) -> u64 {
        self.dropped_messages
    }

    /// Sets up the output recipe at `frequency_hz`; fails naming every
    /// field the controller does not know.
    pub fn setup_outputs(&mut self, names: &[&str], frequency_hz: f64) -> Result<Recipe, HwError> {
        let mut payload = frequency_hz.to_be_bytes().to_vec();
        payload.extend_from_slice(names.join(",").as_bytes());
        let reply = self.request(PackageType::SetupOutputs, payload)?;
        let recipe = parse_recipe(&reply, names, "output")?;
        self.outputs = Some(recipe.clone());
        Ok(recipe)
    }

    /// Sets up an input recipe; fails on unknown or already used fields.
    pub fn setup_inputs(&mut self, names: &[&str]) -> Result<Recipe, HwError> {
        let reply = self.request(PackageType::SetupInputs, names.join(",").into_bytes())?;
        parse_recipe(&reply, names, "input")
    }

    /// Sends the values of an input recipe (checked against its types).
    pub fn send_inputs(&mut self, recipe: &Recipe, values: &[Value]) -> Result<(), HwError> {
        let types: Vec<_> = values.iter().map(Value::field_type).collect();
        if types != recipe.types {
            return Err(rtde_err(
                "input values do not match the input recipe's types",
            ));
        }
        self.send(&encode_data(recipe.id, values))
    }

    /// Starts the data stream.
    pub fn start(&mut self) -> Result<(), HwError> {
        self.accepted(PackageType::Start, "start")
    }

    /// Pauses the data stream.
    pub fn pause(&mut self) -> Result<(), HwError> {
        self.accepted(PackageType::Pause, "pause")
    }

    /// The values of the next output data package, or `None` when nothing
    /// complete arrived within the socket's read timeout (50 ms).
    pub fn poll_data(&mut self) -> Result<Option<Vec<Value>>, HwError> {
        let recipe = self
            .outputs
            .clone()
            .ok_or_else(|| rtde_err("no output recipe set up"))?;
        loop {
            while let Some(package) = self.next_package()? {
                if let Some(values) = self.data_of(&recipe, package)? {
                    return Ok(Some(values));
                }
            }
            if !self.fill()? {
                return Ok(None);
            }
        }
    }

    fn data_of(
        &mut self,
        recipe: &Recipe,
        package: Package,
    ) -> Result<Option<Vec<Value>>, HwError> {
        if package.package_type() != Some(PackageType::DataPackage) {
            return Ok(None);
        }
        let (&id, values) = package
            .payload
            .split_first()
            .ok_or_else(|| rtde_err("empty data package"))?;
        if id != recipe.id {
            return Err(rtde_err(format!(
                "data package of recipe {id}, expected {}",
                recipe.id
            )));
        }
        decode_values(&recipe.types, values).map(Some)
    }

    fn accepted(&mut self, kind: PackageType, what: &str) -> Result<(), HwError> {
        let reply = self.request(kind, Vec::new())?;
        match reply.first() {
            Some(1) => Ok(()),
            _ => Err(rtde_err(format!("the controller refused to {what}"))),
        }
    }

    /// Sends a request and waits for the reply of the same type.
    fn request(&mut self, kind: PackageType, payload: Vec<u8>) -> Result<Vec<u8>, HwError> {
        self.send(&Package::new(kind, payload))?;
        let deadline = Instant::now() + self.timeout;
        loop {
            while let Some(package) = self.next_package()? {
                if package.kind == kind.byte() {
                    return Ok(package.payload);
                }
            }
            if Instant::now() >= deadline {
                return Err(HwError::NoState {
                    seconds: self.timeout.as_secs_f64(),
                });
            }
            self.fill()?;
        }
    }

    /// The next buffered package; text messages are kept, not returned.
    fn next_package(&mut self) -> Result<Option<Package>, HwError> {
        while let Some(package) = take_package(&mut self.buffer)? {
            if package.package_type() == Some(PackageType::TextMessage) {
                if let Ok(message) = TextMessage::decode(&package.payload) {
                    if self.messages.len() == MAX_TEXT_MESSAGES {
                        self.messages.pop_front();
                        self.dropped_messages += 1;
                    }
                    self.messages.push_back(message);
                }
                continue;
            }
            return Ok(Some(package));
        }
        Ok(None)
    }

    /// One read from the socket (at most the read timeout); false when
    /// nothing arrived.
    fn fill(&mut self) -> Result<bool, HwError> {
        let mut chunk = [0u8; 4096];
        match self.stream.read(&mut chunk) {
            Ok(0) => Err(HwError::StateStream {
                reason: "RTDE connection closed by the controller".into(),
            }),
            Ok(n) => {
                self.buffer.extend_from_slice(&chunk[..n]);
                Ok(true)
            }
            Err(e) if is_poll_timeout(&e) => Ok(false),
            Err(e) => Err(HwError::StateStream {
                reason: format!("RTDE read failed: {e}"),
            }),
        }
    }

    fn send(&mut self, package: &Package) -> Result<(), HwError> {
        self.stream
            .write_all(&package.encode())
            .and_then(|()| self.stream.flush())
            .map_err(|source| io_err("RTDE socket", source))
    }
}

fn io_err(what: &str, source: std::io::Error) -> HwError {
    HwError::Io {
        what: what.into(),
        source,
    }
}

fn is_poll_timeout(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
    )
}

/// Reads a setup reply: recipe id, then one type name per requested field.
fn parse_recipe(reply: &[u8], names: &[&str], what: &str) -> Result<Recipe, HwError> {
    let (&id, types) = reply
        .split_first()
        .ok_or_else(|| rtde_err(format!("empty {what} setup reply")))?;
    let types = String::from_utf8_lossy(types);
    let types: Vec<&str> = types.split(',').collect();
    if types.len() != names.len() {
        return Err(rtde_err(format!(
            "{what} setup: {} types for {} fields",
            types.len(),
            names.len()
        )));
    }
    let mut parsed = Vec::with_capacity(names.len());
    let mut refused = Vec::new();
    for (name, kind) in names.iter().zip(&types) {
        match FieldType::from_name(kind) {
            Some(t) => parsed.push(t),
            None => refused.push(format!("{name} ({kind})")),
        }
    }
    if !refused.is_empty() || id == 0 {
        return Err(rtde_err(format!(
            "the controller refused the {what} recipe: {}",
            if refused.is_empty() {
                "recipe id 0".to_string()
            } else {
                refused.join(", ")
            }
        )));
    }
    Ok(Recipe {
        id,
        names: names.iter().map(|n| n.to_string()).collect(),
        types: parsed,
    })
}

/// Sets up the state recipe ([`STATE_FIELDS`]) at the controller's
/// fastest rate and starts the stream; checks the types it got.
pub fn start_state_stream(client: &mut RtdeClient) -> Result<(), HwError> {
    let frequency = client.version().max_frequency_hz();
    let recipe = client.setup_outputs(&STATE_FIELDS, frequency)?;
    if recipe.types != STATE_TYPES {
        let types: Vec<&str> = recipe.types.iter().map(|t| t.name()).collect();
        return Err(rtde_err(format!(
            "unexpected state field types: {}",
            types.join(", ")
        )));
    }
    client.start()
}

/// The robot state in a data package of the state recipe.
pub fn state_from_values(values: &[Value]) -> Result<RobotState, HwError> {
    use Value::*;
    let [Double(time_s), Vector6d(joints_rad), Vector6d(tool_actual), Vector6d(tcp_speed), Vector6d(tool_target), Int32(robot_mode), Int32(safety_mode), Uint32(runtime)] =
        values
    else {
        return Err(rtde_err("data package does not hold the state recipe"));
    };
    let finite = std::iter::once(time_s)
        .chain(joints_rad)
        .chain(tool_actual)
        .chain(tcp_speed)
        .chain(tool_target)
        .all(|v| v.is_finite());
    if !finite {
        return Err(HwError::PacketNotFinite {
            field: "RTDE state",
        });
    }
    Ok(RobotState {
        time_s: *time_s,
        joints_rad: *joints_rad,
        tool_actual: *tool_actual,
        tcp_speed: *tcp_speed,
        tool_target: *tool_target,
        robot_mode: *robot_mode,
        safety_mode: *safety_mode,
        program_state: Some(*runtime as i32),
    })
}

/// The values of the state recipe for `state` (used by the fake).
pub fn state_values(state: &RobotState) -> Vec<Value> {
    vec![
        Value::Double(state.time_s),
        Value::Vector6d(state.joints_rad),
        Value::Vector6d(state.tool_actual),
        Value::Vector6d(state.tcp_speed),
        Value::Vector6d(state.tool_target),
        Value::Int32(state.robot_mode),
        Value::Int32(state.safety_mode),
        Value::Uint32(state.program_state.unwrap_or(0).max(0) as u32),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ur5::rtde::resting_state;

    #[test]
    fn a_setup_reply_names_the_refused_fields() {
        let mut reply = vec![1];
        reply.extend_from_slice(b"INT32,IN_USE");
        let err = parse_recipe(
            &reply,
            &["input_int_register_24", "speed_slider_mask"],
            "input",
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("speed_slider_mask (IN_USE)"),
            "{err}"
        );
        let mut short = vec![1];
        short.extend_from_slice(b"INT32");
        assert!(parse_recipe(&short, &["a", "b"], "input").is_err());
        let ok = parse_recipe(&[2, b'B', b'O', b'O', b'L'], &["x"], "input").unwrap();
        assert_eq!((ok.id, ok.types.as_slice()), (2, &[FieldType::Bool][..]));
    }

    #[test]
    fn state_values_round_trip_and_non_finite_poses_are_refused() {
        let state = resting_state();
        assert_eq!(state_from_values(&state_values(&state)).unwrap(), state);
        let mut values = state_values(&state);
        values[2] = Value::Vector6d([f64::NAN; 6]);
        assert!(matches!(
            state_from_values(&values),
            Err(HwError::PacketNotFinite { .. })
        ));
        assert!(state_from_values(&values[..3]).is_err());
    }
}
