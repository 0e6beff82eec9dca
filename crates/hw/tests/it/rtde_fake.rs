//! tactrace's RTDE client against the fake RTDE controller, and the UR5
//! driver reading its state over RTDE: handshake, recipes, data, inputs,
//! text messages, refusals, and the faults a run must survive (a lost
//! connection, a malformed package, a protective stop during a move).
use std::net::TcpStream;
use std::time::{Duration, Instant};

use tactrace_arm::{Arm, ArmError};
use tactrace_geometry::Pose;
use tactrace_hw::ur5::rtde::protocol::{FieldType, Value};
use tactrace_hw::ur5::rtde::{
    resting_state, state_from_values, ControllerVersion, FakeRtdeOptions, FakeRtdeServer,
    RtdeClient, STATE_FIELDS,
};
use tactrace_hw::{
    FakeBehaviour, FakeUrController, FakeUrOptions, HwError, StateInterface, Ur5Arm,
};

const TIMEOUT: Duration = Duration::from_secs(5);

fn server(options: FakeRtdeOptions) -> FakeRtdeServer {
    FakeRtdeServer::start(0, options).expect("fake RTDE server starts")
}

fn client(server: &FakeRtdeServer) -> RtdeClient {
    let stream = TcpStream::connect(("127.0.0.1", server.port())).unwrap();
    RtdeClient::handshake(stream, TIMEOUT).expect("handshake")
}

/// The next data package, waiting up to 2 s.
fn next_values(client: &mut RtdeClient) -> Vec<Value> {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(2) {
        if let Some(values) = client.poll_data().unwrap() {
            return values;
        }
    }
    panic!("no data package within 2 s");
}

#[test]
fn handshake_reports_the_controller_version_and_streams_the_state() {
    let cb3 = ControllerVersion {
        major: 3,
        minor: 15,
        bugfix: 7,
        build: 106331,
    };
    let server = server(FakeRtdeOptions {
        version: cb3,
        greeting: Some("hello from the fake".into()),
        ..FakeRtdeOptions::default()
    });
    let mut state = resting_state();
    state.tool_actual = [0.41, -0.12, 0.25, 3.0, 0.1, -0.2];
    state.safety_mode = 3;
    server.set_state(state);
    let mut client = client(&server);
    assert_eq!(client.version(), cb3);
    assert_eq!(client.version().max_frequency_hz(), 125.0);
    let recipe = client.setup_outputs(&STATE_FIELDS, 125.0).unwrap();
    assert_eq!(recipe.types[2], FieldType::Vector6d);
    client.start().unwrap();
    let got = state_from_values(&next_values(&mut client)).unwrap();
    assert_eq!(got.tool_actual, state.tool_actual);
    assert_eq!((got.robot_mode, got.safety_mode), (7, 3));
    // The text message sent before the start reply was kept, not lost.
    assert!(client
        .messages()
        .iter()
        .any(|m| m.message == "hello from the fake" && m.level == 3));
    // Paused: the stream stops; started again: it resumes.
    client.pause().unwrap();
    while client.poll_data().unwrap().is_some() {}
    std::thread::sleep(Duration::from_millis(30));
    assert_eq!(client.poll_data().unwrap(), None);
    client.start().unwrap();
    next_values(&mut client);
}

#[test]
fn unknown_fields_are_refused_by_name() {
    let server = server(FakeRtdeOptions::default());
    let mut client = client(&server);
    let err = client
        .setup_outputs(&["actual_TCP_pose", "actual_tcp_pose"], 125.0)
        .unwrap_err();
    assert!(
        matches!(&err, HwError::Rtde { reason } if reason.contains("actual_tcp_pose (NOT_FOUND)")),
        "{err}"
    );
    assert!(client.start().is_err(), "no recipe: start is refused");
}

#[test]
fn input_recipe_values_reach_the_controller() {
    let server = server(FakeRtdeOptions::default());
    let mut client = client(&server);
    client.setup_outputs(&["timestamp"], 500.0).unwrap();
    let inputs = client
        .setup_inputs(&["input_int_register_24", "input_double_register_24"])
        .unwrap();
    assert_eq!(inputs.types, [FieldType::Int32, FieldType::Double]);
    client.start().unwrap();
    client
        .send_inputs(&inputs, &[Value::Int32(-42), Value::Double(2.5)])
        .unwrap();
    assert!(client.send_inputs(&inputs, &[Value::Int32(1)]).is_err());
    let start = Instant::now();
    while server.received_inputs().len() < 2 && start.elapsed() < Duration::from_secs(2) {
        next_values(&mut client);
    }
    let got = server.received_inputs();
    assert_eq!(got["input_int_register_24"], Value::Int32(-42));
    assert_eq!(got["input_double_register_24"], Value::Double(2.5));
}

#[test]
fn a_dropped_connection_is_a_state_stream_error() {
    let server = server(FakeRtdeOptions::default());
    let mut client = client(&server);
    client.setup_outputs(&STATE_FIELDS, 500.0).unwrap();
    client.start().unwrap();
    next_values(&mut client);
    server.drop_clients();
    let start = Instant::now();
    let err = loop {
        match client.poll_data() {
            Ok(_) if start.elapsed() < Duration::from_secs(2) => {}
            Ok(_) => panic!("the lost connection went unnoticed"),
            Err(e) => break e,
        }
    };
    assert!(matches!(err, HwError::StateStream { .. }), "{err}");
}

fn rtde_fake(behaviour: FakeBehaviour) -> FakeUrController {
    FakeUrController::start(FakeUrOptions {
        behaviour,
        state: StateInterface::Rtde,
        lifetime: Duration::from_secs(15),
        ..FakeUrOptions::default()
    })
    .unwrap()
}

fn hw_error(err: &ArmError) -> String {
    match err {
        ArmError::Hardware(m) if m.downcast_ref::<HwError>().is_some() => m.to_string(),
        other => panic!("not a hardware error: {other:?}"),
    }
}

#[test]
fn the_ur5_driver_moves_and_reads_back_over_rtde() {
    let server = rtde_fake(FakeBehaviour::Follow);
    let config = server.config();
    assert_eq!(config.state, StateInterface::Rtde);
    let mut arm = Ur5Arm::connect(config).unwrap();
    let start = arm.pose();
    assert!((start.x - 400.0).abs() < 1e-9 && (start.z - 300.0).abs() < 1e-9);
    let target = Pose {
        x: start.x + 4.0,
        z: start.z - 6.0,
        ..start
    };
    arm.move_to(target).unwrap();
    let actual = arm.actual_pose().unwrap();
    assert!((actual.x - target.x).abs() < 0.1 && (actual.z - target.z).abs() < 0.1);
}

#[test]
fn a_protective_stop_during_a_move_over_rtde_aborts_it() {
    let server = rtde_fake(FakeBehaviour::ProtectiveStopOnMove);
    let mut arm = Ur5Arm::connect(server.config()).unwrap();
    let target = Pose {
        y: arm.pose().y + 3.0,
        ..arm.pose()
    };
    let err = arm.move_to(target).unwrap_err();
    assert!(hw_error(&err).contains("protective stop"), "{err}");
}

#[test]
fn a_malformed_rtde_package_is_an_error_not_a_panic() {
    let server = rtde_fake(FakeBehaviour::MalformedOnMove);
    let mut arm = Ur5Arm::connect(server.config()).unwrap();
    let target = Pose {
        x: arm.pose().x + 1.0,
        ..arm.pose()
    };
    let err = arm.move_to(target).unwrap_err();
    assert!(hw_error(&err).contains("RTDE: data package holds"), "{err}");
    assert!(arm.actual_pose().is_err());
}

#[test]
fn a_lost_rtde_connection_fails_the_next_move() {
    let server = FakeUrController::start(FakeUrOptions {
        state: StateInterface::Rtde,
        lifetime: Duration::from_millis(600),
        ..FakeUrOptions::default()
    })
    .unwrap();
    let mut arm = Ur5Arm::connect(server.config()).unwrap();
    std::thread::sleep(Duration::from_millis(900));
    let err = arm.move_to(arm.pose()).unwrap_err();
    let text = hw_error(&err);
    assert!(text.contains("robot state stream failed"), "{text}");
}
