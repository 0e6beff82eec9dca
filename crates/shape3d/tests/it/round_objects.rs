//! Theory tests of the objects added for the held-out suite: the dome and
//! the cylinder against their closed forms (distance, closest point,
//! normal, the column top at any tilt), the quadric patch's curvatures
//! (a saddle for k1 = -k2, a dome's top to fourth order), and a
//! parametric outline extruded.
use tactrace_geometry::ParametricShape;
use tactrace_shape3d::{
    numeric_gradient, Cylinder, Dome, HeightField, Object3d, ObjectConfig, Vec3,
};

fn close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, want {want} (tol {tol})"
    );
}

/// Points round an object's top, above and below its surface.
fn probes() -> Vec<Vec3> {
    let mut out = Vec::new();
    for (i, x) in [-25.0, -7.5, 0.0, 12.0, 28.0].iter().enumerate() {
        for (j, y) in [-18.0, 0.0, 9.0, 22.0].iter().enumerate() {
            let z = -12.0 + 5.0 * ((i + 2 * j) % 5) as f64;
            out.push(Vec3::new(*x, *y, z));
        }
    }
    out
}

/// The dome is the ball |p - (0, 0, -R)| <= R: its distance, closest
/// point and normal are the ball's; its top is the origin.
#[test]
fn the_dome_is_the_ball_under_the_origin() {
    let r = 60.0;
    let dome = Dome::new(r).unwrap();
    let c = Vec3::new(0.0, 0.0, -r);
    close(
        dome.signed_distance(Vec3::new(0.0, 0.0, 3.0)),
        3.0,
        1e-12,
        "above the top",
    );
    close(dome.signed_distance(c), -r, 1e-12, "the centre");
    for p in probes() {
        let want = (p - c).norm() - r;
        close(dome.signed_distance(p), want, 1e-9, "distance");
        let q = dome.closest_point(p);
        close((q - c).norm(), r, 1e-9, "closest point on the sphere");
        close((p - q).norm(), want.abs(), 1e-9, "closest point's distance");
        let n = dome.normal(p);
        assert!((n - (p - c).normalize()).norm() < 1e-12, "normal at {p:?}");
        assert!(
            (n - numeric_gradient(&dome, p)).norm() < 1e-6,
            "gradient at {p:?}"
        );
    }
    assert!(Dome::new(0.0).is_err() && Dome::new(f64::NAN).is_err());
}

/// The cylinder's distance is the distance from its axis less the
/// radius, the same all along the axis; its normal has no component
/// along the axis.
#[test]
fn the_cylinder_is_invariant_along_its_axis_and_round_across() {
    let r = 40.0;
    let cyl = Cylinder::new(r, 90.0).unwrap(); // lying along y
    for p in probes() {
        let want = p.x.hypot(p.z + r) - r;
        close(cyl.signed_distance(p), want, 1e-9, "distance");
        let along = p + Vec3::new(0.0, 31.0, 0.0);
        close(cyl.signed_distance(along), want, 1e-9, "along the axis");
        let n = cyl.normal(p);
        close(n.y, 0.0, 1e-12, "no normal along the axis");
        assert!(
            (n - numeric_gradient(&cyl, p)).norm() < 1e-6,
            "gradient at {p:?}"
        );
        let q = cyl.closest_point(p);
        close(cyl.signed_distance(q), 0.0, 1e-9, "closest point on it");
        close(q.y, p.y, 1e-9, "closest point across the axis");
    }
    // Turned: along azimuth 30 deg, the same solid seen turned.
    let turned = Cylinder::new(r, 30.0).unwrap();
    let (s, c) = 30f64.to_radians().sin_cos();
    let p = Vec3::new(5.0, -8.0, -3.0);
    // Into the frame where the axis is along y: rotate by 90 - 30 deg.
    let (s2, c2) = 60f64.to_radians().sin_cos();
    let p_y = Vec3::new(c2 * p.x - s2 * p.y, s2 * p.x + c2 * p.y, p.z);
    close(
        turned.signed_distance(p),
        cyl.signed_distance(p_y),
        1e-9,
        "turned",
    );
    close(
        turned.normal(p).dot(&Vec3::new(c, s, 0.0)),
        0.0,
        1e-12,
        "turned normal",
    );
    assert!(Cylinder::new(-1.0, 0.0).is_err() && Cylinder::new(10.0, f64::INFINITY).is_err());
}

/// At any tilt, the column top lies on the surface (distance 0), and a
/// column beside the dome or cylinder misses it.
#[test]
fn column_tops_of_the_dome_and_cylinder_lie_on_the_surface() {
    let objects: [(&str, Box<dyn Object3d>); 2] = [
        ("dome", Box::new(Dome::new(50.0).unwrap())),
        ("cylinder", Box::new(Cylinder::new(35.0, 20.0).unwrap())),
    ];
    for (name, object) in &objects {
        for (tx, ty) in [(0.0, 0.0), (20.0, -10.0), (-30.0, 25.0)] {
            let (tx, ty): (f64, f64) = (f64::to_radians(tx), f64::to_radians(ty));
            let axis = Vec3::new(ty.sin() * tx.cos(), -tx.sin(), ty.cos() * tx.cos());
            for (fx, fy) in [(0.0, 0.0), (12.0, -4.0), (-20.0, 15.0)] {
                let foot = Vec3::new(fx, fy, -15.0);
                let t = object.column_top(foot, axis, 30.0);
                assert!(t.is_finite() && t < 30.0, "{name}: {t}");
                let d = object.signed_distance(foot + axis * t);
                close(d, 0.0, 1e-9, name);
                // Just above is outside, just below inside.
                assert!(object.signed_distance(foot + axis * (t + 1e-3)) > 0.0);
                assert!(object.signed_distance(foot + axis * (t - 1e-3)) < 0.0);
            }
        }
    }
    let dome = Dome::new(50.0).unwrap();
    let beside = dome.column_top(Vec3::new(80.0, 0.0, -10.0), Vec3::z(), 30.0);
    assert_eq!(beside, f64::NEG_INFINITY);
    close(
        dome.column_top(Vec3::new(0.0, 0.0, -10.0), Vec3::z(), 5.0),
        5.0,
        0.0,
        "capped",
    );
}

/// The quadric's curvatures are the ones asked for: k1 = -k2 is the
/// saddle (with the sign of convexity), k1 = k2 = 1/R is a dome of
/// radius R to fourth order (z = -r^2 / 2R - r^4 / 8R^3 + ...), and a
/// curvature beyond 1/20 per mm is refused.
#[test]
fn the_quadric_patch_has_the_curvatures_it_is_given() {
    let r = 60.0;
    let saddle = HeightField::saddle(r).unwrap();
    let quadric = HeightField::quadric([-1.0 / r, 1.0 / r], 0.0).unwrap();
    for p in probes() {
        close(
            quadric.height(p.x, p.y),
            saddle.height(p.x, p.y),
            1e-12,
            "saddle",
        );
        close(
            quadric.signed_distance(p),
            saddle.signed_distance(p),
            1e-9,
            "saddle distance",
        );
    }
    let radius = 50.0;
    let cap = HeightField::quadric([1.0 / radius, 1.0 / radius], 25.0).unwrap();
    let dome = Dome::new(radius).unwrap();
    for (x, y) in [(3.0, 0.0), (0.0, -4.0), (3.0, 3.0)] {
        let dome_z = dome.column_top(Vec3::new(x, y, -20.0), Vec3::z(), 30.0) - 20.0;
        let rr: f64 = x * x + y * y;
        // The difference is the dome's fourth-order term, up to the sixth.
        let fourth = rr * rr / (8.0 * radius.powi(3));
        let sixth = rr.powi(3) / (8.0 * radius.powi(5));
        close(cap.height(x, y) - dome_z, fourth, sixth + 1e-12, "dome top");
    }
    // A cylinder-like patch along 30 deg: flat along it, curved across.
    let trough = HeightField::quadric([0.0, -1.0 / 40.0], 30.0).unwrap();
    let (s, c) = 30f64.to_radians().sin_cos();
    close(
        trough.height(10.0 * c, 10.0 * s),
        0.0,
        1e-12,
        "flat along the azimuth",
    );
    close(
        trough.height(-10.0 * s, 10.0 * c),
        100.0 / 80.0,
        1e-12,
        "concave across it",
    );
    close(cap.max_curvature(), 1.0 / radius, 1e-15, "max curvature");
    for p in probes() {
        let n = trough.normal(p);
        assert!(
            (n - numeric_gradient(&trough, p)).norm() < 1e-5,
            "gradient at {p:?}"
        );
    }
    assert!(HeightField::quadric([0.06, 0.0], 0.0).is_err());
    assert!(HeightField::quadric([0.0, f64::NAN], 0.0).is_err());
}

/// A parametric outline extruded: a square's top is flat at its height,
/// its rim the square's perimeter; an object configuration names it.
#[test]
fn an_extruded_square_has_its_outline_as_rim() {
    let cfg: ObjectConfig =
        toml::from_str("kind = \"prism\"\noutline = \"square:60\"\nheight_mm = 20.0\n").unwrap();
    assert_eq!(
        cfg,
        ObjectConfig::Prism {
            outline: ParametricShape::parse("square:60").unwrap().unwrap(),
            height_mm: 20.0
        }
    );
    let square = cfg.build().unwrap();
    close(
        square.signed_distance(Vec3::new(0.0, 0.0, 23.0)),
        3.0,
        1e-12,
        "over the top",
    );
    close(
        square.signed_distance(Vec3::new(34.0, 0.0, 10.0)),
        4.0,
        1e-9,
        "beside a side",
    );
    let edge = square.edge().unwrap();
    close(edge.length(), 240.0, 1e-6, "perimeter");
    assert!(edge
        .samples
        .iter()
        .all(|s| (s.point.z - 20.0).abs() < 1e-12));
    let bad = "kind = \"prism\"\noutline = \"star:3,5,5\"\nheight_mm = 20.0\n";
    assert!(toml::from_str::<ObjectConfig>(bad).is_err());
    let flat = "kind = \"prism\"\noutline = \"square:60\"\nheight_mm = 0.0\n";
    assert!(toml::from_str::<ObjectConfig>(flat)
        .unwrap()
        .build()
        .is_err());
}
