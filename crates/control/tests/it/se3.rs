//! The SE(3) controller (issue 23 item 3): the error's definition, the
//! tasks' sensed components, the checked configs, and the report's planar
//! loop as its exact special case.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_arm::Pose;
use tactrace_control::{
    apply_servo, next_pose, se3_error, ControlError, PbtsConfig, PbtsController, Se3Config,
    Se3Controller, SensedPose, Task,
};
use tactrace_geometry::{builtin_shape, BuiltinShape, Contour, Vec2};

fn close(a: [f64; 6], b: [f64; 6], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// Perfect planar sensing, as the 2D controller's tests.
fn perfect_sensing(contour: &Contour, pose: Pose) -> SensedPose {
    let e = contour.nearest(Vec2::new(pose.x, pose.y));
    let normal_yaw = e.normal.y.atan2(e.normal.x).to_degrees();
    let yaw = (pose.rz - normal_yaw + 180.0).rem_euclid(360.0) - 180.0;
    SensedPose {
        r_mm: e.signed_distance,
        theta_deg: yaw,
    }
}

/// Runs both controllers on the same sensed poses from the same pose and
/// checks moves and next poses agree within 1e-9.
fn assert_same_steps(pbts: PbtsConfig, sequence: &[SensedPose]) {
    let mut old = PbtsController::try_new(pbts.clone()).unwrap();
    let mut new = Se3Controller::try_new(Se3Config::planar(&pbts).unwrap()).unwrap();
    let mut pose = Pose::planar(10.0, -20.0, 2.0, 35.0);
    for (i, s) in sequence.iter().enumerate() {
        let delta = old.step(*s).to_array();
        let u = new.step([s.r_mm, 0.0, 0.0, 0.0, 0.0, s.theta_deg]).unwrap();
        assert!(close(delta, u, 1e-9), "step {i}: {delta:?} vs {u:?}");
        let (a, b) = (
            next_pose(pose, Pose::from_array(delta)),
            apply_servo(pose, u),
        );
        assert!(
            close(a.to_array(), b.to_array(), 1e-9),
            "pose {i}: {a} vs {b}"
        );
        pose = a;
    }
    assert!(close(old.integral(), new.integral(), 1e-9));
}

#[test]
fn planar_case_gives_the_report_controllers_steps() {
    // A recorded sequence: large errors that saturate the anti-windup,
    // then small ones that unwind it.
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let sequence: Vec<SensedPose> = (0..300)
        .map(|i| {
            let scale = if i < 100 { 4.0 } else { 0.5 };
            SensedPose {
                r_mm: scale * rng.random_range(-1.0..1.0),
                theta_deg: 10.0 * scale * rng.random_range(-1.0..1.0),
            }
        })
        .collect();
    assert_same_steps(PbtsConfig::report(), &sequence);
    // The tuned gains (with a derivative term), the policy off.
    let tuned = PbtsConfig {
        policy: Default::default(),
        ..PbtsConfig::tuned()
    };
    assert_same_steps(tuned, &sequence);
    assert_eq!(
        Se3Config::edge_2d(),
        Se3Config::planar(&PbtsConfig::report()).unwrap()
    );
}

#[test]
fn planar_closed_loop_round_the_disk_is_unchanged() {
    let disk = builtin_shape(BuiltinShape::Disk);
    let (p0, n0) = disk.at_arc_length(0.0);
    let yaw = n0.y.atan2(n0.x).to_degrees();
    let start = Pose::planar(p0.x + 2.0 * n0.x, p0.y + 2.0 * n0.y, 2.0, yaw + 15.0);
    let mut old = PbtsController::new(PbtsConfig::report());
    let mut new = Se3Controller::try_new(Se3Config::edge_2d()).unwrap();
    let (mut a, mut b) = (start, start);
    for i in 0..350 {
        let (sa, sb) = (perfect_sensing(&disk, a), perfect_sensing(&disk, b));
        a = next_pose(a, old.step(sa));
        b = new
            .next_pose(b, [sb.r_mm, 0.0, 0.0, 0.0, 0.0, sb.theta_deg])
            .unwrap();
        assert!(
            close(a.to_array(), b.to_array(), 1e-9),
            "step {i}: {a} vs {b}"
        );
    }
}

#[test]
fn error_is_the_relative_transform() {
    let reference = [0.0, 1.0, 3.0, 0.0, 0.0, 0.0];
    assert!(close(se3_error(reference, reference), [0.0; 6], 1e-12));
    // Too shallow by 2 mm: move 2 mm down the sensor's (upward) z axis.
    let e = se3_error(reference, [0.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    assert!(close(e, [0.0, 0.0, -2.0, 0.0, 0.0, 0.0], 1e-12), "{e:?}");
    // A pure tilt is undone by the opposite rotation vector.
    let e = se3_error(reference, [0.0, 1.0, 3.0, 10.0, 0.0, 0.0]);
    assert!(close(e, [0.0, 0.0, 0.0, -10.0, 0.0, 0.0], 1e-9), "{e:?}");
    // Two tilts at once: the rotation vector of the combined rotation,
    // not the Euler angles (rx = ry = 20 deg is not a rotation of 20 deg
    // about each axis).
    let e = se3_error(reference, [0.0, 1.0, 3.0, 20.0, 20.0, 0.0]);
    let r = Pose::new(0.0, 0.0, 0.0, 20.0, 20.0, 0.0)
        .to_isometry()
        .rotation;
    let v = r.scaled_axis().map(f64::to_degrees);
    assert!(close(e, [0.0, 0.0, 0.0, -v.x, -v.y, -v.z], 1e-9), "{e:?}");
    assert!(v.z.abs() > 0.5, "the Euler pair has a yaw part {v}");
    // A rotated reference: the offset is seen from the reference's frame.
    let rotated = [0.0, 0.0, 0.0, 0.0, 0.0, 90.0];
    let e = se3_error(rotated, [1.0, 0.0, 0.0, 0.0, 0.0, 90.0]);
    assert!(close(e, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0], 1e-9), "{e:?}");
    // The offset is measured in the reference's frame, not the
    // prediction's: a sensor 1 mm out and turned 90 deg is moved 1 mm
    // back along x (T(s)^-1 T(s*) would say 1 mm along y).
    let e = se3_error([0.0; 6], [1.0, 0.0, 0.0, 0.0, 0.0, 90.0]);
    assert!(close(e, [-1.0, 0.0, 0.0, 0.0, 0.0, -90.0], 1e-9), "{e:?}");
    // Applying the move of gain 1 to the predicted pose reaches the
    // reference exactly (single rotation about z and a translation).
    let s = [2.0, -1.0, 3.0, 0.0, 0.0, 0.0];
    let e = se3_error(reference, s);
    let s_pose = Pose::new(s[0], s[1], -s[2], s[3], s[4], s[5]);
    let reached = apply_servo(s_pose, e);
    assert!(close(
        reached.to_array(),
        [0.0, 1.0, -3.0, 0.0, 0.0, 0.0],
        1e-9
    ));
}

#[test]
fn tasks_sense_their_components_only() {
    assert_eq!(Task::Edge2d.sensed_names(), ["x", "rz"]);
    assert_eq!(Task::Surface3d.sensed_names(), ["z", "rx", "ry"]);
    assert_eq!(Task::Edge3d.sensed_names(), ["x", "z", "rz"]);
    assert_eq!(Task::Edge5d.sensed_names(), ["x", "z", "rx", "ry", "rz"]);
    let c = Se3Controller::try_new(Se3Config::surface_3d()).unwrap();
    // Unsensed components (even NaN) are ignored: zero error where the
    // reference is zero, the 1 mm step along y.
    let e = c.error([f64::NAN, 7.0, 3.0, 0.0, 0.0, 45.0]);
    assert!(close(e, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0], 1e-12), "{e:?}");
    // Tilts never leak into the unsensed yaw.
    let e = c.error([0.0, 0.0, 3.0, 20.0, 20.0, 0.0]);
    assert_eq!(e[5], 0.0);
    let mut c = Se3Controller::try_new(Se3Config::surface_3d()).unwrap();
    let err = c.step([0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0]).unwrap_err();
    assert!(
        matches!(
            err,
            ControlError::NonFinitePrediction { component: "z", .. }
        ),
        "{err}"
    );
    assert_eq!(c.integral(), [0.0; 6], "a refused step changes nothing");
    assert_eq!(Task::Edge5d.to_string(), "edge_5d");
}

#[test]
fn surface_3d_gains_and_anti_windup() {
    let mut c = Se3Controller::try_new(Se3Config::surface_3d()).unwrap();
    // 1 mm too shallow, tilted 4 deg about x: first step Kp e + Ki e.
    let u = c.step([0.0, 0.0, 2.0, 4.0, 0.0, 0.0]).unwrap();
    let want = [0.0, 1.0, -(0.5 + 0.3), -4.0 * (0.5 + 0.1), 0.0, 0.0];
    assert!(close(u, want, 1e-9), "{u:?}");
    for _ in 0..100 {
        c.step([0.0, 0.0, 0.0, 40.0, 0.0, 0.0]).unwrap();
    }
    let i = c.integral();
    assert!(close(i, [0.0, 0.0, -5.0, -45.0, 0.0, 0.0], 1e-9), "{i:?}");
}

#[test]
fn configs_are_checked() {
    let s = Se3Config::surface_3d();
    assert_eq!(s.reference, [0.0, 1.0, 3.0, 0.0, 0.0, 0.0]);
    assert_eq!(s.kp, [1.0, 1.0, 0.5, 0.5, 0.5, 1.0]);
    assert_eq!(s.ki, [0.0, 0.0, 0.3, 0.1, 0.1, 0.0]);
    for task in Task::ALL {
        let config = Se3Config::for_task(task);
        assert_eq!(config.task, task);
        let text = toml::to_string(&config).unwrap();
        let back: Se3Config = toml::from_str(&text).unwrap();
        assert_eq!(back, config, "{text}");
    }
    let base = "task = \"edge_5d\"\nreference = [0, 1, 3, 0, 0, 0]\n\
                kp = [0.5, 1, 0.5, 0.5, 0.5, 0.5]\nki = [0.3, 0, 0.3, 0.1, 0.1, 0.1]\n";
    let ok: Se3Config =
        toml::from_str(&format!("{base}integral_clip = [5, 5, 5, 45, 45, 45]\n")).unwrap();
    let unbounded = Se3Config {
        move_clip: None,
        ..Se3Config::edge_5d()
    };
    assert_eq!(ok, unbounded);
    let negative = format!("{base}integral_clip = [5, 5, -5, 45, 45, 45]\n");
    let err = toml::from_str::<Se3Config>(&negative).unwrap_err();
    assert!(err.to_string().contains("integral_clip[2]"), "{err}");
    let unknown = format!("{base}integral_clip = [5, 5, 5, 45, 45, 45]\nkq = 1\n");
    assert!(toml::from_str::<Se3Config>(&unknown).is_err());
    let bad_task = base.replace("edge_5d", "edge_4d") + "integral_clip = [5, 5, 5, 45, 45, 45]\n";
    assert!(toml::from_str::<Se3Config>(&bad_task).is_err());
    let nan = Se3Config::new(Task::Surface3d, [0.0; 6], [f64::NAN; 6], [0.0; 6], [1.0; 6]);
    assert_eq!(
        nan.unwrap_err(),
        ControlError::NonFinite {
            field: "kp",
            index: 0
        }
    );
    let policy_on = PbtsConfig::tuned();
    assert!(matches!(
        Se3Config::planar(&policy_on),
        Err(ControlError::Policy { .. })
    ));
}
