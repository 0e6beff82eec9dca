//! The policy: pose-based tactile servo (PBTS) control, report ch. 5.1.
//!
//! A PI(D) controller in the sensor frame: error e = s* - s(m) (eq. 5.3),
//! delta_s = Kp e + Ki F(sum e) + Kd (e - e_prev) (eq. 5.5-5.6, derivative
//! term from the report's further work), anti-windup F clipping the integral,
//! and the move applied in the robot frame by quaternion composition
//! (eq. 5.7-5.8). Frames and sign conventions: see [`pbts`].
//!
//! [`se3`] is the same controller in SE(3) for the field's surface and
//! edge tasks ([`Task`]): an error on the relative transform between the
//! reference and the predicted pose, the planar loop its special case.

mod error;
pub mod pbts;
pub mod policy;
pub mod se3;
mod task;

pub use error::ControlError;

pub use pbts::{next_pose, PbtsConfig, PbtsController, SensedPose};
pub use policy::{CurvatureEstimate, PolicyConfig};
pub use se3::{
    apply_servo, heading_error_deg, se3_error, Se3Config, Se3Controller, EDGE_MOVE_CLIP,
};
pub use task::{Task, COMPONENTS};
