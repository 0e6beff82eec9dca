//! Theory tests of the simulated TacTip pressed into 3D objects (issue 23,
//! item 2): the planar contact is the level case (a flat surface gives the
//! full-plane press, an extruded shape's rim the planar edge contact), a
//! tilted sensor on a plane is a level sensor on the tilted ramp, and
//! deeper presses move the pins more. The turn of the field with the
//! tilt is tested in `src/contact3d.rs`.
use tactrace_geometry::{builtin_shape, BuiltinShape, Contour, Pose, Vec2};
use tactrace_sensor::{Shear, SimTacTip, SlipSpread, TacTipConfig, TacTipModel, TactileSensor};
use tactrace_shape3d::{Bowl, Extruded, HeightField, Object3d, Vec3};

fn worst(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

fn mean_motion(model: &TacTipModel, pins: &[[f64; 2]]) -> f64 {
    let rest = model.rest_pins();
    pins.iter()
        .zip(rest)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .sum::<f64>()
        / pins.len() as f64
}

/// The default sensor, one with a rigid mount and Cerruti spread, a
/// rings sensor and one with the brush law: every path of the contact's
/// arithmetic.
fn models() -> Vec<TacTipModel> {
    let mut rigid = TacTipConfig::default();
    rigid.mechanics.compliance_mm = 0.0;
    rigid.mechanics.slip_spread = SlipSpread::Cerruti;
    let mut rings = TacTipConfig::default();
    rings.geometry.layout = tactrace_sensor::PinLayout::Rings;
    let mut brush = TacTipConfig::default();
    brush.mechanics.slip_law = tactrace_sensor::SlipLaw::Brush;
    [TacTipConfig::default(), rigid, rings, brush]
        .into_iter()
        .map(|c| TacTipModel::new(c).unwrap())
        .collect()
}

const SHEARS: [Option<Shear>; 2] = [
    None,
    Some(Shear {
        dx_mm: 1.5,
        dy_mm: -0.8,
        drz_deg: 3.0,
    }),
];

#[test]
fn a_flat_surface_at_zero_tilt_is_the_planar_full_press() {
    for model in models() {
        for height in [0.0, 7.5] {
            let floor = HeightField::ramp(height, 0.0, 0.0).unwrap();
            for (depth, yaw) in [(0.5, 0.0), (3.0, 17.0), (6.25, -40.0), (9.0, 100.0)] {
                for shear in SHEARS {
                    let planar =
                        model.pins_sdf(&|_| -1e3, Pose::planar(2.0, -3.0, -depth, yaw), shear);
                    let tip = Pose::planar(2.0, -3.0, height - depth, yaw);
                    let got = model.pins_3d(&floor, tip, shear);
                    let err = worst(&planar, &got);
                    assert!(
                        err < 1e-9,
                        "depth {depth} yaw {yaw}: pins differ by {err} px"
                    );
                    assert!(
                        mean_motion(&model, &got) > 0.01,
                        "depth {depth}: no contact"
                    );
                }
            }
            let above = model.pins_3d(&floor, Pose::planar(0.0, 0.0, height + 0.1, 0.0), None);
            assert_eq!(
                above,
                model.rest_pins(),
                "no contact gives the rest pins exactly"
            );
        }
    }
}

/// Tip poses across the rim of `contour`: at arc lengths, offsets along
/// the outward normal, depths and yaws.
fn rim_poses(contour: &Contour) -> Vec<(Vec2, f64, f64)> {
    let mut out = Vec::new();
    for (k, offset) in [-4.0, -1.0, 0.0, 2.5].into_iter().enumerate() {
        let s = contour.perimeter() * (0.13 + 0.21 * k as f64);
        let (p, n) = contour.at_arc_length(s);
        for (depth, yaw) in [(2.0, 35.0), (5.0, -120.0)] {
            out.push((p + n * offset, depth, yaw));
        }
    }
    out
}

#[test]
fn a_3d_edge_at_zero_tilt_is_the_planar_edge_contact() {
    let h = 200.0;
    let square = Contour::new(vec![
        Vec2::new(-h, -h),
        Vec2::new(h, -h),
        Vec2::new(h, h),
        Vec2::new(-h, h),
    ])
    .unwrap();
    let mut contours: Vec<Contour> = BuiltinShape::ALL.into_iter().map(builtin_shape).collect();
    contours.push(square);
    let height = 12.0;
    for model in models() {
        for contour in &contours {
            let prism = Extruded::new(contour.clone(), height).unwrap();
            for (at, depth, yaw) in rim_poses(contour) {
                for shear in SHEARS {
                    let planar = model.pins(contour, Pose::planar(at.x, at.y, -depth, yaw), shear);
                    let got =
                        model.pins_3d(&prism, Pose::planar(at.x, at.y, height - depth, yaw), shear);
                    let err = worst(&planar, &got);
                    assert!(err < 1e-6, "{contour:?} at {at:?}: pins differ by {err} px");
                }
            }
        }
    }
}

#[test]
fn a_tilted_sensor_on_a_plane_is_a_level_sensor_on_the_tilted_ramp() {
    // Turning the whole scene about the pole by the sensor's inverse
    // rotation: the plane z = 0 becomes the plane of normal n = R^-1 z
    // whose signed distance from the pole is still -depth.
    let plane = HeightField::ramp(0.0, 0.0, 0.0).unwrap();
    for model in models() {
        for (rx, ry, rz, depth) in [
            (10.0, 0.0, 0.0, 3.0),
            (-15.0, 20.0, 40.0, 4.0),
            (5.0, -25.0, -110.0, 2.0),
        ] {
            let tip = Pose::new(3.0, -1.0, -depth, rx, ry, rz);
            let n = tip.to_isometry().rotation.inverse() * Vec3::z();
            let slope = n.z.acos().to_degrees();
            let azimuth = (-n.y).atan2(-n.x).to_degrees();
            let ramp = HeightField::ramp(depth / n.z, slope, azimuth).unwrap();
            for shear in SHEARS {
                let tilted = model.pins_3d(&plane, tip, shear);
                let level = model.pins_3d(&ramp, Pose::default(), shear);
                let err = worst(&tilted, &level);
                assert!(
                    err < 1e-6,
                    "tilt ({rx}, {ry}, {rz}): pins differ by {err} px"
                );
                let flat = model.pins_3d(&plane, Pose::planar(3.0, -1.0, -depth, rz), shear);
                assert!(
                    worst(&tilted, &flat) > 0.1,
                    "the tilt must change the field"
                );
            }
        }
    }
}

#[test]
fn a_deeper_press_moves_the_pins_more_at_any_tilt() {
    let model = TacTipModel::new(TacTipConfig::default()).unwrap();
    let objects: Vec<(&str, Box<dyn Object3d>, Vec3)> = vec![
        (
            "plane",
            Box::new(HeightField::ramp(0.0, 0.0, 0.0).unwrap()),
            Vec3::zeros(),
        ),
        (
            "saddle",
            Box::new(HeightField::saddle(60.0).unwrap()),
            Vec3::zeros(),
        ),
        (
            "wave",
            Box::new(HeightField::wave(1.5, 40.0, 30.0).unwrap()),
            Vec3::new(3.0, 2.0, 0.0),
        ),
        // The bowl's bottom, 40 - sqrt(40^2 - 30^2) mm under the rim.
        (
            "bowl",
            Box::new(Bowl::new(40.0, 30.0).unwrap()),
            Vec3::new(0.0, 0.0, -13.54),
        ),
        (
            "disk rim",
            Box::new(Extruded::new(builtin_shape(BuiltinShape::Disk), 10.0).unwrap()),
            Vec3::new(5.5 + 55.2, -51.5, 10.0),
        ),
    ];
    for (name, object, at) in &objects {
        for (rx, ry) in [(0.0, 0.0), (15.0, -10.0), (-25.0, 20.0)] {
            let mut last = 0.0;
            for step in 1..=12 {
                let depth = 0.5 * step as f64;
                let tip = Pose::new(at.x, at.y, at.z - depth, rx, ry, 30.0);
                let motion = mean_motion(&model, &model.pins_3d(object.as_ref(), tip, None));
                assert!(
                    motion > last,
                    "{name} tilt ({rx}, {ry}): depth {depth} moves the pins {motion} <= {last} px"
                );
                last = motion;
            }
        }
    }
}

#[test]
fn the_simulated_tactip_over_an_object_renders_the_3d_contact() {
    let mut cfg = TacTipConfig::default();
    cfg.nuisance.pin_jitter_px = 0.3;
    let model = TacTipModel::new(cfg).unwrap();
    let saddle = std::sync::Arc::new(HeightField::saddle(60.0).unwrap());
    let tip = Pose::new(0.0, 0.0, -3.0, 10.0, -5.0, 0.0);
    let mut sensor =
        SimTacTip::over_object(model.clone(), saddle.clone(), Box::new(move || tip), 7);
    let frame = sensor.capture().unwrap();
    let mut again = SimTacTip::over_object(model.clone(), saddle.clone(), Box::new(move || tip), 7);
    assert_eq!(frame, again.capture().unwrap(), "seeded nuisance repeats");
    let clean = model.render(&model.pins_3d(saddle.as_ref(), tip, None), None);
    let rest = sensor.reference_frame();
    let differs = |a: &tactrace_sensor::Frame, b: &tactrace_sensor::Frame| {
        a.iter().zip(b.iter()).filter(|(x, y)| x != y).count()
    };
    assert!(differs(&clean, &rest) > 500, "the press shows in the frame");
    assert!(
        differs(&frame, &clean) > 0,
        "the nuisance shows in the frame"
    );
}

/// A closed mesh of the box [-h, h]^2 x [0, top] (12 triangles, outward).
fn box_mesh(h: f64, top: f64) -> tactrace_shape3d::TriangleMesh {
    let v: Vec<Vec3> = (0..8)
        .map(|k| {
            Vec3::new(
                if k & 1 == 0 { -h } else { h },
                if k & 2 == 0 { -h } else { h },
                if k & 4 == 0 { 0.0 } else { top },
            )
        })
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [1, 3, 7, 5],
        [3, 2, 6, 7],
        [2, 0, 4, 6],
    ];
    let triangles = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    tactrace_shape3d::TriangleMesh::new(v, triangles).unwrap()
}

/// The edge_5d tap: the rim of an extruded box against the mesh of the
/// same box (its exact columns, walls included, without the rim's
/// anti-aliasing): at every tilt the fields agree within the patch's
/// resolution, and moving into the object presses more.
#[test]
fn an_extruded_rim_presses_like_the_mesh_of_the_same_box_at_any_tilt() {
    let model = TacTipModel::new(TacTipConfig::default()).unwrap();
    let (h, top) = (40.0, 10.0);
    let square = Contour::new(vec![
        Vec2::new(-h, -h),
        Vec2::new(h, -h),
        Vec2::new(h, h),
        Vec2::new(-h, h),
    ])
    .unwrap();
    let prism = Extruded::new(square, top).unwrap();
    let mesh = box_mesh(h, top);
    // The sample of the rim in the middle of the side x = h.
    let edge = prism.edge().unwrap();
    let side = edge
        .samples
        .iter()
        .min_by(|a, b| {
            let d = |s: &tactrace_shape3d::EdgeSample| (s.point - Vec3::new(h, 0.0, top)).norm();
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    for (rx, ry, rz) in [
        (0.0, 0.0, 30.0),
        (0.0, 20.0, 0.0),
        (0.0, -20.0, 90.0),
        (15.0, 10.0, -45.0),
    ] {
        let mut last = 0.0;
        for x in [4.0, 2.0, 0.0, -2.0, -4.0] {
            let tip = side.pose(Pose::new(x, 0.0, -4.0, rx, ry, rz));
            let a = model.pins_3d(&prism, tip, None);
            let b = model.pins_3d(&mesh, tip, None);
            let (ma, mb) = (mean_motion(&model, &a), mean_motion(&model, &b));
            assert!(
                (ma - mb).abs() <= 0.05 * mb + 0.02,
                "tilt ({rx}, {ry}) x {x}: prism {ma} px, mesh {mb} px"
            );
            assert!(ma > last, "tilt ({rx}, {ry}): moving onto the object to x {x} must press more ({ma} <= {last})");
            last = ma;
        }
    }
}

#[test]
fn an_edge_tap_in_the_rim_frame_at_zero_tilt_is_the_planar_edge_tap() {
    let model = TacTipModel::new(TacTipConfig::default()).unwrap();
    let height = 8.0;
    for shape in [BuiltinShape::Flower, BuiltinShape::Teardrop] {
        let contour = builtin_shape(shape);
        let prism = Extruded::new(contour.clone(), height).unwrap();
        let edge = prism.edge().unwrap();
        for sample in edge.samples.iter().step_by(97) {
            for (x, depth, rz) in [(-3.0, 2.0, 0.0), (0.0, 5.0, 40.0), (2.0, 4.0, -75.0)] {
                let tip = sample.pose(Pose::new(x, 0.0, -depth, 0.0, 0.0, rz));
                let planar = Pose::planar(tip.x, tip.y, tip.z - height, tip.rz);
                let want = model.pins(&contour, planar, SHEARS[1]);
                let got = model.pins_3d(&prism, tip, SHEARS[1]);
                let err = worst(&want, &got);
                assert!(err < 1e-6, "{shape:?} x {x}: pins differ by {err} px");
            }
        }
    }
}

#[test]
fn the_mesh_of_a_surface_presses_like_the_surface() {
    let model = TacTipModel::new(TacTipConfig::default()).unwrap();
    for surface in [
        HeightField::saddle(60.0).unwrap(),
        HeightField::wave(1.5, 40.0, 20.0).unwrap(),
    ] {
        let mesh =
            tactrace_shape3d::TriangleMesh::from_heights(30.0, 1.0, |x, y| surface.height(x, y))
                .unwrap();
        for (rx, ry) in [(0.0, 0.0), (-20.0, 15.0)] {
            let tip = Pose::new(2.0, -1.0, -4.0, rx, ry, 30.0);
            let want = model.pins_3d(&surface, tip, None);
            let err = worst(&want, &model.pins_3d(&mesh, tip, None));
            assert!(
                mean_motion(&model, &want) > 1.0,
                "{surface:?}: a real press"
            );
            assert!(
                err < 0.02,
                "{surface:?} tilt ({rx}, {ry}): mesh and formula differ by {err} px"
            );
        }
    }
}
