//! Typed errors of the control crate.

/// What can be wrong with a controller configuration or input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControlError {
    /// A gain, reference or bound that is NaN or infinite.
    #[error("controller setting {field}[{index}] is not finite")]
    NonFinite { field: &'static str, index: usize },
    /// A negative bound (anti-windup or the move's).
    #[error("{field}[{index}] = {value} must be >= 0")]
    NegativeClip {
        field: &'static str,
        index: usize,
        value: f64,
    },
    /// Policy settings that cannot work (see `PolicyConfig`).
    #[error("controller {reason}")]
    Policy { reason: String },
    /// A pose prediction that is NaN or infinite.
    #[error("sensed pose r = {r_mm} mm, theta = {theta_deg} deg is not finite")]
    NonFiniteInput { r_mm: f64, theta_deg: f64 },
    /// A component of a 6-DoF pose prediction that is NaN or infinite.
    #[error("predicted pose component {component} = {value} is not finite")]
    NonFinitePrediction { component: &'static str, value: f64 },
}
