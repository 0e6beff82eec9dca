//! Issue 20 at the driver boundary, against the loopback fakes: a state no
//! UR arm can be in (far beyond reach, a huge rotation, NaN) is a typed
//! fault and nothing moves; a stop request during a move sends `stopl`;
//! what a controller sends is kept bounded (RTDE text messages, dashboard
//! replies).
use std::net::TcpStream;
use std::time::{Duration, Instant};

use tactrace_arm::{Arm, ArmError};
use tactrace_geometry::Pose;
use tactrace_hw::ur5::rtde::{
    FakeRtdeOptions, FakeRtdeServer, RtdeClient, MAX_TEXT_MESSAGES, STATE_FIELDS,
};
use tactrace_hw::{
    probe_state, Dashboard, FakeDashboard, FakeDashboardState, FakeStateFault, FakeUrController,
    FakeUrOptions, HwError, StateInterface, StopFlag, StopSignal, Ur5Arm,
};

fn fake(options: FakeUrOptions) -> FakeUrController {
    FakeUrController::start(FakeUrOptions {
        lifetime: Duration::from_secs(15),
        ..options
    })
    .expect("fake controller starts")
}

/// The reason of a state the driver refused, for either interface: typed
/// over RTDE and the real-time interface alike, or (NaN, refused by the
/// parsers already) the parsers' error or the stream's failure.
fn refused_state(err: &HwError) -> bool {
    match err {
        HwError::ImplausibleState { .. } | HwError::PacketNotFinite { .. } => true,
        HwError::StateStream { reason } => reason.contains("not finite"),
        _ => false,
    }
}

#[test]
fn an_impossible_state_is_a_fault_and_nothing_moves() {
    let faults = [
        (
            FakeStateFault::HugePosition,
            "1.000e306 m from the robot's base",
        ),
        (FakeStateFault::HugeRotation, "1.000e200 rad long"),
        (FakeStateFault::NotFinite, "not finite"),
    ];
    for state in [StateInterface::Realtime, StateInterface::Rtde] {
        for (fault, reason) in faults {
            let server = fake(FakeUrOptions {
                state,
                state_fault: fault,
                ..FakeUrOptions::default()
            });
            let mut config = server.config();
            config.timeout_s = 2.0;
            let err = Ur5Arm::connect(config.clone()).err().unwrap();
            assert!(refused_state(&err), "{state:?} {fault:?}: {err}");
            assert!(
                err.to_string().contains(reason),
                "{state:?} {fault:?}: {err}"
            );
            drop(server);
            // The probe of `rig check` refuses it the same way.
            let server = fake(FakeUrOptions {
                state,
                state_fault: fault,
                ..FakeUrOptions::default()
            });
            let mut config = server.config();
            config.timeout_s = 2.0;
            let err = probe_state(&config).err().unwrap();
            assert!(refused_state(&err), "probe {state:?} {fault:?}: {err}");
            let lines = server.received_lines();
            assert!(
                !lines.iter().any(|l| l.contains("movel")),
                "{state:?} {fault:?}: {lines:#?}"
            );
        }
    }
}

#[test]
fn a_stop_request_mid_move_sends_stopl_and_nothing_more() {
    let server = fake(FakeUrOptions {
        state: StateInterface::Rtde,
        speed_mm_s: 20.0,
        ..FakeUrOptions::default()
    });
    let stop = StopFlag::new();
    let mut arm = Ur5Arm::connect_stoppable(server.config(), stop.clone()).unwrap();
    let start = arm.pose();
    let asker = stop.clone();
    let signal = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(150));
        asker.request(StopSignal::Interrupt);
    });
    // 40 mm at 20 mm/s: two seconds, unless stopped.
    let began = Instant::now();
    let err = arm
        .move_to(Pose {
            x: start.x + 40.0,
            ..start
        })
        .unwrap_err();
    signal.join().unwrap();
    assert!(began.elapsed() < Duration::from_millis(1500), "not stopped");
    let ArmError::Hardware(source) = &err else {
        panic!("{err}");
    };
    assert!(
        matches!(
            source.downcast_ref::<HwError>(),
            Some(HwError::Interrupted {
                signal: StopSignal::Interrupt
            })
        ),
        "{err}: {source}"
    );
    assert!(stop.halted(), "the flag says the arm was halted");
    // Every later move is refused before anything is sent.
    assert!(arm.move_to(start).is_err());
    drop(arm);
    let deadline = Instant::now() + Duration::from_secs(3);
    while !server.finished() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(5));
    }
    let lines = server.received_lines();
    let moves = lines.iter().filter(|l| l.contains("movel(")).count();
    let last_move = lines.iter().rposition(|l| l.contains("movel(")).unwrap();
    assert_eq!(moves, 1, "{lines:#?}");
    assert!(
        lines[last_move..].iter().any(|l| l.contains("stopl(")),
        "no stopl after the move: {lines:#?}"
    );
}

#[test]
fn an_rtde_text_flood_keeps_only_the_newest_messages() {
    let flood = 100_000;
    let server = FakeRtdeServer::start(
        0,
        FakeRtdeOptions {
            greeting: Some("hello".into()),
            text_flood: flood,
            ..FakeRtdeOptions::default()
        },
    )
    .unwrap();
    let stream = TcpStream::connect(("127.0.0.1", server.port())).unwrap();
    let mut client = RtdeClient::handshake(stream, Duration::from_secs(10)).unwrap();
    client.setup_outputs(&STATE_FIELDS, 500.0).unwrap();
    client.start().unwrap();
    let start = Instant::now();
    while client.poll_data().unwrap().is_none() {
        assert!(start.elapsed() < Duration::from_secs(5), "no data");
    }
    assert_eq!(client.messages().len(), MAX_TEXT_MESSAGES);
    assert_eq!(
        client.dropped_messages(),
        (flood + 1 - MAX_TEXT_MESSAGES) as u64
    );
    assert!(client.messages().iter().all(|m| m.message.len() == 255));
}

#[test]
fn a_flooding_rtde_controller_still_gives_states() {
    // The fake serves one client: one for the probe, one for the arm.
    let flooding = || {
        fake(FakeUrOptions {
            state: StateInterface::Rtde,
            text_flood: 200,
            ..FakeUrOptions::default()
        })
    };
    let server = flooding();
    let probe = probe_state(&server.config()).unwrap();
    assert!((probe.tcp_work.x - 400.0).abs() < 1e-9, "{probe:?}");
    let server = flooding();
    let mut arm = Ur5Arm::connect(server.config()).unwrap();
    let start = arm.pose();
    arm.move_to(Pose {
        z: start.z - 5.0,
        ..start
    })
    .unwrap();
}

#[test]
fn an_endless_dashboard_reply_is_refused_at_the_line_limit() {
    let fake = FakeDashboard::start(
        FakeDashboardState {
            endless_greeting: true,
            ..FakeDashboardState::default()
        },
        Duration::from_secs(15),
    )
    .unwrap();
    let err = Dashboard::connect("127.0.0.1", fake.port(), Duration::from_secs(5))
        .err()
        .unwrap();
    assert!(
        matches!(err, HwError::ReplyTooLong { limit: 4096, .. }),
        "{err}"
    );
}
