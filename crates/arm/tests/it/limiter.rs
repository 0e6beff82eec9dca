//! The workspace/step limiter in both modes, around a noiseless SimArm.
use tactrace_arm::{
    Arm, ArmError, FinitePose, LimitMode, LimitedArm, Pose, SimArm, SimArmConfig, Workspace,
};

fn arm(mode: LimitMode, start: Pose) -> LimitedArm<SimArm> {
    let sim = SimArm::new(
        SimArmConfig {
            repeatability_mm: 0.0,
            repeatability_deg: 0.0,
            seed: 0,
        },
        start,
    );
    let ws = Workspace {
        min: [-100.0, -100.0, -10.0],
        max: [100.0, 100.0, 50.0],
        max_step_mm: 10.0,
        max_step_deg: 30.0,
    };
    LimitedArm::new(sim, ws, mode)
}

#[test]
fn refuse_mode_rejects_and_stays_put() {
    let start = Pose::planar(95.0, 0.0, 2.0, 0.0);
    let mut a = arm(LimitMode::Refuse, start);
    let err = a.move_to(Pose::planar(101.0, 0.0, 2.0, 0.0)).unwrap_err();
    assert!(
        matches!(err, ArmError::OutsideWorkspace { axis: 'x', .. }),
        "{err}"
    );
    let err = a.move_to(Pose::planar(95.0, 11.0, 2.0, 0.0)).unwrap_err();
    assert!(matches!(err, ArmError::StepTooLarge { .. }), "{err}");
    let err = a.move_to(Pose::planar(95.0, 0.0, 2.0, 31.0)).unwrap_err();
    assert!(matches!(err, ArmError::RotationTooLarge { .. }), "{err}");
    assert_eq!(a.pose(), start);
    assert_eq!(a.inner().moves(), 0);
    // Allowed moves go through, including exactly on the bounds.
    a.move_to(Pose::planar(100.0, 0.0, 2.0, 30.0)).unwrap();
    a.tap_down(5.0).unwrap();
    assert_eq!(a.pose(), Pose::planar(100.0, 0.0, -3.0, 30.0));
    assert_eq!(a.inner().moves(), 2);
}

#[test]
fn rotation_limit_uses_the_short_way_round() {
    let mut a = arm(LimitMode::Refuse, Pose::planar(0.0, 0.0, 0.0, 170.0));
    a.move_to(Pose::planar(0.0, 0.0, 0.0, -170.0))
        .expect("a 20 deg turn across +-180");
}

#[test]
fn clamp_mode_shortens_along_the_same_direction() {
    let mut a = arm(LimitMode::Clamp, Pose::planar(0.0, 0.0, 0.0, 0.0));
    a.move_to(Pose::planar(30.0, 40.0, 0.0, 0.0)).unwrap();
    let p = a.pose();
    assert!(
        (p.x - 6.0).abs() < 1e-12 && (p.y - 8.0).abs() < 1e-12,
        "{p:?}"
    );
    a.move_to(Pose::planar(6.0, 8.0, 0.0, 90.0)).unwrap();
    assert!(
        (a.pose().rz - 30.0).abs() < 1e-9,
        "rotation step shortened: {:?}",
        a.pose()
    );
}

#[test]
fn clamp_mode_keeps_the_tip_in_the_box() {
    let mut a = arm(LimitMode::Clamp, Pose::planar(95.0, 95.0, 45.0, 0.0));
    a.move_to(Pose::planar(200.0, 97.0, 60.0, 0.0)).unwrap();
    assert_eq!(a.pose(), Pose::planar(100.0, 97.0, 50.0, 0.0));
    for _ in 0..5 {
        a.move_to(Pose::planar(-500.0, -500.0, -500.0, 0.0))
            .unwrap();
        let p = a.pose();
        assert!(p.x >= -100.0 && p.y >= -100.0 && p.z >= -10.0);
    }
}

#[test]
fn invalid_limits_and_poses_are_errors() {
    let sim = SimArm::new(SimArmConfig::default(), Pose::default());
    let ws = Workspace {
        max_step_mm: 0.0,
        ..Workspace::default()
    };
    let mut a = LimitedArm::new(sim, ws, LimitMode::Clamp);
    assert!(matches!(
        a.move_to(Pose::default()),
        Err(ArmError::InvalidConfig { .. })
    ));
    let mut a = arm(LimitMode::Clamp, Pose::default());
    let nan = Pose {
        rz: f64::NAN,
        ..Pose::default()
    };
    assert!(matches!(
        a.move_to(nan),
        Err(ArmError::NonFinitePose { .. })
    ));
}

#[test]
fn default_workspace_is_valid() {
    Workspace::default().validate().unwrap();
}

#[test]
fn configs_read_from_toml_with_defaults_and_reject_typos() {
    let ws: Workspace = toml::from_str("max_step_mm = 5.0\nmin = [-1.0, -2.0, -3.0]").unwrap();
    assert_eq!(ws.max_step_mm, 5.0);
    assert_eq!(ws.min, [-1.0, -2.0, -3.0]);
    assert_eq!(ws.max, Workspace::default().max);
    assert!(toml::from_str::<Workspace>("max_step = 5.0").is_err());
    let cfg: SimArmConfig = toml::from_str("seed = 4").unwrap();
    assert_eq!(
        cfg,
        SimArmConfig {
            seed: 4,
            ..SimArmConfig::default()
        }
    );
    assert!(toml::from_str::<SimArmConfig>("repeatability = 0.1").is_err());
    let mode: LimitMode = toml::from_str::<toml::Table>("mode = \"clamp\"").unwrap()["mode"]
        .clone()
        .try_into()
        .unwrap();
    assert_eq!(mode, LimitMode::Clamp);
}

/// An arm that reports whatever pose it is given (a driver reading a
/// controller's state) and counts the moves that reach it.
struct Reporting {
    pose: Pose,
    moves: usize,
}

impl Arm for Reporting {
    fn move_to(&mut self, pose: Pose) -> Result<(), ArmError> {
        self.moves += 1;
        self.pose = pose;
        Ok(())
    }
    fn pose(&self) -> Pose {
        self.pose
    }
}

fn reporting(mode: LimitMode, current: Pose) -> LimitedArm<Reporting> {
    let ws = Workspace {
        min: [-100.0, -100.0, -10.0],
        max: [100.0, 100.0, 50.0],
        max_step_mm: 10.0,
        max_step_deg: 30.0,
    };
    LimitedArm::new(
        Reporting {
            pose: current,
            moves: 0,
        },
        ws,
        mode,
    )
}

/// Issue 20: a NaN, infinite or absurdly large current pose (a controller
/// state of 1e306 m became NaN in the work frame) let the step check pass,
/// since `NaN > max_step` is false. Every such current pose must refuse,
/// in both modes, and nothing may reach the arm.
#[test]
fn a_nan_inf_or_huge_current_pose_refuses_every_move() {
    let target = Pose::planar(1.0, 2.0, 3.0, 4.0);
    let non_finite = [
        Pose::planar(f64::NAN, f64::NAN, f64::NAN, 0.0),
        Pose::planar(0.0, 0.0, f64::INFINITY, 0.0),
        Pose::new(0.0, 0.0, 0.0, f64::NAN, 0.0, 0.0),
        Pose::new(0.0, 0.0, 0.0, 0.0, 0.0, f64::NEG_INFINITY),
    ];
    for mode in [LimitMode::Refuse, LimitMode::Clamp] {
        for current in non_finite {
            let mut a = reporting(mode, current);
            let err = a.move_to(target).unwrap_err();
            assert!(
                matches!(err, ArmError::CurrentPoseNotFinite { .. }),
                "{mode:?} {current:?}: {err}"
            );
            assert!(err.to_string().contains("NaN") || err.to_string().contains("inf"));
            assert_eq!(a.inner().moves, 0, "{mode:?} {current:?}");
        }
        let huge = [
            Pose::planar(1e306, 0.0, 0.0, 0.0),
            Pose::planar(-1e200, 1e200, 1e200, 0.0),
            Pose::planar(f64::MAX, f64::MAX, 0.0, 0.0),
        ];
        for current in huge {
            let mut a = reporting(mode, current);
            let err = a.move_to(target).unwrap_err();
            assert!(
                matches!(err, ArmError::StepTooLarge { .. }),
                "{mode:?} {current:?}: {err}"
            );
            assert_eq!(a.inner().moves, 0, "{mode:?} {current:?}");
        }
        // A rotation of 1e200 degrees is finite; the turn it implies is
        // measured like any other.
        let mut a = reporting(mode, Pose::new(1.0, 2.0, 3.0, 1e200, 0.0, 0.0));
        match a.move_to(target) {
            Err(ArmError::RotationTooLarge { step_deg, .. }) => assert!(step_deg.is_finite()),
            Ok(()) => assert!(a.pose().is_finite() && a.inner().moves == 1),
            Err(e) => panic!("{mode:?}: {e}"),
        }
    }
}

/// Issue 20: NaN-proof comparisons in the rule itself, on finite poses
/// whose steps overflow to infinity or whose box check sees a NaN.
#[test]
fn the_refuse_rule_refuses_infinite_steps_and_clamp_never_leaves_the_box() {
    let ws = Workspace::default();
    let at = |x: f64| FinitePose::new(Pose::planar(x, 0.0, 0.0, 0.0)).unwrap();
    let err = ws.check_move(at(1e300), at(0.0)).unwrap_err();
    assert!(matches!(err, ArmError::StepTooLarge { step_mm, .. } if step_mm.is_infinite()));
    assert!(ws.check_move(at(0.0), at(10.0)).is_ok());
    let err = ws.check_inside(Pose::planar(f64::NAN, 0.0, 0.0, 0.0));
    assert!(matches!(
        err,
        Err(ArmError::OutsideWorkspace { axis: 'x', .. })
    ));
    // Clamp mode from outside the box: a step that would end outside it
    // is refused, never sent.
    let mut a = reporting(LimitMode::Clamp, Pose::planar(500.0, 0.0, 0.0, 0.0));
    let err = a.move_to(Pose::planar(0.0, 0.0, 0.0, 0.0)).unwrap_err();
    assert!(matches!(err, ArmError::OutsideWorkspace { .. }), "{err}");
    assert_eq!(a.inner().moves, 0);
    // A NaN target is refused in both modes, before the arm is asked.
    for mode in [LimitMode::Refuse, LimitMode::Clamp] {
        let mut a = reporting(mode, Pose::default());
        let err = a
            .move_to(Pose::planar(0.0, f64::NAN, 0.0, 0.0))
            .unwrap_err();
        assert!(matches!(err, ArmError::NonFinitePose { .. }), "{err}");
        assert_eq!(a.inner().moves, 0);
    }
}
