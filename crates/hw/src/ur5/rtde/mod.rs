//! RTDE, the Real-Time Data Exchange interface of UR controllers (port
//! 30004): named-field recipes streamed at up to 125 Hz (CB3) or 500 Hz
//! (e-series). UR recommend it over the fixed-layout real-time interface
//! (port 30003), deprecated since software 3.5.
//!
//! - `protocol`: packages, field types and values (pure, no I/O);
//! - [`RtdeClient`]: the handshake, recipes, start/pause and data;
//! - [`FakeRtdeServer`] / [`RtdeSession`]: the controller side, for tests
//!   and for checking independent clients (`ur_rtde`) against it.

mod client;
mod fake;
pub mod protocol;

pub use client::{
    start_state_stream, state_from_values, state_values, ControllerVersion, Recipe, RtdeClient,
    MAX_TEXT_MESSAGES, STATE_FIELDS,
};
pub use fake::{resting_state, FakeRtdeOptions, FakeRtdeServer, RtdeSession};
