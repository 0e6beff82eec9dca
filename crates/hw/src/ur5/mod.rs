//! The UR5 arm over TCP: URScript out (port 30002), state in over RTDE
//! (port 30004) or the real-time interface (port 30003), with pure
//! conversions and a loopback fake controller.
//!
//! Units and frames at the public boundary are those of the `Arm` trait:
//! the sensor tip in the work frame, mm and degrees (extrinsic x-y-z).
//! Metres and rotation vectors exist only on the wire (module `script`).

mod arm;
mod fake;
mod link;
pub mod realtime;
pub mod rtde;
pub mod script;

pub use arm::{StateInterface, Ur5Arm, Ur5Config, MAX_LINEAR_ACCEL_MM_S2, MAX_LINEAR_SPEED_MM_S};
pub use fake::{FakeBehaviour, FakeUrController, FakeUrOptions};
pub use realtime::RobotState;
