//! 6-DoF poses through the arm crate (issue 23 item 3): composition,
//! the limiter's rotation step, clamp and tilt bound, and the simulated
//! arm, all with tilted poses.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_arm::{
    level_to, tilt_deg, Arm, ArmError, FinitePose, LimitMode, LimitedArm, Pose, PoseProbe, SimArm,
    SimArmConfig, Workspace,
};

fn exact() -> SimArmConfig {
    SimArmConfig {
        repeatability_mm: 0.0,
        repeatability_deg: 0.0,
        seed: 0,
    }
}

fn workspace() -> Workspace {
    Workspace {
        min: [-100.0, -100.0, -50.0],
        max: [100.0, 100.0, 50.0],
        max_step_mm: 10.0,
        max_step_deg: 30.0,
    }
}

fn random_pose(rng: &mut ChaCha8Rng, tilt: f64) -> Pose {
    Pose::new(
        rng.random_range(-40.0..40.0),
        rng.random_range(-40.0..40.0),
        rng.random_range(-20.0..20.0),
        rng.random_range(-tilt..tilt),
        rng.random_range(-tilt..tilt),
        rng.random_range(-180.0..180.0),
    )
}

/// Same rigid pose: positions within 1e-9 mm, rotations within 1e-7 deg.
fn same(a: Pose, b: Pose) -> bool {
    a.distance(b) < 1e-9 && a.angle_to(b) < 1e-7
}

#[test]
fn tilted_poses_compose_and_relate() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..500 {
        let (a, b) = (random_pose(&mut rng, 89.0), random_pose(&mut rng, 89.0));
        assert!(same(a.compose(a.relative(b)), b), "{a} -> {b}");
        // The move is in a's own frame: its translation rotated by a.
        let step = Pose::new(0.0, 1.0, 0.0, 0.0, 0.0, 0.0);
        let moved = a.compose(step);
        let y_axis = a.to_isometry().rotation * nalgebra::Vector3::y();
        let d = nalgebra::Vector3::new(moved.x - a.x, moved.y - a.y, moved.z - a.z);
        assert!((d - y_axis).norm() < 1e-12);
    }
    // The same rotation written two ways is no rotation at all.
    let flipped = Pose::new(0.0, 0.0, 0.0, 180.0, 0.0, 0.0);
    let same_rotation = Pose::new(0.0, 0.0, 0.0, 0.0, 180.0, 180.0);
    assert!(flipped.angle_to(same_rotation) < 1e-9);
}

#[test]
fn rotation_step_is_the_relative_rotation_angle() {
    let ws = workspace();
    let check =
        |a: Pose, b: Pose| ws.check_move(FinitePose::new(a).unwrap(), FinitePose::new(b).unwrap());
    // A yaw of 25 deg about the work z axis at 40 deg of tilt is 25 deg.
    let tilted = Pose::new(0.0, 0.0, 0.0, 40.0, 0.0, 0.0);
    check(tilted, Pose { rz: 25.0, ..tilted }).unwrap();
    let err = check(tilted, Pose { rz: 35.0, ..tilted }).unwrap_err();
    assert!(
        matches!(err, ArmError::RotationTooLarge { step_deg, .. } if (step_deg - 35.0).abs() < 1e-9)
    );
    // Across the +-180 seam of roll: 20 deg, not 340.
    let a = Pose::new(0.0, 0.0, 0.0, 170.0, 10.0, 0.0);
    check(a, Pose { rx: -170.0, ..a }).unwrap();
    // Roll and pitch together: the angle of the combined rotation.
    let b = Pose::new(0.0, 0.0, 0.0, 20.0, 20.0, 0.0);
    let angle = Pose::default().angle_to(b);
    assert!(angle > 28.0 && angle < 28.3, "{angle}");
    check(Pose::default(), b).unwrap();
    assert!(check(Pose::default(), Pose { rx: 25.0, ..b }).is_err());
}

#[test]
fn clamp_turns_along_the_shortest_rotation() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..200 {
        let start = Pose {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            ..random_pose(&mut rng, 60.0)
        };
        let target = Pose {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            ..random_pose(&mut rng, 60.0)
        };
        let mut arm = LimitedArm::new(SimArm::new(exact(), start), workspace(), LimitMode::Clamp);
        arm.move_to(target).unwrap();
        let (got, total) = (arm.pose(), start.angle_to(target));
        if total <= 30.0 {
            assert!(same(got, target));
        } else {
            // On the geodesic: 30 deg from the start, the rest to go.
            assert!(
                (start.angle_to(got) - 30.0).abs() < 1e-6,
                "{start} {target} {got}"
            );
            assert!((got.angle_to(target) - (total - 30.0)).abs() < 1e-6);
        }
    }
}

#[test]
fn tilt_is_bounded_when_asked() {
    assert_eq!(tilt_deg(Pose::planar(1.0, 2.0, 3.0, 123.0)), 0.0);
    assert!((tilt_deg(Pose::new(0.0, 0.0, 0.0, 30.0, 0.0, 77.0)) - 30.0).abs() < 1e-9);
    let both = (30f64.to_radians().cos() * 40f64.to_radians().cos())
        .acos()
        .to_degrees();
    assert!((tilt_deg(Pose::new(0.0, 0.0, 0.0, 30.0, 40.0, 0.0)) - both).abs() < 1e-9);
    let levelled = level_to(Pose::new(1.0, 2.0, 3.0, 0.0, 50.0, 20.0), 25.0);
    assert!((tilt_deg(levelled) - 25.0).abs() < 1e-9, "{levelled}");
    assert_eq!((levelled.x, levelled.y, levelled.z), (1.0, 2.0, 3.0));

    let start = Pose::new(0.0, 0.0, 0.0, 20.0, 0.0, 0.0);
    let mut arm = LimitedArm::new(SimArm::new(exact(), start), workspace(), LimitMode::Refuse)
        .with_max_tilt_deg(25.0);
    let err = arm.move_to(Pose { rx: 26.0, ..start }).unwrap_err();
    assert!(matches!(err, ArmError::TiltTooLarge { .. }), "{err}");
    assert_eq!(arm.pose(), start);
    arm.move_to(Pose { rx: 25.0, ..start }).unwrap();
    // An unbounded limiter lets the same tilt through.
    let mut free = LimitedArm::new(SimArm::new(exact(), start), workspace(), LimitMode::Refuse);
    free.move_to(Pose { rx: 26.0, ..start }).unwrap();
    for bad in [0.0, -5.0, 181.0, f64::NAN] {
        let mut arm = LimitedArm::new(SimArm::new(exact(), start), workspace(), LimitMode::Refuse)
            .with_max_tilt_deg(bad);
        let err = arm.move_to(start).unwrap_err();
        assert!(
            matches!(
                err,
                ArmError::InvalidConfig {
                    field: "max_tilt_deg",
                    ..
                }
            ),
            "{err}"
        );
    }
    // Clamping levels the target and keeps within the step limits.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..300 {
        let from = level_to(random_pose(&mut rng, 40.0), 25.0);
        let to = random_pose(&mut rng, 70.0);
        let mut arm = LimitedArm::new(SimArm::new(exact(), from), workspace(), LimitMode::Clamp)
            .with_max_tilt_deg(25.0);
        arm.move_to(to).unwrap();
        let got = arm.pose();
        assert!(tilt_deg(got) <= 25.0 + 1e-9, "{from} -> {to}: {got}");
        assert!(from.angle_to(got) <= 30.0 + 1e-6, "{from} -> {to}: {got}");
        assert!(from.distance(got) <= 10.0 + 1e-9);
    }
}

#[test]
fn sim_arm_reaches_tilted_poses() {
    let cfg = SimArmConfig {
        repeatability_mm: 0.05,
        repeatability_deg: 0.1,
        seed: 9,
    };
    let (mut arm, probe): (SimArm, PoseProbe) = SimArm::with_probe(cfg, Pose::default());
    let target = Pose::new(5.0, -3.0, 2.0, 25.0, -15.0, 60.0);
    let n = 5000;
    let mut sum2 = 0.0;
    for _ in 0..n {
        arm.move_to(target).unwrap();
        assert_eq!(arm.pose(), target, "the commanded pose is exact");
        let reached = probe.actual();
        // The orientation error is a turn about the work z axis: the tilt
        // is reached exactly.
        assert!((tilt_deg(reached) - tilt_deg(target)).abs() < 1e-9);
        sum2 += target.angle_to(reached).powi(2);
    }
    let sd = (sum2 / n as f64).sqrt();
    assert!((sd / 0.1 - 1.0).abs() < 0.05, "orientation error sd {sd}");
}
