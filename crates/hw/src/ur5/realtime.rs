//! The UR controller's real-time state packet (port 30003), parsed by hand.
//!
//! Layout used (Universal Robots, "Remote Control Via TCP/IP" support
//! article and its attached "Client Interface" spreadsheet, CB3 3.x and
//! e-series 5.x real-time tables): the packet is big-endian; it starts with
//! an `int32` message size in bytes (including those 4 bytes), followed by
//! `double` fields. The byte offsets below count from the start of the
//! packet (so the first double, controller time, is at 4):
//!
//! | field                                  | offset | doubles |
//! |----------------------------------------|-------:|--------:|
//! | time since controller start (s)        |      4 |       1 |
//! | actual joint positions q (rad)         |    252 |       6 |
//! | tool vector actual (m, rotation vector)|    444 |       6 |
//! | TCP speed actual (m/s, rad/s)          |    492 |       6 |
//! | tool vector target                     |    588 |       6 |
//! | robot mode                             |    756 |       1 |
//! | safety mode                            |    812 |       1 |
//! | program state (3.2 and later)          |   1052 |       1 |
//!
//! These offsets are the same from CB3 3.0 on and in the e-series; older
//! (pre-3.0, 812-byte) packets have another layout and are refused because
//! they are too short for the safety mode. Packets of 3.0/3.1 (1044 bytes)
//! are accepted without the program state. Newer controllers append fields
//! after 1108 bytes; they are skipped.
use crate::HwError;

/// Smallest packet accepted: up to and including the safety mode.
pub const MIN_PACKET_LEN: usize = OFFSET_SAFETY_MODE + 8;
/// Largest packet accepted (e-series packets are about 1.2 kB).
pub const MAX_PACKET_LEN: usize = 4096;
/// Size of the CB3 3.5 packet the fake controller writes.
pub const CB3_PACKET_LEN: usize = 1108;

const OFFSET_TIME: usize = 4;
const OFFSET_Q_ACTUAL: usize = 252;
const OFFSET_TOOL_ACTUAL: usize = 444;
const OFFSET_TCP_SPEED: usize = 492;
const OFFSET_TOOL_TARGET: usize = 588;
const OFFSET_ROBOT_MODE: usize = 756;
const OFFSET_SAFETY_MODE: usize = 812;
const OFFSET_PROGRAM_STATE: usize = 1052;

/// Robot mode "running" (CB3 and e-series numbering).
pub const ROBOT_MODE_RUNNING: i32 = 7;
/// Safety mode "normal".
pub const SAFETY_MODE_NORMAL: i32 = 1;

/// The fields of one real-time packet that the driver uses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotState {
    /// Time since the controller started, s.
    pub time_s: f64,
    /// Actual joint positions, rad.
    pub joints_rad: [f64; 6],
    /// Actual TCP pose in the base frame: m and rotation vector (rad).
    pub tool_actual: [f64; 6],
    /// Actual TCP speed: m/s and rad/s.
    pub tcp_speed: [f64; 6],
    /// Target TCP pose in the base frame: m and rotation vector (rad).
    pub tool_target: [f64; 6],
    /// Robot mode (7 = running).
    pub robot_mode: i32,
    /// Safety mode (1 = normal).
    pub safety_mode: i32,
    /// Program state, when the packet carries it (3.2 and later).
    pub program_state: Option<i32>,
}

/// Checks a packet's declared size (its first four bytes) and returns it.
pub fn declared_length(header: [u8; 4]) -> Result<usize, HwError> {
    let declared = i32::from_be_bytes(header) as i64;
    if declared < MIN_PACKET_LEN as i64 || declared > MAX_PACKET_LEN as i64 {
        return Err(HwError::PacketLength {
            declared,
            min: MIN_PACKET_LEN,
            max: MAX_PACKET_LEN,
        });
    }
    Ok(declared as usize)
}

/// Parses one complete packet (size header included).
pub fn parse_packet(bytes: &[u8]) -> Result<RobotState, HwError> {
    let header: [u8; 4] =
        bytes
            .get(..4)
            .and_then(|h| h.try_into().ok())
            .ok_or(HwError::PacketTooShort {
                len: bytes.len(),
                needed: 4,
            })?;
    let declared = declared_length(header)?;
    if bytes.len() < declared {
        return Err(HwError::PacketTooShort {
            len: bytes.len(),
            needed: declared,
        });
    }
    let packet = &bytes[..declared];
    let program_state = if declared >= OFFSET_PROGRAM_STATE + 8 {
        Some(read_mode(packet, OFFSET_PROGRAM_STATE, "program state")?)
    } else {
        None
    };
    Ok(RobotState {
        time_s: read_doubles::<1>(packet, OFFSET_TIME, "time")?[0],
        joints_rad: read_doubles(packet, OFFSET_Q_ACTUAL, "q actual")?,
        tool_actual: read_doubles(packet, OFFSET_TOOL_ACTUAL, "tool vector actual")?,
        tcp_speed: read_doubles(packet, OFFSET_TCP_SPEED, "TCP speed actual")?,
        tool_target: read_doubles(packet, OFFSET_TOOL_TARGET, "tool vector target")?,
        robot_mode: read_mode(packet, OFFSET_ROBOT_MODE, "robot mode")?,
        safety_mode: read_mode(packet, OFFSET_SAFETY_MODE, "safety mode")?,
        program_state,
    })
}

fn read_doubles<const N: usize>(
    packet: &[u8],
    offset: usize,
    field: &'static str,
) -> Result<[f64; N], HwError> {
    let mut out = [0.0; N];
    for (i, value) in out.iter_mut().enumerate() {
        let at = offset + 8 * i;
        let raw: [u8; 8] = packet
            .get(at..at + 8)
            .and_then(|b| b.try_into().ok())
            .ok_or(HwError::PacketTooShort {
                len: packet.len(),
                needed: at + 8,
            })?;
        *value = f64::from_be_bytes(raw);
        if !value.is_finite() {
            return Err(HwError::PacketNotFinite { field });
        }
    }
    Ok(out)
}

/// Modes are sent as doubles holding small integers.
fn read_mode(packet: &[u8], offset: usize, field: &'static str) -> Result<i32, HwError> {
    let value = read_doubles::<1>(packet, offset, field)?[0];
    if value.abs() > 1e6 {
        return Err(HwError::PacketNotFinite { field });
    }
    Ok(value.round() as i32)
}

/// Writes a CB3 3.5-sized packet holding `state` (other fields zero); used
/// by the fake controller and tests.
pub fn encode_packet(state: &RobotState) -> Vec<u8> {
    let mut packet = vec![0u8; CB3_PACKET_LEN];
    packet[..4].copy_from_slice(&(CB3_PACKET_LEN as i32).to_be_bytes());
    write_doubles(&mut packet, OFFSET_TIME, &[state.time_s]);
    write_doubles(&mut packet, OFFSET_Q_ACTUAL, &state.joints_rad);
    write_doubles(&mut packet, OFFSET_TOOL_ACTUAL, &state.tool_actual);
    write_doubles(&mut packet, OFFSET_TCP_SPEED, &state.tcp_speed);
    write_doubles(&mut packet, OFFSET_TOOL_TARGET, &state.tool_target);
    write_doubles(&mut packet, OFFSET_ROBOT_MODE, &[state.robot_mode as f64]);
    write_doubles(&mut packet, OFFSET_SAFETY_MODE, &[state.safety_mode as f64]);
    let program = state.program_state.unwrap_or(0) as f64;
    write_doubles(&mut packet, OFFSET_PROGRAM_STATE, &[program]);
    packet
}

fn write_doubles(packet: &mut [u8], offset: usize, values: &[f64]) {
    for (i, v) in values.iter().enumerate() {
        let at = offset + 8 * i;
        packet[at..at + 8].copy_from_slice(&v.to_be_bytes());
    }
}

/// Name of a robot mode (CB3/e-series numbering).
pub fn robot_mode_name(mode: i32) -> &'static str {
    match mode {
        -1 => "no controller",
        0 => "disconnected",
        1 => "confirm safety",
        2 => "booting",
        3 => "power off",
        4 => "power on",
        5 => "idle",
        6 => "backdrive",
        7 => "running",
        8 => "updating firmware",
        _ => "unknown",
    }
}

/// Name of a safety mode, and whether the arm is halted in it.
pub fn safety_mode_name(mode: i32) -> (&'static str, bool) {
    match mode {
        1 => ("normal", false),
        2 => ("reduced", false),
        3 => ("protective stop", true),
        4 => ("recovery", true),
        5 => ("safeguard stop", true),
        6 => ("system emergency stop", true),
        7 => ("robot emergency stop", true),
        8 => ("violation", true),
        9 => ("fault", true),
        _ => ("unknown", false),
    }
}

/// Fails when the state says the arm cannot move (safety stop, not running).
pub fn check_can_move(state: &RobotState) -> Result<(), HwError> {
    let (name, halted) = safety_mode_name(state.safety_mode);
    if halted {
        return Err(HwError::SafetyStop {
            mode: state.safety_mode,
            name,
        });
    }
    if state.robot_mode != ROBOT_MODE_RUNNING {
        return Err(HwError::NotRunning {
            mode: state.robot_mode,
            name: robot_mode_name(state.robot_mode),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> RobotState {
        RobotState {
            time_s: 12.5,
            joints_rad: [0.1, -1.2, 1.3, -1.6, -1.57, 0.0],
            tool_actual: [0.4, -0.1, 0.25, 3.0, 0.01, -0.02],
            tcp_speed: [0.01, 0.0, 0.0, 0.0, 0.0, 0.0],
            tool_target: [0.41, -0.1, 0.25, 3.0, 0.01, -0.02],
            robot_mode: ROBOT_MODE_RUNNING,
            safety_mode: SAFETY_MODE_NORMAL,
            program_state: Some(2),
        }
    }

    #[test]
    fn encode_then_parse_is_identity() {
        let state = sample();
        assert_eq!(parse_packet(&encode_packet(&state)).unwrap(), state);
    }

    #[test]
    fn tool_vector_sits_at_byte_444() {
        let packet = encode_packet(&sample());
        let x = f64::from_be_bytes(packet[444..452].try_into().unwrap());
        let rz = f64::from_be_bytes(packet[484..492].try_into().unwrap());
        assert_eq!((x, rz), (0.4, -0.02));
        assert_eq!(i32::from_be_bytes(packet[..4].try_into().unwrap()), 1108);
    }

    #[test]
    fn cb3_1_packet_has_no_program_state() {
        let mut packet = encode_packet(&sample());
        packet.truncate(1044);
        packet[..4].copy_from_slice(&1044i32.to_be_bytes());
        let state = parse_packet(&packet).unwrap();
        assert_eq!(state.program_state, None);
        assert_eq!(state.tool_actual, sample().tool_actual);
    }

    #[test]
    fn malformed_packets_are_errors_not_panics() {
        let good = encode_packet(&sample());
        assert!(matches!(
            parse_packet(&[]),
            Err(HwError::PacketTooShort { .. })
        ));
        assert!(matches!(
            parse_packet(&good[..500]),
            Err(HwError::PacketTooShort { .. })
        ));
        let mut tiny = good.clone();
        tiny[..4].copy_from_slice(&12i32.to_be_bytes());
        assert!(matches!(
            parse_packet(&tiny),
            Err(HwError::PacketLength { declared: 12, .. })
        ));
        let mut huge = good.clone();
        huge[..4].copy_from_slice(&(-5i32).to_be_bytes());
        assert!(matches!(
            parse_packet(&huge),
            Err(HwError::PacketLength { .. })
        ));
        let mut nan = good.clone();
        nan[452..460].copy_from_slice(&f64::NAN.to_be_bytes());
        assert!(matches!(
            parse_packet(&nan),
            Err(HwError::PacketNotFinite { .. })
        ));
    }

    #[test]
    fn protective_stop_and_idle_block_moves() {
        let mut state = sample();
        assert!(check_can_move(&state).is_ok());
        state.safety_mode = 3;
        assert!(matches!(
            check_can_move(&state),
            Err(HwError::SafetyStop { mode: 3, .. })
        ));
        state.safety_mode = 1;
        state.robot_mode = 5;
        assert!(matches!(
            check_can_move(&state),
            Err(HwError::NotRunning { mode: 5, .. })
        ));
    }
}
