//! 6-DoF (tilted) poses through the UR5 driver's conversions and the
//! loopback fake controller (issue 23 item 3): pose -> rotation vector ->
//! pose round trips at any tilt.
use std::time::Duration;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_arm::Arm;
use tactrace_geometry::Pose;
use tactrace_hw::ur5::script::{
    base_to_work, isometry_to_tool_vector, pose_to_tool_vector, tool_vector_to_isometry,
    tool_vector_to_pose, work_to_base,
};
use tactrace_hw::{FakeBehaviour, FakeUrController, FakeUrOptions, Ur5Arm};

/// Position within `mm` and orientation within `deg` (as rotations).
fn assert_same(a: Pose, b: Pose, mm: f64, deg: f64) {
    let (dp, dr) = (a.distance(b), a.angle_to(b));
    assert!(dp <= mm && dr <= deg, "{a} vs {b}: {dp} mm, {dr} deg");
}

fn wrap(a: f64) -> f64 {
    (a + 180.0).rem_euclid(360.0) - 180.0
}

fn tilted_poses() -> Vec<Pose> {
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let mut poses: Vec<Pose> = (0..1000)
        .map(|_| {
            Pose::new(
                rng.random_range(-300.0..300.0),
                rng.random_range(-300.0..300.0),
                rng.random_range(-100.0..300.0),
                rng.random_range(-180.0..180.0),
                rng.random_range(-89.0..89.0),
                rng.random_range(-180.0..180.0),
            )
        })
        .collect();
    // Near the rotation vector's seam (a half turn) and near gimbal lock.
    poses.extend([
        Pose::new(1.0, 2.0, 3.0, 180.0, 0.0, 0.0),
        Pose::new(1.0, 2.0, 3.0, 179.999, 0.5, -0.5),
        Pose::new(1.0, 2.0, 3.0, 0.0, 180.0, 0.0),
        Pose::new(1.0, 2.0, 3.0, 25.0, 89.999, 40.0),
        Pose::new(1.0, 2.0, 3.0, -25.0, -25.0, 180.0),
    ]);
    poses
}

#[test]
fn tool_vector_round_trips_tilted_poses() {
    for pose in tilted_poses() {
        let v = pose_to_tool_vector(pose);
        // The rotation vector's length is the angle of the rotation.
        let angle = (v[3] * v[3] + v[4] * v[4] + v[5] * v[5])
            .sqrt()
            .to_degrees();
        assert!(
            (angle - Pose::default().angle_to(pose)).abs() < 1e-7,
            "{pose}"
        );
        let back = tool_vector_to_pose(v);
        assert_same(back, pose, 1e-9, 1e-7);
        // Away from gimbal lock the Euler angles come back themselves.
        if pose.ry.abs() < 89.0 {
            for (a, b) in [(pose.rx, back.rx), (pose.ry, back.ry), (pose.rz, back.rz)] {
                assert!(wrap(a - b).abs() < 1e-7, "{pose} vs {back}");
            }
        }
    }
}

#[test]
fn work_frame_round_trips_tilted_poses() {
    let work = Pose::new(288.0, 0.0, -100.0, 180.0, 0.0, -90.0);
    for pose in tilted_poses() {
        let base = work_to_base(work, pose);
        let sent = isometry_to_tool_vector(&base);
        let back = base_to_work(work, &tool_vector_to_isometry(sent));
        assert_same(back, pose, 1e-9, 1e-7);
    }
}

#[test]
fn fake_ur5_reaches_tilted_poses() {
    let server = FakeUrController::start(FakeUrOptions {
        behaviour: FakeBehaviour::Follow,
        lifetime: Duration::from_secs(15),
        ..FakeUrOptions::default()
    })
    .expect("fake controller starts");
    let mut config = server.config();
    config.work_frame = Pose::new(288.0, 0.0, -100.0, 0.0, 0.0, -90.0);
    let mut arm = Ur5Arm::connect(config).expect("connects");
    // The flange down (rx = 180) and then tilted 20 deg and 15 deg.
    for target in [
        Pose::new(110.0, 0.0, 400.0, 180.0, 0.0, 0.0),
        Pose::new(110.0, 0.5, 400.0, -160.0, 15.0, 30.0),
        Pose::new(111.0, 0.5, 399.0, 165.0, -20.0, -45.0),
    ] {
        arm.move_to(target).expect("move reaches target");
        assert_eq!(arm.pose(), target);
        assert_same(arm.actual_pose().unwrap(), target, 0.1, 0.1);
    }
}
