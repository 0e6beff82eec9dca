//! A unit test of the SE(3) control law in closed loop with a pose ORACLE
//! (issue 23 item 3): the "sensed" pose is computed from the geometry of
//! the crates/shape3d surfaces, not predicted by a model from sensor data,
//! so these runs check the controller converges and are not results.
use tactrace_arm::Pose;
use tactrace_control::{Se3Config, Se3Controller};
use tactrace_shape3d::{HeightField, Object3d, Vec3};

/// The oracle: the sensor's pose relative to the surface frame at the
/// nearest surface point (z along the outward normal, the sensor's own
/// axes tilted the least way onto it), as a label vector (z as depth).
fn oracle(surface: &dyn Object3d, pose: Pose) -> [f64; 6] {
    let sensor = pose.to_isometry();
    let p = sensor.translation.vector;
    let q = surface.closest_point(p);
    let n = surface.normal(p);
    let axis = sensor.rotation * Vec3::z();
    let align = nalgebra::UnitQuaternion::rotation_between(&axis, &n).expect("not upside down");
    let frame = nalgebra::Isometry3::from_parts(q.into(), align * sensor.rotation);
    let s = Pose::from_isometry(&(frame.inverse() * sensor));
    [s.x, s.y, -s.z, s.rx, s.ry, s.rz]
}

struct Run {
    worst_depth_error_mm: f64,
    worst_tilt_deg: f64,
    mean_step_mm: f64,
}

/// `steps` surface_3d steps from `start`; the worst errors after `settle`.
fn follow(surface: &dyn Object3d, start: Pose, steps: usize, settle: usize) -> Run {
    let mut c = Se3Controller::try_new(Se3Config::surface_3d()).unwrap();
    let mut pose = start;
    let (mut depth, mut tilt, mut travelled) = (0.0_f64, 0.0_f64, 0.0);
    for i in 0..steps {
        let s = oracle(surface, pose);
        let next = c.next_pose(pose, s).unwrap();
        if i >= settle {
            let axis = pose.to_isometry().rotation * Vec3::z();
            let n = surface.normal(Vec3::new(pose.x, pose.y, pose.z));
            depth = depth.max((s[2] - 3.0).abs());
            tilt = tilt.max(axis.angle(&n).to_degrees());
            travelled += pose.distance(next);
        }
        pose = next;
    }
    Run {
        worst_depth_error_mm: depth,
        worst_tilt_deg: tilt,
        mean_step_mm: travelled / (steps - settle) as f64,
    }
}

#[test]
fn oracle_loop_settles_on_a_tilted_plane() {
    let ramp = HeightField::ramp(0.0, 20.0, 60.0).unwrap();
    // 1 mm above the surface, level, heading along +y.
    let start = Pose::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0);
    let run = follow(&ramp, start, 80, 40);
    eprintln!(
        "ramp (oracle): depth error {:.2e} mm, tilt {:.2e} deg, step {:.4} mm",
        run.worst_depth_error_mm, run.worst_tilt_deg, run.mean_step_mm
    );
    assert!(
        run.worst_depth_error_mm < 1e-3,
        "depth {}",
        run.worst_depth_error_mm
    );
    assert!(run.worst_tilt_deg < 1e-2, "tilt {}", run.worst_tilt_deg);
    assert!(
        (run.mean_step_mm - 1.0).abs() < 1e-3,
        "step {}",
        run.mean_step_mm
    );
}

#[test]
fn oracle_loop_follows_the_saddle() {
    let saddle = HeightField::saddle(40.0).unwrap();
    // Start off the surface and tilted 10 deg against it, heading diagonally.
    let start = Pose::new(
        -20.0,
        -25.0,
        saddle.height(-20.0, -25.0) + 1.0,
        10.0,
        -5.0,
        -30.0,
    );
    let run = follow(&saddle, start, 60, 20);
    eprintln!(
        "saddle (oracle): depth error {:.3} mm, tilt {:.3} deg, step {:.4} mm",
        run.worst_depth_error_mm, run.worst_tilt_deg, run.mean_step_mm
    );
    assert!(
        run.worst_depth_error_mm < 0.02,
        "depth {}",
        run.worst_depth_error_mm
    );
    assert!(run.worst_tilt_deg < 1.0, "tilt {}", run.worst_tilt_deg);
    assert!(
        (run.mean_step_mm - 1.0).abs() < 0.05,
        "step {}",
        run.mean_step_mm
    );
}
