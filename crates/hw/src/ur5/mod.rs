//! The UR5 arm over TCP: URScript out (port 30002), state in over RTDE
//! (port 30004) or the real-time interface (port 30003), with pure
//! conversions and a loopback fake controller.
//!
//! Units and frames at the public boundary are those of the `Arm` trait:
//! the sensor tip in the work frame, mm and degrees (extrinsic x-y-z).
//! Metres and rotation vectors exist only on the wire (module `script`).

mod arm;
mod dashboard;
mod dashboard_fake;
mod fake;
mod link;
mod probe;
pub mod realtime;
pub mod rtde;
pub mod script;
pub mod state;

pub use arm::{StateInterface, Ur5Arm, Ur5Config, MAX_LINEAR_ACCEL_MM_S2, MAX_LINEAR_SPEED_MM_S};
pub use dashboard::{Dashboard, PolyscopeVersion, DASHBOARD_PORT};
pub use dashboard_fake::{FakeDashboard, FakeDashboardState};
pub use fake::{FakeBehaviour, FakeStateFault, FakeUrController, FakeUrOptions};
pub use probe::{probe_state, StateProbe};
pub use realtime::RobotState;
pub use state::{ArmState, ToolPose, MAX_REACH_M};

/// A non-blocking listener of a loopback fake on 127.0.0.1:`port` (0: an
/// ephemeral port) and the port it got; errors name `what`.
pub(crate) fn fake_listener(
    port: u16,
    what: &str,
) -> Result<(std::net::TcpListener, u16), crate::HwError> {
    let io_err = |source| crate::HwError::Io {
        what: what.to_string(),
        source,
    };
    let listener = std::net::TcpListener::bind(("127.0.0.1", port)).map_err(io_err)?;
    listener.set_nonblocking(true).map_err(io_err)?;
    let port = listener.local_addr().map_err(io_err)?.port();
    Ok((listener, port))
}
