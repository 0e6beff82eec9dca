//! The dashboard client against the fake dashboard server, and the state
//! probe of `rig check` against the fake controller.
use std::time::Duration;

use tactrace_hw::{
    probe_state, Dashboard, FakeDashboard, FakeDashboardState, FakeUrController, FakeUrOptions,
    HwError, StateInterface,
};

const TIMEOUT: Duration = Duration::from_secs(5);

fn dashboard(state: FakeDashboardState) -> (FakeDashboard, Dashboard) {
    let fake = FakeDashboard::start(state, Duration::from_secs(15)).unwrap();
    let client = Dashboard::connect("127.0.0.1", fake.port(), TIMEOUT).unwrap();
    (fake, client)
}

#[test]
fn session_set_up_steps_on_an_e_series() {
    let (fake, mut d) = dashboard(FakeDashboardState {
        safety_status: "PROTECTIVE_STOP".into(),
        ..FakeDashboardState::default()
    });
    assert!(d
        .greeting()
        .starts_with("Connected: Universal Robots Dashboard Server"));
    assert_eq!(d.robot_mode().unwrap(), "RUNNING");
    assert_eq!(d.safety_status().unwrap(), "PROTECTIVE_STOP");
    let version = d.polyscope_version().unwrap();
    assert_eq!((version.major, version.minor), (5, 11));
    assert_eq!(d.is_in_remote_control().unwrap(), Some(true));
    d.close_safety_popup().unwrap();
    d.unlock_protective_stop().unwrap();
    assert_eq!(d.safety_status().unwrap(), "NORMAL");
    // Unlocking again is refused by the controller: a typed error.
    assert!(matches!(
        d.unlock_protective_stop(),
        Err(HwError::Dashboard { .. })
    ));
    assert!(matches!(d.play(), Err(HwError::Dashboard { reply, .. }) if reply.contains("Failed")));
    let err = d.load("missing.urp").unwrap_err();
    assert!(
        err.to_string().contains("File not found: missing.urp"),
        "{err}"
    );
    d.load("tactrace.urp").unwrap();
    d.play().unwrap();
    assert_eq!(
        d.program_state().unwrap(),
        ("PLAYING".to_string(), "tactrace.urp".to_string())
    );
    assert!(fake
        .commands()
        .contains(&"unlock protective stop".to_string()));
}

#[test]
fn a_cb3_has_no_remote_control_query() {
    let (_fake, mut d) = dashboard(FakeDashboardState {
        version: "URSoftware 3.15.7.106331 (Sep 21 2021)".into(),
        remote_control: None,
        ..FakeDashboardState::default()
    });
    assert_eq!(d.is_in_remote_control().unwrap(), None);
    assert!(!d.polyscope_version().unwrap().has_remote_control());
}

#[test]
fn the_state_probe_reads_rtde_and_realtime_without_commanding() {
    for state in [StateInterface::Rtde, StateInterface::Realtime] {
        let fake = FakeUrController::start(FakeUrOptions {
            state,
            ..FakeUrOptions::default()
        })
        .unwrap();
        let probe = probe_state(&fake.config()).unwrap();
        assert!((probe.tcp_work.x - 400.0).abs() < 1e-9, "{probe:?}");
        assert!((probe.tcp_work.z - 300.0).abs() < 1e-9, "{probe:?}");
        assert_eq!(probe.state.robot_mode, 7);
        assert_eq!(probe.controller.is_some(), state == StateInterface::Rtde);
        assert!(fake.received_lines().is_empty(), "nothing was commanded");
    }
}
