//! The calibration's errors: every way the input can be wrong, each with
//! what was expected, so the CLI can print it once and exit 2.
use thiserror::Error;

/// Errors of the calibration library.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum CalibError {
    /// Fewer paired taps than the fit needs.
    #[error("too few calibration taps: {got} given, at least {needed} needed ({recommended} recommended)")]
    TooFewTaps {
        got: usize,
        needed: usize,
        recommended: usize,
    },
    /// The taps do not span edge position r and angle theta.
    #[error("calibration taps do not span r and theta: {reason}")]
    NoSpan { reason: String },
    /// Two things that must have the same size do not (pin counts, tap counts).
    #[error("mismatched dimensions: {what}: expected {expected}, found {found}")]
    Dimension {
        what: String,
        expected: usize,
        found: usize,
    },
    /// A NaN, infinite or missing label.
    #[error("label of tap {index} is missing or not finite (r {r}, theta {theta})")]
    BadLabel { index: usize, r: f64, theta: f64 },
    /// A NaN or infinite value in a displacement field.
    #[error("{what}: tap {index} has a non-finite value at coordinate {coord}")]
    BadField {
        what: String,
        index: usize,
        coord: usize,
    },
    /// A correction record or tensor set that this version cannot read.
    #[error("calibration record: {0}")]
    Record(String),
    /// Parameters that make no sense (empty penalty grid, zero taps asked).
    #[error("invalid parameter: {0}")]
    Param(String),
}

/// Result with [`CalibError`].
pub type Result<T> = std::result::Result<T, CalibError>;
