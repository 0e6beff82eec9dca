//! Typed errors of the arm crate: what a move can be refused for.
use tactrace_geometry::Pose;

/// The error a real robot driver reported, kept typed as the source.
pub type DriverError = std::sync::Arc<dyn std::error::Error + Send + Sync>;

/// Why an arm refused or failed a move.
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum ArmError {
    /// The target position leaves the workspace box along one axis.
    #[error("pose {} is outside the workspace: {axis} = {value_mm:.3} mm, allowed [{min_mm}, {max_mm}] mm", plain(.pose))]
    OutsideWorkspace {
        pose: Pose,
        axis: char,
        value_mm: f64,
        min_mm: f64,
        max_mm: f64,
    },
    /// The move is longer than the largest allowed single step.
    #[error("step of {step_mm:.3} mm exceeds the maximum of {max_mm} mm")]
    StepTooLarge { step_mm: f64, max_mm: f64 },
    /// The move turns the tool by more than the largest allowed rotation.
    #[error("rotation step of {step_deg:.3} deg exceeds the maximum of {max_deg} deg")]
    RotationTooLarge { step_deg: f64, max_deg: f64 },
    /// The target tilts the tool (its z axis from the work frame's) by more
    /// than the largest allowed tilt.
    #[error("tilt of {tilt_deg:.3} deg exceeds the maximum of {max_deg} deg")]
    TiltTooLarge { tilt_deg: f64, max_deg: f64 },
    /// A pose with a NaN or infinite component.
    #[error("pose {} has a non-finite component", plain(.pose))]
    NonFinitePose { pose: Pose },
    /// The arm reports a current pose with a NaN or infinite component: no
    /// step from it can be checked, so no move is made.
    #[error(
        "the arm's current pose {} has a non-finite component: no move can be checked from it",
        plain(.pose)
    )]
    CurrentPoseNotFinite { pose: Pose },
    /// A configuration value that cannot be used.
    #[error("invalid arm configuration: {field} = {value} ({reason})")]
    InvalidConfig {
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// A failure reported by a real robot driver (its error is the source).
    #[error("the arm's driver failed")]
    Hardware(#[source] DriverError),
}

/// A pose for people: position in mm and rotation in degrees (its debug form
/// `Pose { x: .. }` once reached the CLI's error messages).
fn plain(p: &Pose) -> String {
    p.to_string()
}
