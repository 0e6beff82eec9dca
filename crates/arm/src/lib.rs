//! The arm: a robot that moves the tactile sensor and taps it on objects.
//!
//! [`Arm`] is the hardware seam. [`SimArm`] is the simulated UR5-class arm
//! (poses reached up to a configurable repeatability); [`LimitedArm`] wraps
//! any arm and refuses or clamps moves outside a workspace box or larger
//! than a maximum step (and, optionally, tilted beyond a largest angle).
//! A real UR5 driver implements the same trait. Poses are full 6-DoF
//! (orientation as a quaternion inside; any tilt).
//! [`FinitePose`] is a pose checked to be finite, which the limiter and the
//! real arm's driver work on.

mod error;
mod finite;
mod limiter;
mod sim;
mod tilt;
mod traits;

pub use error::{ArmError, DriverError};
pub use finite::FinitePose;
pub use limiter::{LimitMode, LimitedArm, Workspace};
pub use sim::{PoseProbe, SimArm, SimArmConfig};
pub use tactrace_geometry::Pose;
pub use tilt::{level_to, tilt_deg};
pub use traits::Arm;
