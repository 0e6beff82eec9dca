//! Real hardware behind tactrace's traits: a UR5 arm and the TacTip camera.
//!
//! - [`Ur5Arm`] implements `tactrace_arm::Arm` over plain TCP (std::net):
//!   URScript `movel` to the secondary interface, the arm's state
//!   over RTDE (`ur5::rtde`, port 30004) or the real-time interface
//!   (port 30003). [`FakeUrController`] is a loopback stand-in for tests.
//!   Always wrap the real arm in `tactrace_arm::LimitedArm`. States are
//!   checked once as they are read ([`ArmState`]); a [`StopFlag`] set by
//!   SIGINT/SIGTERM makes the driver send `stopl` and stop.
//! - [`Dashboard`] talks to the dashboard server (port 29999) for the
//!   set-up steps (robot mode, safety status, unlock, load and play);
//!   [`FakeDashboard`] stands in for it; [`probe_state`] reads the arm's
//!   state once without commanding anything.
//! - [`CameraSensor`] implements `tactrace_sensor::TactileSensor` over any
//!   [`FrameSource`] (`camera::v4l2::V4l2Source` keeps a V4L2 camera
//!   open, [`CommandSource`] runs an external capture program,
//!   [`FolderSource`] replays a folder), through the preprocessing stage
//!   every command shares ([`Preprocess`], `tactrace_vision`: grey, crop,
//!   dome mask, median blur, threshold, resize), set by a sensor file or
//!   the rig file's `[preprocess]` table ([`PreprocessConfig`]).
//!
//! See docs/hardware.md for running on a real rig.

pub mod camera;
mod error;
mod stop;
pub mod ur5;

pub use camera::v4l2::{list_cameras, open_v4l2, CameraInfo, V4l2Config};
pub use camera::{
    CameraSensor, CommandSource, CommandSourceConfig, FolderSource, FrameSource, Preprocess,
    PreprocessConfig, ThresholdMethod,
};
pub use error::HwError;
pub use stop::{StopFlag, StopSignal};
pub use ur5::{
    probe_state, ArmState, Dashboard, FakeBehaviour, FakeDashboard, FakeDashboardState,
    FakeStateFault, FakeUrController, FakeUrOptions, PolyscopeVersion, RobotState, StateInterface,
    StateProbe, ToolPose, Ur5Arm, Ur5Config,
};
