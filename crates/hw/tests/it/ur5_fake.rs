//! The UR5 driver against the loopback fake controller: moves, read-back,
//! work frame, timeout, malformed packets and protective stops.
use std::time::{Duration, Instant};

use tactrace_arm::{Arm, ArmError};
use tactrace_geometry::Pose;
use tactrace_hw::ur5::script::{script_to_pose, work_to_base};
use tactrace_hw::{FakeBehaviour, FakeUrController, FakeUrOptions, HwError, Ur5Arm};

fn fake(behaviour: FakeBehaviour) -> FakeUrController {
    FakeUrController::start(FakeUrOptions {
        behaviour,
        lifetime: Duration::from_secs(15),
        ..FakeUrOptions::default()
    })
    .expect("fake controller starts")
}

/// Waits up to 1 s for the fake to have received a line containing `text`.
fn wait_for_line(server: &FakeUrController, text: &str) -> bool {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(1) {
        if server.received_lines().iter().any(|l| l.contains(text)) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    false
}

fn assert_pose_near(a: Pose, b: Pose, tol_mm: f64, tol_deg: f64) {
    let (ia, ib) = (a.to_isometry(), b.to_isometry());
    let dp = (ia.translation.vector - ib.translation.vector).norm();
    let dr = ia.rotation.angle_to(&ib.rotation).to_degrees();
    assert!(
        dp <= tol_mm && dr <= tol_deg,
        "{a:?} vs {b:?}: {dp} mm, {dr} deg"
    );
}

#[test]
fn connect_then_move_twice_and_read_back() {
    let server = fake(FakeBehaviour::Follow);
    let mut config = server.config();
    config.work_frame = Pose::new(288.0, 0.0, -100.0, 0.0, 0.0, -90.0);
    config.tcp = Pose::new(0.0, 0.0, 101.0, 0.0, 0.0, 0.0);
    let mut arm = Ur5Arm::connect(config.clone()).expect("connects");
    // Start pose of the fake: base (400, 0, 300) mm, flange down (rx = 180).
    let start_base = Pose::new(400.0, 0.0, 300.0, 180.0, 0.0, 0.0).to_isometry();
    let expected_start = tactrace_hw::ur5::script::base_to_work(config.work_frame, &start_base);
    assert_pose_near(arm.pose(), expected_start, 1e-6, 1e-6);

    let first = Pose::new(10.0, -5.0, 120.0, 180.0, 0.0, 30.0);
    let second = Pose::new(12.5, -5.0, 115.0, 180.0, 0.0, 25.0);
    for target in [first, second] {
        arm.move_to(target).expect("move reaches target");
        assert_eq!(arm.pose(), target);
        assert_pose_near(arm.actual_pose().unwrap(), target, 0.1, 0.1);
    }
    arm.tap_down(5.0).expect("tap down");
    assert!((arm.pose().z - 110.0).abs() < 1e-12);

    // The controller saw set_tcp and movel in base-frame metres.
    let lines = server.received_lines();
    assert!(lines
        .iter()
        .any(|l| l.contains("set_tcp(p[0.000000, 0.000000, 0.101000")));
    let movel: Vec<&String> = lines.iter().filter(|l| l.contains("movel(")).collect();
    assert_eq!(movel.len(), 3, "{lines:?}");
    let literal = &movel[0][movel[0].find("p[").unwrap()..=movel[0].find(']').unwrap()];
    let sent = script_to_pose(literal).unwrap().to_isometry();
    let want = work_to_base(config.work_frame, first);
    assert!((sent.translation.vector - want.translation.vector).norm() < 1e-3);
    assert!(movel[0].contains("a=0.1000, v=0.0100"), "{}", movel[0]);
}

#[test]
fn frozen_arm_times_out_with_a_hardware_error() {
    let server = fake(FakeBehaviour::IgnoreMoves);
    let mut config = server.config();
    config.timeout_s = 0.3;
    let mut arm = Ur5Arm::connect(config).unwrap();
    let before = arm.pose();
    let start = Instant::now();
    let err = arm
        .move_to(Pose {
            z: before.z - 20.0,
            ..before
        })
        .unwrap_err();
    assert!(start.elapsed() < Duration::from_secs(3));
    assert!(
        matches!(&err, ArmError::Hardware(m) if m.downcast_ref::<tactrace_hw::HwError>().is_some() && m.to_string().starts_with("timeout")),
        "{err:?}"
    );
    assert_eq!(arm.pose(), before, "a failed move does not change the pose");
    assert!(
        wait_for_line(&server, "stopl("),
        "no stopl after the timeout"
    );
}

#[test]
fn malformed_packet_is_an_error_not_a_panic() {
    let server = fake(FakeBehaviour::MalformedOnMove);
    let mut arm = Ur5Arm::connect(server.config()).unwrap();
    let target = Pose {
        x: arm.pose().x + 1.0,
        ..arm.pose()
    };
    let err = arm.move_to(target).unwrap_err();
    assert!(
        matches!(&err, ArmError::Hardware(m) if m.downcast_ref::<tactrace_hw::HwError>().is_some() && m.to_string().contains("realtime packet")),
        "{err:?}"
    );
    // The stream stays failed: later calls error too, still without panics.
    assert!(arm.actual_pose().is_err());
    assert!(arm.move_to(target).is_err());
}

#[test]
fn protective_stop_aborts_the_move() {
    let server = fake(FakeBehaviour::ProtectiveStopOnMove);
    let mut arm = Ur5Arm::connect(server.config()).unwrap();
    let target = Pose {
        y: arm.pose().y + 3.0,
        ..arm.pose()
    };
    let err = arm.move_to(target).unwrap_err();
    assert!(
        matches!(&err, ArmError::Hardware(m) if m.downcast_ref::<tactrace_hw::HwError>().is_some() && m.to_string().contains("protective stop")),
        "{err:?}"
    );
}

#[test]
fn non_finite_target_is_refused_before_sending() {
    let server = fake(FakeBehaviour::Follow);
    let mut arm = Ur5Arm::connect(server.config()).unwrap();
    let err = arm
        .move_to(Pose {
            x: f64::NAN,
            ..arm.pose()
        })
        .unwrap_err();
    assert!(matches!(err, ArmError::NonFinitePose { .. }), "{err:?}");
    assert!(!server.received_lines().iter().any(|l| l.contains("movel(")));
}

#[test]
fn nobody_listening_is_a_connect_error() {
    // Bind then drop a listener to get a loopback port that refuses.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut config = tactrace_hw::Ur5Config::new("127.0.0.1");
    config.command_port = port;
    config.timeout_s = 1.0;
    assert!(matches!(
        Ur5Arm::connect(config),
        Err(HwError::Connect { .. })
    ));
}

#[test]
fn fake_controller_stops_by_itself() {
    let server = FakeUrController::start(FakeUrOptions {
        lifetime: Duration::from_millis(200),
        ..FakeUrOptions::default()
    })
    .unwrap();
    let mut config = server.config();
    config.timeout_s = 2.0;
    let arm = Ur5Arm::connect(config);
    if let Ok(arm) = arm {
        std::thread::sleep(Duration::from_millis(400));
        assert!(matches!(
            arm.actual_pose(),
            Err(HwError::StateStream { .. })
        ));
    }
    let start = Instant::now();
    drop(server);
    assert!(start.elapsed() < Duration::from_secs(1));
}

#[test]
fn limited_ur5_refuses_moves_outside_the_box() {
    use tactrace_arm::{LimitMode, LimitedArm, Workspace};
    let server = fake(FakeBehaviour::Follow);
    let mut config = server.config();
    // Fake start: base (400, 0, 300) mm -> work (0, 0, 50) with this frame.
    config.work_frame = Pose::new(400.0, 0.0, 250.0, 0.0, 0.0, 0.0);
    let arm = Ur5Arm::connect(config).unwrap();
    assert_pose_near(
        arm.pose(),
        Pose::new(0.0, 0.0, 50.0, 180.0, 0.0, 0.0),
        1e-6,
        1e-6,
    );
    let mut limited = LimitedArm::new(arm, Workspace::default(), LimitMode::Refuse);
    let inside = Pose::new(5.0, -5.0, 40.0, 180.0, 0.0, 0.0);
    limited.move_to(inside).expect("move inside the box");
    let outside = Pose { x: 400.0, ..inside };
    let err = limited.move_to(outside).unwrap_err();
    assert!(
        matches!(err, ArmError::OutsideWorkspace { axis: 'x', .. }),
        "{err:?}"
    );
    assert_eq!(limited.pose(), inside);
    let sent = server
        .received_lines()
        .iter()
        .filter(|l| l.contains("movel("))
        .count();
    assert_eq!(sent, 1, "the refused move never reached the controller");
}
