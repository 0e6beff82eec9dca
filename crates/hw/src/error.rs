//! The one error type of the hardware crate.
//!
//! Every failure on the real rig (network, protocol, robot safety state,
//! camera command, image decoding, bad configuration) is a [`HwError`]
//! variant with structured fields, so callers can react without parsing
//! text. At the trait seams it is converted into `ArmError::Hardware` or the
//! sensor crate's error.
use std::path::PathBuf;

use thiserror::Error;

/// Errors of the UR5 driver, the camera sources and the preprocessing.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum HwError {
    /// A TCP connection could not be opened.
    #[error("cannot connect to {addr}: {source}")]
    Connect {
        addr: String,
        #[source]
        source: std::io::Error,
    },
    /// Reading or writing an open connection or a file failed.
    #[error("i/o error on {what}: {source}")]
    Io {
        what: String,
        #[source]
        source: std::io::Error,
    },
    /// A realtime packet's declared length is implausible.
    #[error("realtime packet declares {declared} bytes, expected {min}..={max}")]
    PacketLength {
        declared: i64,
        min: usize,
        max: usize,
    },
    /// A realtime packet is shorter than the fields read from it.
    #[error("realtime packet has {len} bytes, need at least {needed}")]
    PacketTooShort { len: usize, needed: usize },
    /// A realtime field holds NaN or infinity.
    #[error("realtime field `{field}` is not finite")]
    PacketNotFinite { field: &'static str },
    /// The realtime state stream stopped or failed.
    #[error("robot state stream failed: {reason}")]
    StateStream { reason: String },
    /// No state packet arrived in time.
    #[error("timeout: no robot state within {seconds} s")]
    NoState { seconds: f64 },
    /// The arm did not reach its target in time (message starts "timeout").
    #[error(
        "timeout after {seconds} s moving to {target}: still {position_error_mm:.3} mm \
         and {rotation_error_deg:.3} deg away"
    )]
    MoveTimeout {
        seconds: f64,
        target: String,
        position_error_mm: f64,
        rotation_error_deg: f64,
    },
    /// The controller reports a protective, safeguard or emergency stop.
    #[error("robot halted: safety mode {mode} ({name})")]
    SafetyStop { mode: i32, name: &'static str },
    /// The controller reports a robot mode in which it cannot move.
    #[error("robot not running: robot mode {mode} ({name})")]
    NotRunning { mode: i32, name: &'static str },
    /// A pose component is NaN or infinite.
    #[error("pose component `{component}` is not finite")]
    PoseNotFinite { component: &'static str },
    /// Text that should hold a URScript pose `p[...]` does not.
    #[error("bad URScript pose `{text}`: {reason}")]
    ScriptPose { text: String, reason: String },
    /// A configuration value is out of range.
    #[error("invalid configuration `{field}`: {reason}")]
    Config { field: &'static str, reason: String },
    /// The preprocessing cannot take a camera image (its settings are
    /// invalid, its crop box does not fit, the image is not the size a
    /// sensor file was made for).
    #[error("camera image preprocessing: {source}")]
    Preprocess {
        #[source]
        source: tactrace_vision::VisionError,
    },
    /// An image file could not be decoded.
    #[error("cannot decode image {path}: {source}")]
    Image {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    /// The external capture command failed.
    #[error("capture command `{command}` failed: {reason}")]
    Command { command: String, reason: String },
    /// A folder source found no image files.
    #[error("no image files in {dir}")]
    EmptyFolder { dir: PathBuf },
    /// A folder source has handed out all its frames.
    #[error("folder source exhausted after {count} frames")]
    Exhausted { count: usize },
    /// The RTDE interface (port 30004) broke its protocol or refused a
    /// request (a field it does not know, a version it does not speak).
    #[error("RTDE: {reason}")]
    Rtde { reason: String },
    /// The dashboard server (port 29999) answered a command with an error.
    #[error("dashboard `{command}`: {reply}")]
    Dashboard { command: String, reply: String },
    /// No camera device at this path.
    #[error("no camera at {device}: check the cable and `tactrace camera list`")]
    CameraMissing { device: String },
    /// Another program holds the camera.
    #[error("camera {device} is busy: another program (a browser, ffmpeg, guvcview) holds it")]
    CameraBusy { device: String },
    /// The camera offers none of the usable pixel formats.
    #[error("camera {device} offers no usable format (GREY, YUYV or MJPG); it offers {offered}")]
    CameraFormat { device: String, offered: String },
    /// No frame arrived in time.
    #[error("timeout: camera {device} gave no frame within {seconds} s")]
    CameraTimeout { device: String, seconds: f64 },
    /// The camera went away while open.
    #[error("camera {device} was unplugged")]
    CameraUnplugged { device: String },
    /// Another failure talking to the camera.
    #[error("camera {device}: {source}")]
    CameraIo {
        device: String,
        #[source]
        source: std::io::Error,
    },
    /// A camera buffer that cannot be a frame of the negotiated format.
    #[error("bad camera frame: {reason}")]
    FrameData { reason: String },
    /// The controller reports a state no UR arm can be in (a tool pose far
    /// outside any UR arm's reach, a rotation vector longer than a turn, a
    /// non-finite number): a hardware fault; nothing is moved on it.
    #[error("the controller reports an impossible {field}: {reason}")]
    ImplausibleState { field: &'static str, reason: String },
    /// A SIGINT or SIGTERM stopped the run; a connected arm was sent
    /// `stopl` first.
    #[error("interrupted by {signal}")]
    Interrupted { signal: crate::StopSignal },
    /// A SIGINT or SIGTERM asked for a stop and `stopl` could not be sent.
    #[error("interrupted by {signal}, but stopl could not be sent")]
    StopFailed {
        signal: crate::StopSignal,
        #[source]
        source: Box<HwError>,
    },
    /// A controller sent more than one reply may hold (a line that does
    /// not end).
    #[error("{what}: more than {limit} bytes without a line end")]
    ReplyTooLong { what: String, limit: usize },
    /// A camera path that is no V4L2 capture device (a regular file, a
    /// folder, /dev/null).
    #[error("{device} is not a camera: {reason}")]
    NotACamera { device: String, reason: String },
    /// The collection metadata (collection_meta.json) could not be used.
    #[error("collection metadata: {reason}")]
    Meta { reason: String },
}

impl From<HwError> for tactrace_arm::ArmError {
    fn from(err: HwError) -> Self {
        tactrace_arm::ArmError::Hardware(std::sync::Arc::new(err))
    }
}
