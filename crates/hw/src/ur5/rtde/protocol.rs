//! RTDE wire format (Real-Time Data Exchange, port 30004), protocol
//! version 2, encoded and decoded by hand.
//!
//! Facts used (Universal Robots, "Real-Time Data Exchange (RTDE) Guide"):
//! every package is big-endian and starts with a 3-byte header, `uint16`
//! size (header included) and `uint8` type, an ASCII letter:
//!
//! | type | letter | client -> controller          | controller -> client              |
//! |-----:|:------:|-------------------------------|-----------------------------------|
//! |   86 |  `V`   | `uint16` protocol version     | `uint8` accepted                  |
//! |  118 |  `v`   | (empty)                       | `uint32` major, minor, bugfix, build |
//! |   77 |  `M`   | -                             | v2: `uint8` length + message, `uint8` length + source, `uint8` warning level |
//! |   79 |  `O`   | `double` frequency (v2), names joined by `,` | `uint8` recipe id, types joined by `,` |
//! |   73 |  `I`   | names joined by `,`           | `uint8` recipe id, types joined by `,` |
//! |   83 |  `S`   | (empty)                       | `uint8` accepted                  |
//! |   80 |  `P`   | (empty)                       | `uint8` accepted                  |
//! |   85 |  `U`   | `uint8` recipe id, input values | `uint8` recipe id, output values |
//!
//! A name the controller does not know is answered with the type
//! `NOT_FOUND`; an input already written by another client with `IN_USE`.
//! Values are packed without padding in recipe order: `BOOL` and `UINT8`
//! one byte, `INT32`/`UINT32` four, `UINT64`/`DOUBLE` eight, `VECTOR3D`
//! three doubles, `VECTOR6D` six doubles, `VECTOR6INT32`/`VECTOR6UINT32`
//! six four-byte integers.
use crate::HwError;

/// The protocol version tactrace speaks (frequency in the output setup).
pub const PROTOCOL_VERSION: u16 = 2;
/// Largest package accepted (the header's size field is a `uint16`).
pub const MAX_PACKAGE_LEN: usize = u16::MAX as usize;

/// The package types of the protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PackageType {
    /// `V`: request a protocol version.
    RequestProtocolVersion,
    /// `v`: the controller's URControl version.
    GetUrControlVersion,
    /// `M`: a text message.
    TextMessage,
    /// `U`: a data package of a recipe.
    DataPackage,
    /// `O`: set up the output recipe.
    SetupOutputs,
    /// `I`: set up an input recipe.
    SetupInputs,
    /// `S`: start streaming.
    Start,
    /// `P`: pause streaming.
    Pause,
}

impl PackageType {
    /// The type byte on the wire.
    pub fn byte(self) -> u8 {
        match self {
            Self::RequestProtocolVersion => b'V',
            Self::GetUrControlVersion => b'v',
            Self::TextMessage => b'M',
            Self::DataPackage => b'U',
            Self::SetupOutputs => b'O',
            Self::SetupInputs => b'I',
            Self::Start => b'S',
            Self::Pause => b'P',
        }
    }

    /// The type of a wire byte, if it is one of the protocol's.
    pub fn from_byte(byte: u8) -> Option<Self> {
        Some(match byte {
            b'V' => Self::RequestProtocolVersion,
            b'v' => Self::GetUrControlVersion,
            b'M' => Self::TextMessage,
            b'U' => Self::DataPackage,
            b'O' => Self::SetupOutputs,
            b'I' => Self::SetupInputs,
            b'S' => Self::Start,
            b'P' => Self::Pause,
            _ => return None,
        })
    }
}

/// One package: its type and payload (header removed).
#[derive(Debug, Clone, PartialEq)]
pub struct Package {
    /// The type byte (kept raw: unknown types are skipped, not errors).
    pub kind: u8,
    /// The bytes after the header.
    pub payload: Vec<u8>,
}

impl Package {
    /// A package of a known type.
    pub fn new(kind: PackageType, payload: Vec<u8>) -> Self {
        Self {
            kind: kind.byte(),
            payload,
        }
    }

    /// The type, if known.
    pub fn package_type(&self) -> Option<PackageType> {
        PackageType::from_byte(self.kind)
    }

    /// Header and payload, ready to send.
    pub fn encode(&self) -> Vec<u8> {
        let len = (self.payload.len() + 3).min(MAX_PACKAGE_LEN) as u16;
        let mut out = Vec::with_capacity(len as usize);
        out.extend_from_slice(&len.to_be_bytes());
        out.push(self.kind);
        out.extend_from_slice(&self.payload[..len as usize - 3]);
        out
    }
}

/// Removes the first complete package from the front of `buffer`; `None`
/// while it is incomplete. A size below the header's is an error.
pub fn take_package(buffer: &mut Vec<u8>) -> Result<Option<Package>, HwError> {
    if buffer.len() < 3 {
        return Ok(None);
    }
    let len = u16::from_be_bytes([buffer[0], buffer[1]]) as usize;
    if len < 3 {
        return Err(rtde_err(format!(
            "package declares {len} bytes, below the 3-byte header"
        )));
    }
    if buffer.len() < len {
        return Ok(None);
    }
    let kind = buffer[2];
    let payload = buffer[3..len].to_vec();
    buffer.drain(..len);
    Ok(Some(Package { kind, payload }))
}

pub(crate) fn rtde_err(reason: impl Into<String>) -> HwError {
    HwError::Rtde {
        reason: reason.into(),
    }
}

/// The data types of recipe fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldType {
    /// One byte, 0 or 1.
    Bool,
    /// One unsigned byte.
    Uint8,
    /// Four-byte unsigned integer.
    Uint32,
    /// Eight-byte unsigned integer.
    Uint64,
    /// Four-byte signed integer.
    Int32,
    /// Eight-byte IEEE double.
    Double,
    /// Three doubles.
    Vector3d,
    /// Six doubles.
    Vector6d,
    /// Six signed four-byte integers.
    Vector6Int32,
    /// Six unsigned four-byte integers.
    Vector6Uint32,
}

impl FieldType {
    /// The name the controller uses in setup replies.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bool => "BOOL",
            Self::Uint8 => "UINT8",
            Self::Uint32 => "UINT32",
            Self::Uint64 => "UINT64",
            Self::Int32 => "INT32",
            Self::Double => "DOUBLE",
            Self::Vector3d => "VECTOR3D",
            Self::Vector6d => "VECTOR6D",
            Self::Vector6Int32 => "VECTOR6INT32",
            Self::Vector6Uint32 => "VECTOR6UINT32",
        }
    }

    /// The type of a name, if known.
    pub fn from_name(name: &str) -> Option<Self> {
        [
            Self::Bool,
            Self::Uint8,
            Self::Uint32,
            Self::Uint64,
            Self::Int32,
            Self::Double,
            Self::Vector3d,
            Self::Vector6d,
            Self::Vector6Int32,
            Self::Vector6Uint32,
        ]
        .into_iter()
        .find(|t| t.name() == name)
    }

    /// Bytes one value takes on the wire.
    pub fn size(self) -> usize {
        match self {
            Self::Bool | Self::Uint8 => 1,
            Self::Uint32 | Self::Int32 => 4,
            Self::Uint64 | Self::Double => 8,
            Self::Vector3d => 24,
            Self::Vector6d => 48,
            Self::Vector6Int32 | Self::Vector6Uint32 => 24,
        }
    }

    /// The zero value of this type.
    pub fn zero(self) -> Value {
        match self {
            Self::Bool => Value::Bool(false),
            Self::Uint8 => Value::Uint8(0),
            Self::Uint32 => Value::Uint32(0),
            Self::Uint64 => Value::Uint64(0),
            Self::Int32 => Value::Int32(0),
            Self::Double => Value::Double(0.0),
            Self::Vector3d => Value::Vector3d([0.0; 3]),
            Self::Vector6d => Value::Vector6d([0.0; 6]),
            Self::Vector6Int32 => Value::Vector6Int32([0; 6]),
            Self::Vector6Uint32 => Value::Vector6Uint32([0; 6]),
        }
    }
}

/// One field value of a data package.
#[derive(Debug, Clone, Copy, PartialEq)]
#[allow(missing_docs)]
pub enum Value {
    Bool(bool),
    Uint8(u8),
    Uint32(u32),
    Uint64(u64),
    Int32(i32),
    Double(f64),
    Vector3d([f64; 3]),
    Vector6d([f64; 6]),
    Vector6Int32([i32; 6]),
    Vector6Uint32([u32; 6]),
}

impl Value {
    /// The value's type.
    pub fn field_type(&self) -> FieldType {
        match self {
            Self::Bool(_) => FieldType::Bool,
            Self::Uint8(_) => FieldType::Uint8,
            Self::Uint32(_) => FieldType::Uint32,
            Self::Uint64(_) => FieldType::Uint64,
            Self::Int32(_) => FieldType::Int32,
            Self::Double(_) => FieldType::Double,
            Self::Vector3d(_) => FieldType::Vector3d,
            Self::Vector6d(_) => FieldType::Vector6d,
            Self::Vector6Int32(_) => FieldType::Vector6Int32,
            Self::Vector6Uint32(_) => FieldType::Vector6Uint32,
        }
    }

    /// Appends the big-endian bytes.
    pub fn write(&self, out: &mut Vec<u8>) {
        match self {
            Self::Bool(b) => out.push(u8::from(*b)),
            Self::Uint8(v) => out.push(*v),
            Self::Uint32(v) => out.extend_from_slice(&v.to_be_bytes()),
            Self::Uint64(v) => out.extend_from_slice(&v.to_be_bytes()),
            Self::Int32(v) => out.extend_from_slice(&v.to_be_bytes()),
            Self::Double(v) => out.extend_from_slice(&v.to_be_bytes()),
            Self::Vector3d(v) => v.iter().for_each(|x| out.extend(x.to_be_bytes())),
            Self::Vector6d(v) => v.iter().for_each(|x| out.extend(x.to_be_bytes())),
            Self::Vector6Int32(v) => v.iter().for_each(|x| out.extend(x.to_be_bytes())),
            Self::Vector6Uint32(v) => v.iter().for_each(|x| out.extend(x.to_be_bytes())),
        }
    }

    /// Reads one value of type `kind` from the front of `bytes`.
    pub fn read(kind: FieldType, bytes: &[u8]) -> Option<Self> {
        let b = bytes.get(..kind.size())?;
        let f = |i: usize| f64::from_be_bytes(b[8 * i..8 * i + 8].try_into().unwrap_or([0; 8]));
        let w = |i: usize| <[u8; 4]>::try_from(&b[4 * i..4 * i + 4]).unwrap_or([0; 4]);
        Some(match kind {
            FieldType::Bool => Self::Bool(b[0] != 0),
            FieldType::Uint8 => Self::Uint8(b[0]),
            FieldType::Uint32 => Self::Uint32(u32::from_be_bytes(w(0))),
            FieldType::Uint64 => Self::Uint64(u64::from_be_bytes(b.try_into().ok()?)),
            FieldType::Int32 => Self::Int32(i32::from_be_bytes(w(0))),
            FieldType::Double => Self::Double(f(0)),
            FieldType::Vector3d => Self::Vector3d(std::array::from_fn(f)),
            FieldType::Vector6d => Self::Vector6d(std::array::from_fn(f)),
            FieldType::Vector6Int32 => {
                Self::Vector6Int32(std::array::from_fn(|i| i32::from_be_bytes(w(i))))
            }
            FieldType::Vector6Uint32 => {
                Self::Vector6Uint32(std::array::from_fn(|i| u32::from_be_bytes(w(i))))
            }
        })
    }
}

/// Decodes the values of a data package payload (recipe id removed) in
/// the order of `types`; the payload must hold exactly those values.
pub fn decode_values(types: &[FieldType], bytes: &[u8]) -> Result<Vec<Value>, HwError> {
    let expected: usize = types.iter().map(|t| t.size()).sum();
    if bytes.len() != expected {
        return Err(rtde_err(format!(
            "data package holds {} bytes, its recipe needs {expected}",
            bytes.len()
        )));
    }
    let mut at = 0;
    let mut values = Vec::with_capacity(types.len());
    for &kind in types {
        values.push(Value::read(kind, &bytes[at..]).ok_or_else(|| rtde_err("short value"))?);
        at += kind.size();
    }
    Ok(values)
}

/// A data package: recipe id, then the values.
pub fn encode_data(recipe_id: u8, values: &[Value]) -> Package {
    let mut payload = vec![recipe_id];
    for v in values {
        v.write(&mut payload);
    }
    Package::new(PackageType::DataPackage, payload)
}

/// The field names of a setup request: split at commas, empty names (a
/// trailing comma, as `ur_rtde` sends) kept so the reply lines up.
pub fn split_names(text: &str) -> Vec<&str> {
    text.split(',').collect()
}

/// A text message of protocol version 2 (`M`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TextMessage {
    /// The message text.
    pub message: String,
    /// Who sent it.
    pub source: String,
    /// 0 exception, 1 error, 2 warning, 3 info.
    pub level: u8,
}

impl TextMessage {
    /// The package carrying this message.
    pub fn encode(&self) -> Package {
        let mut payload = Vec::new();
        for text in [&self.message, &self.source] {
            let bytes = &text.as_bytes()[..text.len().min(255)];
            payload.push(bytes.len() as u8);
            payload.extend_from_slice(bytes);
        }
        payload.push(self.level);
        Package::new(PackageType::TextMessage, payload)
    }

    /// Reads a version 2 text message payload.
    pub fn decode(payload: &[u8]) -> Result<Self, HwError> {
        let bad = || rtde_err("truncated text message");
        let (message, rest) = length_prefixed(payload).ok_or_else(bad)?;
        let (source, rest) = length_prefixed(rest).ok_or_else(bad)?;
        let level = *rest.first().ok_or_else(bad)?;
        Ok(Self {
            message,
            source,
            level,
        })
    }
}

fn length_prefixed(bytes: &[u8]) -> Option<(String, &[u8])> {
    let len = *bytes.first()? as usize;
    let text = bytes.get(1..1 + len)?;
    Some((
        String::from_utf8_lossy(text).into_owned(),
        &bytes[1 + len..],
    ))
}

/// The type of a controller output field, for the fields the fake
/// controller serves (the RTDE guide's output table; registers 0..=47).
pub fn output_field_type(name: &str) -> Option<FieldType> {
    use FieldType::*;
    if let Some(kind) = register_type(name, "output_") {
        return Some(kind);
    }
    Some(match name {
        "timestamp"
        | "actual_execution_time"
        | "speed_scaling"
        | "target_speed_fraction"
        | "actual_momentum"
        | "actual_main_voltage"
        | "actual_robot_voltage"
        | "actual_robot_current"
        | "standard_analog_input0"
        | "standard_analog_input1"
        | "standard_analog_output0"
        | "standard_analog_output1"
        | "payload"
        | "tool_output_current"
        | "tool_analog_input0"
        | "tool_analog_input1" => Double,
        "target_q"
        | "target_qd"
        | "target_qdd"
        | "target_current"
        | "target_moment"
        | "actual_q"
        | "actual_qd"
        | "actual_current"
        | "joint_control_output"
        | "actual_TCP_pose"
        | "actual_TCP_speed"
        | "actual_TCP_force"
        | "target_TCP_pose"
        | "target_TCP_speed"
        | "joint_temperatures"
        | "actual_joint_voltage"
        | "ft_raw_wrench"
        | "payload_inertia"
        | "elbow_position" => Vector6d,
        "actual_tool_accelerometer" | "payload_cog" | "elbow_velocity" => Vector3d,
        "actual_digital_input_bits" | "actual_digital_output_bits" => Uint64,
        "robot_mode" | "safety_mode" | "safety_status" | "tool_mode" | "tool_output_voltage" => {
            Int32
        }
        "joint_mode" => Vector6Int32,
        "runtime_state"
        | "robot_status_bits"
        | "safety_status_bits"
        | "analog_io_types"
        | "tool_analog_input_types"
        | "output_bit_registers0_to_31"
        | "output_bit_registers32_to_63" => Uint32,
        _ => return None,
    })
}

/// The type of a controller input field (registers 0..=47 and the
/// standard outputs the guide lists), for the fake controller.
pub fn input_field_type(name: &str) -> Option<FieldType> {
    use FieldType::*;
    if let Some(kind) = register_type(name, "input_") {
        return Some(kind);
    }
    Some(match name {
        "speed_slider_mask"
        | "standard_digital_output_mask"
        | "standard_digital_output"
        | "configurable_digital_output_mask"
        | "configurable_digital_output"
        | "tool_digital_output_mask"
        | "tool_digital_output"
        | "standard_analog_output_mask"
        | "standard_analog_output_type" => Uint8,
        "speed_slider_fraction" | "standard_analog_output_0" | "standard_analog_output_1" => Double,
        "input_bit_registers0_to_31" | "input_bit_registers32_to_63" => Uint32,
        _ => return None,
    })
}

/// `{prefix}int_register_N` (INT32), `double_register_N` (DOUBLE) and
/// `bit_register_N` (BOOL, N in 64..=127), N within the guide's ranges.
fn register_type(name: &str, prefix: &str) -> Option<FieldType> {
    let rest = name.strip_prefix(prefix)?;
    let (kind, index, range) = if let Some(n) = rest.strip_prefix("int_register_") {
        (FieldType::Int32, n, 0..=47)
    } else if let Some(n) = rest.strip_prefix("double_register_") {
        (FieldType::Double, n, 0..=47)
    } else if let Some(n) = rest.strip_prefix("bit_register_") {
        (FieldType::Bool, n, 64..=127)
    } else {
        return None;
    };
    let index: u32 = index.parse().ok()?;
    range.contains(&index).then_some(kind)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn package_header_is_size_then_type() {
        let bytes = Package::new(PackageType::RequestProtocolVersion, vec![0, 2]).encode();
        assert_eq!(bytes, [0, 5, 86, 0, 2]);
        let mut buffer = bytes.clone();
        buffer.extend_from_slice(&[0, 3]);
        let got = take_package(&mut buffer).unwrap().unwrap();
        assert_eq!(
            got.package_type(),
            Some(PackageType::RequestProtocolVersion)
        );
        assert_eq!(got.payload, [0, 2]);
        assert_eq!(buffer, [0, 3], "the incomplete next package stays");
        assert_eq!(take_package(&mut buffer).unwrap(), None);
        let mut bad = vec![0, 1, 85];
        assert!(matches!(take_package(&mut bad), Err(HwError::Rtde { .. })));
    }

    #[test]
    fn values_round_trip_in_recipe_order() {
        let values = [
            Value::Double(1.5),
            Value::Vector6d([0.4, -0.1, 0.3, 3.1, 0.0, -0.2]),
            Value::Int32(-7),
            Value::Uint32(2),
            Value::Bool(true),
            Value::Vector6Int32([1, -2, 3, -4, 5, -6]),
            Value::Uint64(1 << 40),
            Value::Vector3d([1.0, 2.0, 3.0]),
        ];
        let package = encode_data(3, &values);
        assert_eq!(package.payload[0], 3);
        let types: Vec<_> = values.iter().map(Value::field_type).collect();
        assert_eq!(package.payload.len(), 1 + 8 + 48 + 4 + 4 + 1 + 24 + 8 + 24);
        assert_eq!(
            decode_values(&types, &package.payload[1..]).unwrap(),
            values
        );
        assert!(decode_values(&types, &package.payload[2..]).is_err());
    }

    #[test]
    fn text_message_round_trips() {
        let m = TextMessage {
            message: "hello".into(),
            source: "RTDE".into(),
            level: 2,
        };
        assert_eq!(TextMessage::decode(&m.encode().payload).unwrap(), m);
        assert!(TextMessage::decode(&[9, b'a']).is_err());
    }

    #[test]
    fn field_tables_know_the_state_fields_and_registers() {
        assert_eq!(
            output_field_type("actual_TCP_pose"),
            Some(FieldType::Vector6d)
        );
        assert_eq!(output_field_type("runtime_state"), Some(FieldType::Uint32));
        assert_eq!(
            output_field_type("output_int_register_19"),
            Some(FieldType::Int32)
        );
        assert_eq!(output_field_type("output_double_register_48"), None);
        assert_eq!(output_field_type(""), None);
        assert_eq!(
            input_field_type("input_int_register_24"),
            Some(FieldType::Int32)
        );
        assert_eq!(
            input_field_type("input_bit_register_64"),
            Some(FieldType::Bool)
        );
        assert_eq!(input_field_type("input_bit_register_1"), None);
        assert_eq!(split_names("a,b,"), ["a", "b", ""]);
        for t in ["BOOL", "VECTOR6D", "VECTOR6INT32", "UINT64"] {
            assert_eq!(FieldType::from_name(t).unwrap().name(), t);
        }
    }
}
