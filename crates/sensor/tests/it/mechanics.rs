//! Contact mechanics against theory: rest pattern without contact, and the
//! symmetries and monotonicity the physics demands (docs/sensor-model.md).
#![allow(clippy::needless_range_loop)]
use crate::common;
use common::*;
use tactrace_geometry::{Pose, Vec2};
use tactrace_sensor::Shear;

/// A typical tap, mm: the rig's default depth; the real edge taps fit
/// 4.5-6.5 mm (docs/sensor-model.md).
const TAP: f64 = 5.0;

#[test]
fn no_contact_gives_the_rest_pins_exactly() {
    let model = plain_model();
    let object = square([0.0, 0.0], 30.0);
    let above = model.pins(&object, Pose::planar(0.0, 0.0, 0.5, 17.0), None);
    assert_eq!(above, model.rest_pins());
    let off_object = model.pins(&object, tap(80.0, 0.0, 4.0, 0.0), None);
    assert_eq!(off_object, model.rest_pins());
    let with_shear = Some(Shear {
        dx_mm: 3.0,
        dy_mm: 0.0,
        drz_deg: 4.0,
    });
    assert_eq!(
        model.pins(&object, tap(80.0, 0.0, 4.0, 0.0), with_shear),
        model.rest_pins()
    );
}

#[test]
fn rotating_the_sensor_by_60_degrees_permutes_and_rotates_the_field() {
    // Straight edge y = -2 (object below). Sensor yaw +60 turns the object by
    // -60 in the sensor frame: d60(p) = R(-60) d0(R(60) p) on the hexagonal
    // lattice, which is symmetric under 60 degree turns.
    let model = plain_model();
    let sd = |p: Vec2| p.y + 2.0;
    let d0 = displacement(&model, &model.pins_sdf(&sd, tap(0.0, 0.0, TAP, 0.0), None));
    let d60 = displacement(&model, &model.pins_sdf(&sd, tap(0.0, 0.0, TAP, 60.0), None));
    let rest = model.rest_pins();
    assert!(mean_magnitude(&d0) > 1.0, "edge contact must move pins");
    for i in 0..rest.len() {
        let j = partner(rest, i, |v| rotate(v, 60.0));
        let expected = rotate(d0[j], -60.0);
        let err = (d60[i][0] - expected[0]).hypot(d60[i][1] - expected[1]);
        assert!(err < 1e-3, "pin {i}: {:?} vs {:?}", d60[i], expected);
    }
}

#[test]
fn rotating_the_sensor_by_any_angle_rotates_the_net_displacement() {
    // Off the lattice's 60 deg symmetry the equality holds up to the patch
    // quadrature; a 0.5 mm patch keeps that error small for the fitted
    // sharp flow core (0.19 mm; at the default 1 mm patch: 3.7 deg at 37).
    let mut cfg = plain_model().config().clone();
    cfg.mechanics.patch_grid_mm = 0.5;
    let model = tactrace_sensor::TacTipModel::new(cfg).expect("valid");
    let sd = |p: Vec2| p.y + 1.0;
    let net = |rz: f64| {
        let d = displacement(&model, &model.pins_sdf(&sd, tap(0.0, 0.0, 3.0, rz), None));
        let s = d.iter().fold([0.0, 0.0], |a, v| [a[0] + v[0], a[1] + v[1]]);
        (s, mean_magnitude(&d))
    };
    let (n0, m0) = net(0.0);
    for rz in [17.0, 37.0, -41.0] {
        let (n, m) = net(rz);
        let expected = rotate(n0, -rz);
        let angle = (n[1].atan2(n[0]) - expected[1].atan2(expected[0])).to_degrees();
        let angle = (angle + 180.0).rem_euclid(360.0) - 180.0;
        assert!(
            angle.abs() < 2.0,
            "rz {rz}: net displacement off by {angle} deg"
        );
        assert!(
            (m / m0 - 1.0).abs() < 0.03,
            "rz {rz}: mean magnitude {m} vs {m0}"
        );
    }
}

#[test]
fn edge_at_r_and_mirrored_edge_at_minus_r_give_mirrored_fields() {
    // Object on -y with the edge at y = -r, versus object on +y with the
    // edge at y = +r: mirror images about the sensor's x axis.
    let model = plain_model();
    let rest = model.rest_pins();
    for r in [-3.0, 0.0, 2.5] {
        let below = move |p: Vec2| p.y + r;
        let above = move |p: Vec2| -p.y + r;
        let a = displacement(
            &model,
            &model.pins_sdf(&below, tap(0.0, 0.0, 3.0, 0.0), None),
        );
        let b = displacement(
            &model,
            &model.pins_sdf(&above, tap(0.0, 0.0, 3.0, 0.0), None),
        );
        for i in 0..rest.len() {
            let j = partner(rest, i, |v| [v[0], -v[1]]);
            let err = (b[i][0] - a[j][0]).hypot(b[i][1] + a[j][1]);
            assert!(
                err < 1e-3,
                "r {r} pin {i}: {:?} vs mirrored {:?}",
                b[i],
                a[j]
            );
        }
    }
}

#[test]
fn angle_and_minus_angle_give_mirrored_fields() {
    let model = plain_model();
    let rest = model.rest_pins();
    let sd = |p: Vec2| p.y + 1.5;
    let a = displacement(&model, &model.pins_sdf(&sd, tap(0.0, 0.0, 3.0, 25.0), None));
    let b = displacement(
        &model,
        &model.pins_sdf(&sd, tap(0.0, 0.0, 3.0, -25.0), None),
    );
    for i in 0..rest.len() {
        let j = partner(rest, i, |v| [-v[0], v[1]]);
        let err = (b[i][0] + a[j][0]).hypot(b[i][1] - a[j][1]);
        assert!(err < 0.05, "pin {i}: {:?} vs mirrored {:?}", b[i], a[j]);
    }
}

#[test]
fn deeper_taps_move_pins_further() {
    let model = plain_model();
    let object = square([0.0, -30.0], 30.0);
    let mut last = 0.0;
    for depth in [0.5, 1.0, 2.0, 3.0, 4.0, 5.0] {
        let d = displacement(
            &model,
            &model.pins(&object, tap(0.0, 0.0, depth, 0.0), None),
        );
        let m = mean_magnitude(&d);
        assert!(m > last * 1.05, "depth {depth}: mean {m} not above {last}");
        last = m;
    }
}

#[test]
fn moving_the_edge_changes_the_field_and_pins_near_the_edge_respond() {
    let model = plain_model();
    let at = |r: f64| {
        let sd = move |p: Vec2| p.y + r;
        displacement(&model, &model.pins_sdf(&sd, tap(0.0, 0.0, TAP, 0.0), None))
    };
    let (a, b) = (at(1.0), at(1.5));
    let change: f64 = a
        .iter()
        .zip(&b)
        .map(|(u, v)| (u[0] - v[0]).hypot(u[1] - v[1]))
        .sum::<f64>()
        / a.len() as f64;
    assert!(
        change > 0.1,
        "0.5 mm edge shift changed pins by only {change} px on average"
    );
    // The ring-1 pins at +-30 and +-150 deg sit 2.1 mm either side of an
    // edge through the origin and must respond. (The ones at +-90 deg are
    // 4.2 mm away: the one in the middle of the pressed half barely moves
    // sideways, as pins in the middle of the contact do on the real frames.)
    let through = at(0.0);
    let rest = model.rest_pins();
    let beside_edge = |i: &usize| {
        let (dx, dy) = (rest[*i][0] - rest[0][0], rest[*i][1] - rest[0][1]);
        dy.abs() < dx.abs()
    };
    let near: Vec<usize> = (1..7).filter(beside_edge).collect();
    assert_eq!(near.len(), 4);
    for (i, d) in near.iter().map(|&i| (i, through[i])) {
        assert!(
            d[0].hypot(d[1]) > 0.3,
            "pin {i} next to the edge moved {d:?}"
        );
    }
}

#[test]
fn curvature_and_corners_change_the_pattern() {
    let model = plain_model();
    let straight = square([0.0, -40.0], 40.0);
    let corner = square([-40.0, -40.0], 40.0);
    let disk_vertices = (0..720)
        .map(|k| {
            let t = k as f64 / 720.0 * std::f64::consts::TAU;
            Vec2::new(12.0 * t.cos(), 12.0 * t.sin() - 12.0)
        })
        .collect();
    let small_disk = tactrace_geometry::Contour::new(disk_vertices).expect("disk");
    let pose = tap(0.0, 0.0, TAP, 0.0);
    let d_straight = displacement(&model, &model.pins(&straight, pose, None));
    for other in [&corner, &small_disk] {
        let d = displacement(&model, &model.pins(other, pose, None));
        let diff: f64 = d
            .iter()
            .zip(&d_straight)
            .map(|(u, v)| (u[0] - v[0]).hypot(u[1] - v[1]))
            .sum::<f64>()
            / d.len() as f64;
        assert!(diff > 0.3, "pattern barely changed: {diff} px");
    }
}

#[test]
fn shear_drags_contact_pins_against_the_slide_and_saturates() {
    let model = plain_model();
    let object = square([0.0, 0.0], 30.0);
    let pose = tap(0.0, 0.0, 3.0, 0.0);
    let base = model.pins(&object, pose, None);
    let slid = |dx: f64| {
        let pins = model.pins(
            &object,
            pose,
            Some(Shear {
                dx_mm: dx,
                dy_mm: 0.0,
                drz_deg: 0.0,
            }),
        );
        pins[0][0] - base[0][0]
    };
    let (small, big, huge) = (slid(0.5), slid(5.0), slid(10.0));
    assert!(small < -0.5, "centre pin lags the slide: {small}");
    assert!(big < small, "more slide, more drag: {big} vs {small}");
    assert!(
        (huge - big).abs() < 0.05 * big.abs(),
        "drag saturates: {huge} vs {big}"
    );
}

#[test]
fn the_rim_clamp_holds_the_outer_ring_and_leaves_the_centre() {
    let object = square([0.0, -30.0], 30.0);
    let pose = tap(0.0, 2.0, TAP, 10.0);
    let run = |rim: f64| {
        let mut cfg = tactrace_sensor::TacTipConfig::default();
        cfg.camera.rotation_deg = 0.0;
        cfg.camera.mirror = false;
        cfg.mechanics.rim_clamp_mm = rim;
        let model = tactrace_sensor::TacTipModel::new(cfg).expect("valid");
        displacement(&model, &model.pins(&object, pose, None))
    };
    let (free, clamped, tight) = (run(1e6), run(29.81), run(20.0));
    let outer = |d: &[[f64; 2]]| mean_magnitude(&d[91..]);
    assert!(
        outer(&clamped) < 0.5 * outer(&free),
        "outer ring {} vs free {}",
        outer(&clamped),
        outer(&free)
    );
    let c = (clamped[0][0] - free[0][0]).hypot(clamped[0][1] - free[0][1]);
    assert!(c < 1e-9, "centre pin unaffected by the clamp: {c}");
    // The outer ring (index 91 on) lies beyond 20 mm of skin: held still.
    assert!(tight[91..].iter().all(|d| d[0] == 0.0 && d[1] == 0.0));
}

#[test]
fn a_compliant_mount_shrinks_a_wide_contact_more_than_a_narrow_one() {
    // Eq. S4a: the depth lost grows with the indented volume, so the field
    // of a tap fully on the object shrinks more than one near the edge.
    let rigid = plain_model();
    let mut cfg = rigid.config().clone();
    cfg.mechanics.compliance_mm = 0.5;
    let soft = tactrace_sensor::TacTipModel::new(cfg).expect("valid");
    let size = |model: &tactrace_sensor::TacTipModel, edge: f64| {
        let sd = move |p: Vec2| p.y - edge;
        mean_magnitude(&displacement(
            model,
            &model.pins_sdf(&sd, tap(0.0, 0.0, TAP, 0.0), None),
        ))
    };
    let (wide, narrow) = (20.0, -6.0);
    let ratio_wide = size(&soft, wide) / size(&rigid, wide);
    let ratio_narrow = size(&soft, narrow) / size(&rigid, narrow);
    assert!(
        ratio_wide < 1.0 && ratio_narrow < 1.0,
        "{ratio_wide} {ratio_narrow}"
    );
    assert!(
        ratio_wide < ratio_narrow - 0.05,
        "wide {ratio_wide} narrow {ratio_narrow}"
    );
}
