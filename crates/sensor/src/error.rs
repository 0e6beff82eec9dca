//! Typed errors of the sensor crate: bad configuration, mismatched rest
//! layouts and unreadable frames, each naming what was wrong.
use std::path::PathBuf;

/// What can go wrong building a sensor model or capturing a frame.
#[derive(Debug, thiserror::Error)]
pub enum SensorError {
    /// A field correction that does not fit the sensor.
    #[error("invalid field correction: {reason}")]
    Correction { reason: String },
    /// A configuration value outside its valid range.
    #[error("invalid sensor config `{field}` = {value}: {reason}")]
    InvalidConfig {
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// Configuration values that would need more memory (or time) than
    /// the model allows: `reason` says how much and the bound.
    #[error("invalid sensor config `{field}` = {value}: {reason}")]
    TooLarge {
        field: &'static str,
        value: f64,
        reason: String,
    },
    /// Measured rest pins that do not fit the configured layout.
    #[error("rest pin layout mismatch: expected {expected} pins, got {got}: {reason}")]
    RestPins {
        expected: usize,
        got: usize,
        reason: String,
    },
    /// Measured rest pins that neither kind of layout fits: `source` says
    /// where the closer fit fails.
    #[error(
        "no pin layout fits the {pins} rest pins ({hex_px:.2} px RMS from a hexagonal \
         lattice, {rings_px:.2} px from concentric rings)"
    )]
    NoLayoutFits {
        pins: usize,
        hex_px: f64,
        rings_px: f64,
        #[source]
        source: Box<SensorError>,
    },
    /// A frame file that does not exist.
    #[error("frame file `{path}` does not exist")]
    FrameMissing { path: PathBuf },
    /// A frame file that could not be opened or read.
    #[error("cannot read frame file `{path}`: {reason}")]
    FrameUnreadable { path: PathBuf, reason: String },
    /// A file that is not in a supported image format.
    #[error("frame file `{path}` is not a supported image: {reason}")]
    NotAnImage { path: PathBuf, reason: String },
    /// An image file whose contents are damaged.
    #[error("frame file `{path}` is corrupt: {reason}")]
    CorruptFrame { path: PathBuf, reason: String },
    /// A bank of labelled frames that cannot answer (nearest-frame sensor).
    #[error("unusable bank of labelled frames: {0}")]
    Bank(String),
    /// The replay sensor has handed out every frame it was given.
    #[error("replay sensor exhausted: all {count} frames were already captured")]
    ReplayExhausted { count: usize },
}

impl SensorError {
    /// Whether the sensor's set-up is at fault (its configuration, field
    /// correction, rest layout or bank of frames), not a frame met while
    /// running: a bad input wherever it is found.
    pub fn is_config(&self) -> bool {
        matches!(
            self,
            SensorError::InvalidConfig { .. }
                | SensorError::TooLarge { .. }
                | SensorError::Correction { .. }
                | SensorError::RestPins { .. }
                | SensorError::NoLayoutFits { .. }
                | SensorError::Bank(_)
        )
    }
}
