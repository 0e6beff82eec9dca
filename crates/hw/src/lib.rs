//! Real hardware behind tactrace's traits: a UR5 arm and the TacTip camera.
//!
//! - [`Ur5Arm`] implements `tactrace_arm::Arm` over plain TCP (std::net):
//!   URScript `movel` to the secondary interface, pose feedback from the
//!   real-time interface. [`FakeUrController`] is a loopback stand-in for
//!   tests. Always wrap the real arm in `tactrace_arm::LimitedArm`.
//! - [`CameraSensor`] implements `tactrace_sensor::TactileSensor` over any
//!   [`FrameSource`] ([`CommandSource`] runs an external capture program,
//!   [`FolderSource`] replays a folder), with the Bristol TacTip
//!   preprocessing (grayscale, crop, median blur, adaptive threshold,
//!   resize) in [`Preprocess`].
//!
//! See docs/hardware.md for running on a real rig.

pub mod camera;
mod error;
pub mod ur5;

pub use camera::{
    adaptive_threshold, CameraSensor, CommandSource, CommandSourceConfig, FolderSource,
    FrameSource, Preprocess, PreprocessConfig, ThresholdMethod,
};
pub use error::HwError;
pub use ur5::{
    FakeBehaviour, FakeUrController, FakeUrOptions, RobotState, StateInterface, Ur5Arm, Ur5Config,
};
