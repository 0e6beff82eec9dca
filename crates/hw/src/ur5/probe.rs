//! Reading the arm's state once without commanding anything: what
//! `tactrace rig check` does before a run. The state is checked as the
//! driver's is ([`ArmState`]): one no UR arm can be in is an error.
use std::time::{Duration, Instant};

use tactrace_arm::FinitePose;

use super::arm::{StateInterface, Ur5Config};
use super::link::{connect, StateStream};
use super::rtde::{start_state_stream, state_from_values, ControllerVersion, RtdeClient};
use super::state::ArmState;
use crate::HwError;

/// One state read from the configured interface.
#[derive(Debug, Clone, PartialEq)]
pub struct StateProbe {
    /// The state, checked.
    pub state: ArmState,
    /// The measured TCP in the work frame, mm and degrees.
    pub tcp_work: FinitePose,
    /// The controller's version, when read over RTDE.
    pub controller: Option<ControllerVersion>,
}

/// Connects to the state interface of `config` only (no URScript is
/// sent), reads one state and hangs up. Blocks up to `timeout_s` for the
/// connection and the first state.
pub fn probe_state(config: &Ur5Config) -> Result<StateProbe, HwError> {
    config.validate()?;
    let timeout = Duration::from_secs_f64(config.timeout_s);
    let (state, controller) = match config.state {
        StateInterface::Rtde => {
            let stream = connect(&config.host, config.rtde_port, timeout)?;
            let mut client = RtdeClient::handshake(stream, timeout)?;
            start_state_stream(&mut client)?;
            let start = Instant::now();
            let values = loop {
                if let Some(values) = client.poll_data()? {
                    break values;
                }
                if start.elapsed() >= timeout {
                    return Err(HwError::NoState {
                        seconds: config.timeout_s,
                    });
                }
            };
            let _ = client.pause();
            let state = ArmState::check(state_from_values(&values)?)?;
            (state, Some(client.version()))
        }
        StateInterface::Realtime => {
            let stream = connect(&config.host, config.state_port, timeout)?;
            let states = StateStream::start(stream)?;
            (states.wait_newer(0, timeout)?.1, None)
        }
    };
    let tcp_work = state.tool_actual().in_work_frame(config.work_frame)?;
    Ok(StateProbe {
        state,
        tcp_work,
        controller,
    })
}
