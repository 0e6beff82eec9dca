//! The 2D curvature policy carried by the SE(3) controller (the edge
//! tasks' `[controller.policy]`): off it changes no move at all; on, in
//! the plane, it is the 2D controller's policy (crates/control/src/
//! policy.rs: the reference shift c kappa and the shortened step).
use tactrace_control::{
    ControlError, PbtsConfig, PbtsController, PolicyConfig, Se3Config, Se3Controller, SensedPose,
    Task,
};

/// A seeded sequence of edge_5d predictions (x, z mm; rx, ry, rz deg)
/// with a turn in the middle, as a corner reads.
fn predictions(n: usize) -> Vec<[f64; 6]> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut noise = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    (0..n)
        .map(|k| {
            let turn = if (20..30).contains(&k) { 12.0 } else { 0.0 };
            [
                0.4 * noise(),
                0.0,
                3.0 + 0.3 * noise(),
                4.0 * noise(),
                4.0 * noise(),
                turn + 3.0 * noise(),
            ]
        })
        .collect()
}

/// The policy's settings as the 2D controller's tuned ones.
fn policy_on() -> PolicyConfig {
    PbtsConfig::tuned().policy
}

#[test]
fn the_policy_off_gives_bit_for_bit_the_same_moves() {
    // Off with other (inert) settings changed, and with the contact
    // observed each tap: every move identical to the preset's.
    let inert = PolicyConfig {
        max_offset_mm: 1.0,
        curvature_smoothing: 0.7,
        min_step_fraction: 0.5,
        ..PolicyConfig::default()
    };
    assert!(inert.is_off());
    let cfg = Se3Config {
        policy: inert,
        ..Se3Config::edge_5d()
    };
    let mut plain = Se3Controller::try_new(Se3Config::edge_5d()).unwrap();
    let mut off = Se3Controller::try_new(cfg).unwrap();
    for (k, p) in predictions(60).into_iter().enumerate() {
        off.observe_contact(1.0 + (k % 7) as f64);
        let a = plain.step(p).unwrap();
        let b = off.step(p).unwrap();
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "step {k}");
    }
    assert_eq!(off.curvature_per_mm(), 0.0);
    assert_eq!(plain.integral(), off.integral());
}

#[test]
fn in_the_plane_the_policy_is_the_2d_controllers() {
    let pbts = PbtsConfig {
        policy: PolicyConfig {
            step_contact: 0.5,
            ..policy_on()
        },
        ..PbtsConfig::report()
    };
    let mut planar = PbtsController::try_new(pbts.clone()).unwrap();
    let se3 = Se3Config {
        policy: pbts.policy.clone(),
        ..Se3Config::planar(&PbtsConfig::report()).unwrap()
    };
    let mut c = Se3Controller::try_new(se3).unwrap();
    for (k, p) in predictions(60).into_iter().enumerate() {
        let d = 2.0 + (k % 5) as f64;
        planar.observe_contact(d);
        c.observe_contact(d);
        let want = planar.step(SensedPose {
            r_mm: p[0],
            theta_deg: p[5],
        });
        let got = c.step([p[0], 0.0, 0.0, 0.0, 0.0, p[5]]).unwrap();
        let want = [want.x, want.y, want.rz];
        for (i, (g, w)) in [got[0], got[1], got[5]].iter().zip(want).enumerate() {
            assert!((g - w).abs() < 1e-9, "step {k}, component {i}: {g} vs {w}");
        }
        assert!((c.curvature_per_mm() - planar.curvature_per_mm()).abs() < 1e-12);
    }
}

#[test]
fn a_turn_read_at_a_corner_shortens_the_step() {
    let cfg = Se3Config {
        policy: policy_on(),
        ..Se3Config::edge_5d()
    };
    let mut c = Se3Controller::try_new(cfg).unwrap();
    let mut steps = Vec::new();
    for p in predictions(30) {
        steps.push(c.step(p).unwrap()[1]);
    }
    // Before the turn the step is near the reference's 1 mm (the read
    // noise alone shortens it a little); in the turn (predicted rz 12 deg
    // off the edge) it falls below half, and never below the floor.
    let floor = policy_on().min_step_fraction;
    let before = steps[5..20].iter().sum::<f64>() / 15.0;
    assert!(before > 0.75, "{before}: {steps:?}");
    assert!(steps[22..30].iter().all(|s| *s < 0.5), "{steps:?}");
    assert!(steps.iter().all(|s| *s >= floor - 1e-12), "{steps:?}");
    c.reset();
    assert_eq!(c.curvature_per_mm(), 0.0);
}

#[test]
fn the_policy_is_refused_where_it_cannot_act() {
    let surface = Se3Config {
        policy: policy_on(),
        ..Se3Config::surface_3d()
    };
    assert!(matches!(
        Se3Controller::try_new(surface),
        Err(ControlError::Policy { .. })
    ));
    let bad = Se3Config {
        policy: PolicyConfig {
            curvature_smoothing: 0.0,
            ..policy_on()
        },
        ..Se3Config::edge_5d()
    };
    let err = bad.validate().unwrap_err();
    assert!(err.to_string().contains("curvature_smoothing"), "{err}");
    assert_eq!(Task::Edge5d, Se3Config::edge_5d().task);
}

#[test]
fn the_policy_table_is_read_from_toml() {
    let text = "task = \"edge_5d\"\nreference = [0, 1, 3, 0, 0, 0]\n\
                kp = [0.5, 1, 0.5, 0.5, 0.5, 0.5]\nki = [0.3, 0, 0.3, 0.1, 0.1, 0.1]\n\
                integral_clip = [5, 5, 5, 45, 45, 45]\n\
                [policy]\nstep_curvature_mm = 10.0\nstep_contact = 1.0\n";
    let cfg: Se3Config = toml::from_str(text).unwrap();
    assert_eq!(cfg.policy.step_curvature_mm, 10.0);
    assert_eq!(cfg.policy.step_contact, 1.0);
    assert_eq!(
        cfg.policy.max_offset_mm,
        PolicyConfig::default().max_offset_mm
    );
    let unknown = text.replace("step_contact", "step_kontakt");
    assert!(toml::from_str::<Se3Config>(&unknown).is_err());
    let surface = text.replace("edge_5d", "surface_3d");
    let err = toml::from_str::<Se3Config>(&surface).unwrap_err();
    assert!(err.to_string().contains("senses rz"), "{err}");
}
