//! The PBTS controller: signs, anti-windup, derivative term, and the
//! closed loop with perfect sensing on a straight edge and on the disk, and
//! the curvature policy against a curvature-biased model (issue 12).
use tactrace_arm::Pose;
use tactrace_control::{next_pose, ControlError, PbtsConfig, PbtsController, SensedPose};
use tactrace_geometry::{builtin_shape, BuiltinShape, Contour, Vec2};

fn sensed(r_mm: f64, theta_deg: f64) -> SensedPose {
    SensedPose { r_mm, theta_deg }
}

fn wrap_deg(a: f64) -> f64 {
    (a + 180.0).rem_euclid(360.0) - 180.0
}

/// Perfect pose model: r = signed distance of the centre, theta = yaw
/// relative to the outward normal of the nearest edge point.
fn perfect_sensing(contour: &Contour, pose: Pose) -> SensedPose {
    let e = contour.nearest(Vec2::new(pose.x, pose.y));
    let normal_yaw = e.normal.y.atan2(e.normal.x).to_degrees();
    sensed(e.signed_distance, wrap_deg(pose.rz - normal_yaw))
}

#[test]
fn on_the_edge_the_move_is_the_tangential_step() {
    let mut c = PbtsController::new(PbtsConfig::default());
    let d = c.step(sensed(0.0, 0.0));
    assert_eq!(d, Pose::new(0.0, 1.0, 0.0, 0.0, 0.0, 0.0));
}

#[test]
fn errors_drive_the_sensor_back_onto_the_edge() {
    let mut c = PbtsController::new(PbtsConfig::default());
    let d = c.step(sensed(2.0, 10.0));
    // e = (-2, 1, 0, 0, 0, -10): Kp e + Ki e on the first step.
    assert!((d.x - (0.5 * -2.0 + 0.3 * -2.0)).abs() < 1e-12);
    assert!((d.y - 1.0).abs() < 1e-12);
    assert!((d.rz - (0.5 * -10.0 + 0.1 * -10.0)).abs() < 1e-12);
    assert_eq!((d.z, d.rx, d.ry), (0.0, 0.0, 0.0));
    assert_eq!(
        c.error(sensed(2.0, 10.0)),
        [-2.0, 1.0, 0.0, 0.0, 0.0, -10.0]
    );
}

#[test]
fn anti_windup_clips_the_integral() {
    let mut c = PbtsController::new(PbtsConfig::default());
    let mut d = Pose::default();
    for _ in 0..100 {
        d = c.step(sensed(10.0, 100.0));
    }
    let i = c.integral();
    assert_eq!(i[0], -5.0, "x integral clipped to -5 mm");
    assert_eq!(i[5], -45.0, "rz integral clipped to -45 deg");
    assert!((d.x - (0.5 * -10.0 + 0.3 * -5.0)).abs() < 1e-12);
    assert!((d.rz - (0.5 * -100.0 + 0.1 * -45.0)).abs() < 1e-12);
    c.reset();
    assert_eq!(c.integral(), [0.0; 6]);
}

#[test]
fn y_integral_stays_zero_and_the_step_constant() {
    let mut c = PbtsController::new(PbtsConfig::default());
    for k in 0..50 {
        let d = c.step(sensed(0.3 * (k as f64).sin(), 2.0));
        assert!((d.y - 1.0).abs() < 1e-12);
        assert_eq!(c.integral()[1], 0.0);
    }
    // The report's printed K_i y = 1 makes the step grow until F clips it.
    let mut printed = PbtsController::new(PbtsConfig::as_printed());
    let steps: Vec<f64> = (0..10).map(|_| printed.step(sensed(0.0, 0.0)).y).collect();
    assert_eq!(steps[0], 2.0);
    assert_eq!(steps[9], 6.0, "1 mm + clipped integral of 5 mm");
}

#[test]
fn derivative_term_acts_on_the_error_change() {
    let cfg = PbtsConfig {
        kd: [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
        ki: [0.0; 6],
        ..PbtsConfig::default()
    };
    let mut c = PbtsController::new(cfg);
    let d1 = c.step(sensed(1.0, 0.0));
    assert!(
        (d1.x + 0.5).abs() < 1e-12,
        "no derivative kick on the first step"
    );
    let d2 = c.step(sensed(3.0, 0.0));
    assert!((d2.x - (-1.5 + 0.2 * (-3.0 - -1.0))).abs() < 1e-12);
}

#[test]
fn non_finite_predictions_do_not_corrupt_the_state() {
    let mut c = PbtsController::new(PbtsConfig::default());
    c.step(sensed(1.0, 1.0));
    let before = c.clone();
    assert!(c.step(sensed(f64::NAN, 0.0)).x.is_nan());
    assert_eq!(c, before);
    assert!(matches!(
        c.try_step(sensed(0.0, f64::INFINITY)),
        Err(ControlError::NonFiniteInput { .. })
    ));
}

#[test]
fn config_validation_and_toml() {
    assert!(PbtsConfig::default().validate().is_ok());
    let bad = PbtsConfig {
        kp: [f64::NAN, 1.0, 0.0, 0.0, 0.0, 0.5],
        ..PbtsConfig::default()
    };
    assert_eq!(
        bad.validate(),
        Err(ControlError::NonFinite {
            field: "kp",
            index: 0
        })
    );
    let bad = PbtsConfig {
        integral_clip: [-1.0, 5.0, 5.0, 45.0, 45.0, 45.0],
        ..PbtsConfig::default()
    };
    assert!(matches!(
        PbtsController::try_new(bad),
        Err(ControlError::NegativeClip { index: 0, .. })
    ));
    let cfg: PbtsConfig = toml::from_str("reference = [0, 2, 0, 0, 0, 0]").unwrap();
    assert_eq!(cfg.reference[1], 2.0);
    assert_eq!(
        cfg.kp,
        PbtsConfig::default().kp,
        "unset fields keep their defaults"
    );
    assert!(
        toml::from_str::<PbtsConfig>("kp_x = 1.0").is_err(),
        "unknown fields are rejected"
    );
}

#[test]
fn next_pose_moves_in_the_sensor_frame() {
    // Sensor yawed 90 deg: its x axis is the work +y axis.
    let p = next_pose(
        Pose::planar(0.0, 0.0, 2.0, 90.0),
        Pose::new(1.0, 0.0, 0.0, 0.0, 0.0, 10.0),
    );
    assert!(p.x.abs() < 1e-12 && (p.y - 1.0).abs() < 1e-12 && (p.z - 2.0).abs() < 1e-12);
    assert!((p.rz - 100.0).abs() < 1e-12);
}

#[test]
fn closed_loop_on_a_straight_edge_converges_and_advances_1mm_per_step() {
    // Object below the work x axis: outward normal +y (yaw 90), so +y in the
    // sensor frame (counter-clockwise) is the work -x direction.
    let edge = Contour::new(vec![
        Vec2::new(-1e4, -1e4),
        Vec2::new(1e4, -1e4),
        Vec2::new(1e4, 0.0),
        Vec2::new(-1e4, 0.0),
    ])
    .unwrap();
    let mut c = PbtsController::new(PbtsConfig::default());
    let mut pose = Pose::planar(0.0, 3.0, 2.0, 90.0 + 20.0);
    let mut last = (0.0, 0.0);
    for step in 0..60 {
        let s = perfect_sensing(&edge, pose);
        last = (s.r_mm, s.theta_deg);
        let next = next_pose(pose, c.step(s));
        if step >= 40 {
            assert!(
                (pose.distance(next) - 1.0).abs() < 1e-3,
                "step {step}: {}",
                pose.distance(next)
            );
            assert!(
                (next.x - pose.x + 1.0).abs() < 1e-3,
                "advances along -x (counter-clockwise)"
            );
        }
        pose = next;
    }
    assert!(
        last.0.abs() < 1e-4 && last.1.abs() < 1e-4,
        "r, theta = {last:?}"
    );
}

#[test]
fn closed_loop_goes_round_the_disk() {
    let disk = builtin_shape(BuiltinShape::Disk);
    let (p0, n0) = disk.at_arc_length(0.0);
    let start_yaw = n0.y.atan2(n0.x).to_degrees();
    let mut pose = Pose::planar(p0.x + 2.0 * n0.x, p0.y + 2.0 * n0.y, 2.0, start_yaw + 15.0);
    let mut c = PbtsController::new(PbtsConfig::default());
    let (mut travelled, mut worst_late) = (0.0, 0.0_f64);
    let mut steps = 0;
    let mut arc_prev = 0.0;
    while travelled < disk.perimeter() && steps < 1000 {
        let s = perfect_sensing(&disk, pose);
        if steps >= 20 {
            worst_late = worst_late.max(s.r_mm.abs());
        }
        pose = next_pose(pose, c.step(s));
        let arc = disk.nearest(Vec2::new(pose.x, pose.y)).arc_length;
        travelled += (arc - arc_prev).rem_euclid(disk.perimeter());
        arc_prev = arc;
        steps += 1;
    }
    eprintln!("disk with perfect sensing: {steps} steps per lap, worst |r| after settling {worst_late:.4} mm");
    assert!(worst_late < 0.05, "tracks the edge: {worst_late}");
    // 1 mm steps along the edge: one lap of 346.8 mm in about 347 steps.
    assert!((340..=355).contains(&steps), "{steps} steps");
}

/// Issue 12's failure and its cure, in theory: on a circle of radius R a
/// pose model trained on gentle curves reads r = d + c / R (the measured
/// bias on tight turns, c in mm^2). The report's controller drives that
/// reading to 0 and so settles c / R inside the edge; the curvature policy
/// estimates kappa = 1 / R from its own moves and aims at r = c kappa,
/// back on the edge.
#[test]
fn the_curvature_policy_undoes_a_curvature_bias() {
    let (radius, c) = (12.0, 14.0);
    let points: Vec<Vec2> = (0..720)
        .map(|i| {
            let t = (i as f64 / 720.0) * std::f64::consts::TAU;
            Vec2::new(radius * t.cos(), radius * t.sin())
        })
        .collect();
    let circle = Contour::new(points).unwrap();
    let settle = |cfg: PbtsConfig| {
        let mut ctl = PbtsController::new(cfg);
        let mut pose = Pose::planar(radius, 0.0, 2.0, 0.0);
        let mut late = Vec::new();
        for step in 0..300 {
            let truth = perfect_sensing(&circle, pose);
            if step >= 200 {
                late.push(truth.r_mm);
            }
            let biased = sensed(truth.r_mm + c / radius, truth.theta_deg);
            pose = next_pose(pose, ctl.step(biased));
        }
        let mean = late.iter().sum::<f64>() / late.len() as f64;
        (mean, ctl.curvature_per_mm())
    };
    let (report, _) = settle(PbtsConfig::report());
    assert!(
        (report + c / radius).abs() < 0.05,
        "report settles at {report}"
    );
    let mut cfg = PbtsConfig::report();
    cfg.policy.curvature_offset_mm2 = c;
    let (policy, kappa) = settle(cfg);
    assert!((kappa - 1.0 / radius).abs() < 0.01, "kappa {kappa}");
    assert!(policy.abs() < 0.15, "policy settles at {policy}");
}
