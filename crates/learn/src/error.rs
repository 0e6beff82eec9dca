//! The learning crate's one error type, so callers can tell bad data from a
//! bad model file from a bad configuration without parsing strings.
use thiserror::Error;

/// Everything that can go wrong while fitting, predicting or (de)serialising.
#[derive(Debug, Error)]
pub enum LearnError {
    /// A buffer does not have the length its declared shape implies.
    #[error("{what}: expected {expected} values, got {got}")]
    Shape {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    /// A dataset needs at least one sample and one column.
    #[error("empty dataset ({n} samples, {dim_x} inputs, {dim_y} targets)")]
    Empty {
        n: usize,
        dim_x: usize,
        dim_y: usize,
    },
    /// A value in the data is NaN or infinite.
    #[error("non-finite {what} value {value} at row {row}, column {column}")]
    NonFinite {
        what: &'static str,
        row: usize,
        column: usize,
        value: f32,
    },
    /// The input vector handed to a model has the wrong length.
    #[error("dimension mismatch: the model expects {expected} inputs, got {got}")]
    DimensionMismatch { expected: usize, got: usize },
    /// A configuration value is out of range.
    #[error("invalid configuration: {field}: {reason}")]
    Config { field: &'static str, reason: String },
    /// A serialised model has another format version.
    #[error(
        "model format version {found} is not supported (this build reads version {supported})"
    )]
    Version { found: u32, supported: u32 },
    /// A serialised model could not be parsed or is inconsistent.
    #[error("corrupt model data: {reason}")]
    Corrupt { reason: String },
    /// Training produced non-finite weights (learning rate or beta too large).
    #[error(
        "training diverged in network {net} at epoch {epoch} (loss {loss}); \
         lower the learning rate (or beta), e.g. with --config"
    )]
    Diverged {
        net: String,
        epoch: usize,
        loss: f64,
    },
}
