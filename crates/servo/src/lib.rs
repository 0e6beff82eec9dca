//! The servo loop of report ch. 5 and everything it needs that does no I/O.
//!
//! [`servo_loop()`] taps, perceives ([`Perception`]: pins then the pose
//! model), asks the PBTS controller for a move and makes it, on any
//! [`tactrace_arm::Arm`] and [`tactrace_sensor::TactileSensor`]: the
//! simulated rig of this crate ([`SimRig`]), the real-frame world
//! ([`ReplayRig`]: a simulated arm, taps answered by saved real frames) or a
//! real UR5 and camera. Each
//! step goes to [`StepSink`]s (files and progress bars are sinks the caller
//! brings). [`metrics`] scores a finished trajectory against the true
//! contour, which the loop itself never sees.
//!
//! This crate writes no files and prints nothing.

pub mod error;
pub mod image_input;
pub mod metrics;
pub mod perception;
pub mod replay_rig;
pub mod rig;
pub mod servo_3d;
pub mod servo_loop;
pub mod start;

pub use error::{error_chain, Result, ServoError};
pub use image_input::ImageInput;
pub use metrics::{
    evaluate, l2_curve, l2_curve_arc_mm, traced_fraction, trajectory_closes, ClosureDetector,
    FollowMetrics,
};
pub use perception::{Percept, Perception};
pub use replay_rig::ReplayRig;
pub use rig::{tap, RigConfig, SimRig, TapConfig};
pub use servo_3d::{
    component_of, lifted, servo_loop_3d, servo_loop_3d_taps, Loop3dConfig, Perception3d, Sensed,
    Step3d,
};
pub use servo_loop::{servo_loop, Ending, FnSink, LoopConfig, LoopSummary, StepRecord, StepSink};
pub use start::{flattest_arc_mm, pose_at_edge, start_pose, StartConfig};
