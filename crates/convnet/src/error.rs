//! The crate's one error type: bad data, a bad configuration, a diverged
//! fit and a corrupt model file are told apart by variant, never by text.
use thiserror::Error;

/// Everything that can go wrong while fitting, predicting or
/// (de)serialising a convolutional model.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ConvError {
    /// A buffer does not have the length its declared shape implies.
    #[error("{what}: expected {expected} values, got {got}")]
    Shape {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    /// Training needs at least one frame (and as many target rows).
    #[error("no frames to train on")]
    Empty,
    /// A target value is NaN or infinite.
    #[error("target {column} of frame {row} is not a finite number ({value})")]
    NonFinite {
        row: usize,
        column: usize,
        value: f64,
    },
    /// A pin value is NaN or infinite.
    #[error("pin value {column} of frame {row} is not a finite number ({value})")]
    PinNonFinite {
        row: usize,
        column: usize,
        value: f64,
    },
    /// A pins-and-pixels model was given frames without each one's pin
    /// displacement vector (`got` 0), or vectors of another length.
    #[error(
        "the model reads {expected} pin values a frame beside its pixels, the frames carry {got}"
    )]
    PinCount { expected: usize, got: usize },
    /// A frame of another size than the model's input.
    #[error("frame size {got_height} x {got_width} px, the model takes {height} x {width} px")]
    FrameSize {
        height: usize,
        width: usize,
        got_height: usize,
        got_width: usize,
    },
    /// An angle's sine column whose cosine column (the next) lies past the
    /// row's `dim` targets, or that overlaps another angle's pair.
    #[error("angle column {column} (a sine, its cosine next) does not fit {dim} target columns or overlaps another angle")]
    AngleColumns { column: usize, dim: usize },
    /// A turned vector's column that lies past the row's `dim` targets or
    /// is already an angle's or another vector's.
    #[error("vector column {column} does not fit {dim} target columns or is taken by an angle or another vector")]
    VectorColumns { column: usize, dim: usize },
    /// A configuration value is out of range.
    #[error("invalid configuration: {field}: {reason}")]
    Config { field: &'static str, reason: String },
    /// Training diverged: the epoch's mean loss is not a finite number, or
    /// exceeds `limit` (`DIVERGENCE_FACTOR` times the loss of predicting
    /// the training mean).
    #[error(
        "training diverged at epoch {epoch}: loss {loss:.4e} {}; lower the learning rate",
        if loss.is_finite() { format!("exceeds {limit:.4e}") } else { "is not a finite number".into() }
    )]
    Diverged { epoch: usize, loss: f64, limit: f64 },
    /// A serialised model has another format version.
    #[error("convolutional model format version {found} is not supported (this build reads version {supported})")]
    Version { found: u32, supported: u32 },
    /// A serialised model could not be parsed or is inconsistent.
    #[error("corrupt convolutional model: {reason}")]
    Corrupt { reason: String },
}

impl ConvError {
    /// Whether the error is the caller's input (data, configuration, model
    /// file) rather than a run that failed (divergence): exit 2 against 1.
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, ConvError::Diverged { .. })
    }
}

/// A [`ConvError::Config`].
pub(crate) fn config_error(field: &'static str, reason: impl Into<String>) -> ConvError {
    ConvError::Config {
        field,
        reason: reason.into(),
    }
}
