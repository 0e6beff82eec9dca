//! Poses: the Euler convention, composition in the sensor frame (eq.
//! 5.7-5.8) and the relative/compose round trip.
use nalgebra::{Point3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_geometry::Pose;

fn close(a: Pose, b: Pose, tol: f64) -> bool {
    a.distance(b) < tol && a.angle_to(b) < tol
}

#[test]
fn euler_angles_are_extrinsic_xyz() {
    // R = Rz(rz) Ry(ry) Rx(rx): rotate about fixed x first, then y, then z.
    let pose = Pose::new(0.0, 0.0, 0.0, 90.0, 0.0, 90.0);
    let r = pose.to_isometry().rotation;
    // x first: y axis -> z; then z by 90 about fixed z stays z.
    assert!((r * Vector3::y() - Vector3::z()).norm() < 1e-12);
    // The x axis is unchanged by Rx, then Rz turns it to y.
    assert!((r * Vector3::x() - Vector3::y()).norm() < 1e-12);
    let back = Pose::from_isometry(&pose.to_isometry());
    assert!(close(back, pose, 1e-9));
    assert!((back.rx - 90.0).abs() < 1e-9 && (back.rz - 90.0).abs() < 1e-9);
}

#[test]
fn yaw_then_sensor_x_move_goes_along_base_y() {
    let at = Pose::planar(10.0, 20.0, 2.0, 90.0);
    let moved = at.compose(Pose::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0));
    assert!(
        (moved.x - 10.0).abs() < 1e-12
            && (moved.y - 21.0).abs() < 1e-12
            && (moved.z - 2.0).abs() < 1e-12
    );
    assert!((moved.rz - 90.0).abs() < 1e-12);
    // A sensor-frame yaw adds to the base yaw.
    let turned = at.compose(Pose::planar(0.0, 1.0, 0.0, 30.0));
    assert!((turned.x - 9.0).abs() < 1e-12 && (turned.y - 20.0).abs() < 1e-12);
    assert!((turned.rz - 120.0).abs() < 1e-12);
}

#[test]
fn transform_maps_points_like_the_quaternion_sandwich() {
    // Eq. 5.8: tau' = Q dtau Q* + tau.
    let at = Pose::new(1.0, 2.0, 3.0, 10.0, -20.0, 35.0);
    let d = Vector3::new(0.5, -1.5, 2.0);
    let q = at.to_isometry().rotation;
    let sandwich = q * d + Vector3::new(1.0, 2.0, 3.0);
    let composed = at.compose(Pose::new(d.x, d.y, d.z, 0.0, 0.0, 0.0));
    assert!((Vector3::new(composed.x, composed.y, composed.z) - sandwich).norm() < 1e-12);
    let p = at.to_isometry() * Point3::new(d.x, d.y, d.z);
    assert!((p.coords - sandwich).norm() < 1e-12);
}

#[test]
fn compose_relative_round_trip_on_random_poses() {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let random_pose = |rng: &mut ChaCha8Rng| {
        Pose::new(
            rng.random_range(-100.0..100.0),
            rng.random_range(-100.0..100.0),
            rng.random_range(-100.0..100.0),
            rng.random_range(-180.0..180.0),
            rng.random_range(-89.0..89.0),
            rng.random_range(-180.0..180.0),
        )
    };
    for _ in 0..1000 {
        let (a, b) = (random_pose(&mut rng), random_pose(&mut rng));
        let rel = a.relative(b);
        assert!(close(a.compose(rel), b, 1e-9), "{a:?} -> {b:?}");
        assert!(
            close(b.relative(a), rel.relative(Pose::default()), 1e-9),
            "relative inverts"
        );
        // Round trip through the isometry preserves the pose exactly up to rounding.
        let back = Pose::from_isometry(&a.to_isometry());
        assert!(
            (back.rx - a.rx).abs() < 1e-9
                && (back.ry - a.ry).abs() < 1e-9
                && (back.rz - a.rz).abs() < 1e-9
        );
        // Composition is associative.
        let c = random_pose(&mut rng);
        assert!(close(
            a.compose(b).compose(c),
            a.compose(b.compose(c)),
            1e-9
        ));
    }
}

#[test]
fn distance_is_euclidean_in_position() {
    let a = Pose::new(0.0, 0.0, 0.0, 10.0, 0.0, 0.0);
    let b = Pose::new(3.0, 4.0, 12.0, 0.0, 50.0, 0.0);
    assert!((a.distance(b) - 13.0).abs() < 1e-12);
}

/// Issue 20: poses reached messages as Rust debug structs
/// (`Pose { x: .. }`), and a pose table in a configuration accepted keys it
/// does not have.
#[test]
fn a_pose_reads_as_millimetres_and_degrees_and_refuses_unknown_keys() {
    let p = Pose::new(1.0, -2.5, 300.0, 0.0, 90.0, -45.25);
    assert_eq!(
        p.to_string(),
        "(1.000, -2.500, 300.000) mm, (0.000, 90.000, -45.250) deg"
    );
    assert_eq!(
        format!("{p:.1}"),
        "(1.0, -2.5, 300.0) mm, (0.0, 90.0, -45.2) deg"
    );
    let text = r#"{"x": 1, "y": 2, "z": 3, "rx": 0, "ry": 0, "rz": 0, "yaw": 5}"#;
    let err = serde_json::from_str::<Pose>(text).unwrap_err();
    assert!(err.to_string().contains("unknown field `yaw`"), "{err}");
}
