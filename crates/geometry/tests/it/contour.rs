//! Contour queries checked against closed-form answers (square, circle)
//! and against brute force over every edge.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_geometry::{builtin_shape, BuiltinShape, Contour, GeometryError, Vec2};

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x, y)
}

fn square() -> Contour {
    Contour::new(vec![v(0.0, 0.0), v(10.0, 0.0), v(10.0, 10.0), v(0.0, 10.0)]).unwrap()
}

fn circle(c: Vec2, r: f64, n: usize) -> Contour {
    let pts = (0..n)
        .map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            c + r * v(t.cos(), t.sin())
        })
        .collect();
    Contour::new(pts).unwrap()
}

/// Exact nearest distance by scanning every edge.
fn brute_distance(contour: &Contour, p: Vec2) -> f64 {
    let vs = contour.vertices();
    (0..vs.len())
        .map(|i| {
            let (a, b) = (vs[i], vs[(i + 1) % vs.len()]);
            let d = b - a;
            let t = ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
            (a + d * t - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Even-odd ray casting, the textbook inside test.
fn brute_inside(contour: &Contour, p: Vec2) -> bool {
    let vs = contour.vertices();
    let mut inside = false;
    for i in 0..vs.len() {
        let (a, b) = (vs[i], vs[(i + 1) % vs.len()]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

#[test]
fn square_measures() {
    let s = square();
    assert!((s.perimeter() - 40.0).abs() < 1e-12);
    assert!((s.area() - 100.0).abs() < 1e-12);
    assert_eq!(s.bounds(), (v(0.0, 0.0), v(10.0, 10.0)));
    assert!(s.contains(v(5.0, 5.0)));
    assert!(!s.contains(v(11.0, 5.0)));
    assert!(
        !s.contains(v(10.0, 5.0)),
        "points on the edge are not strictly inside"
    );
}

#[test]
fn square_signed_distance_and_normals() {
    let s = square();
    let e = s.nearest(v(5.0, 2.0));
    assert!((e.signed_distance + 2.0).abs() < 1e-12);
    assert!((e.point - v(5.0, 0.0)).norm() < 1e-12);
    assert!(
        (e.normal - v(0.0, -1.0)).norm() < 1e-12,
        "outward normal of the bottom edge"
    );
    assert!((e.arc_length - 5.0).abs() < 1e-12);
    // Off a corner, outside: the normal points from the corner to the query.
    let e = s.nearest(v(13.0, 14.0));
    assert!((e.signed_distance - 5.0).abs() < 1e-12);
    assert!((e.normal - v(0.6, 0.8)).norm() < 1e-12);
    assert!((e.arc_length - 20.0).abs() < 1e-12);
    // Exactly on an edge: the edge normal.
    let e = s.nearest(v(10.0, 4.0));
    assert_eq!(e.signed_distance, 0.0);
    assert!((e.normal - v(1.0, 0.0)).norm() < 1e-12);
    // Exactly on a vertex: the bisecting pseudo-normal.
    let e = s.nearest(v(0.0, 0.0));
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!((e.normal - v(-h, -h)).norm() < 1e-12);
}

#[test]
fn clockwise_input_is_reversed_keeping_first_vertex() {
    let cw = Contour::new(vec![v(0.0, 0.0), v(0.0, 10.0), v(10.0, 10.0), v(10.0, 0.0)]).unwrap();
    assert_eq!(cw.vertices()[0], v(0.0, 0.0));
    assert_eq!(
        cw.vertices()[1],
        v(10.0, 0.0),
        "counter-clockwise after the first vertex"
    );
    assert!((cw.signed_distance(v(5.0, 5.0)) + 5.0).abs() < 1e-12);
}

#[test]
fn repeated_closing_point_is_dropped() {
    let c = Contour::new(vec![v(0.0, 0.0), v(10.0, 0.0), v(10.0, 10.0), v(0.0, 0.0)]).unwrap();
    assert_eq!(c.vertices().len(), 3);
    assert!((c.area() - 50.0).abs() < 1e-12);
}

#[test]
fn invalid_polygons_are_rejected() {
    let err = Contour::new(vec![v(0.0, 0.0), v(1.0, 0.0)]).unwrap_err();
    assert!(matches!(
        err,
        GeometryError::TooFewPoints { points: 2, min: 3 }
    ));
    let err = Contour::new(vec![v(0.0, 0.0), v(1.0, 0.0), v(1.0, 0.0), v(0.0, 0.0)]).unwrap_err();
    assert!(matches!(err, GeometryError::TooFewPoints { points: 2, .. }));
    let err = Contour::new(vec![v(0.0, 0.0), v(1.0, 1.0), v(2.0, 2.0)]).unwrap_err();
    assert!(matches!(err, GeometryError::Degenerate));
    let err = Contour::new(vec![v(0.0, 0.0), v(2.0, 2.0), v(2.0, 0.0), v(0.0, 2.0)]).unwrap_err();
    assert!(
        matches!(err, GeometryError::SelfIntersecting { .. }),
        "{err}"
    );
    let err = Contour::new(vec![v(0.0, 0.0), v(f64::NAN, 1.0), v(1.0, 1.0)]).unwrap_err();
    assert!(matches!(err, GeometryError::NonFinite { index: 1 }));
    // A figure eight pinched at one shared vertex.
    let eight = vec![
        v(0.0, 0.0),
        v(1.0, 1.0),
        v(2.0, 0.0),
        v(3.0, 1.0),
        v(3.0, -1.0),
        v(2.0, 0.0),
        v(1.0, -1.0),
    ];
    assert!(matches!(
        Contour::new(eight),
        Err(GeometryError::SelfIntersecting { .. })
    ));
}

#[test]
fn circle_distance_matches_radius_formula() {
    let (c, r) = (v(5.5, -51.5), 55.2);
    let contour = circle(c, r, 4000);
    // Polygon inscribed in the circle: sagitta r (1 - cos(pi/n)).
    let tol = r * (1.0 - (std::f64::consts::PI / 4000.0).cos()) + 1e-9;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..2000 {
        let p = c + v(rng.random_range(-90.0..90.0), rng.random_range(-90.0..90.0));
        let expected = (p - c).norm() - r;
        let e = contour.nearest(p);
        assert!(
            (e.signed_distance - expected).abs() <= tol,
            "at {p:?}: {} vs {expected}",
            e.signed_distance
        );
        if (p - c).norm() > 1.0 {
            let radial = (p - c).normalize();
            assert!((e.normal - radial).norm() < 1e-3, "normal at {p:?}");
        }
        if expected.abs() > tol {
            assert_eq!(contour.contains(p), expected < 0.0, "inside test at {p:?}");
        }
    }
}

#[test]
fn nearest_agrees_with_brute_force_on_every_shape() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for shape in BuiltinShape::ALL {
        let contour = builtin_shape(shape);
        let (min, max) = contour.bounds();
        for _ in 0..300 {
            let p = v(
                rng.random_range(min.x - 20.0..max.x + 20.0),
                rng.random_range(min.y - 20.0..max.y + 20.0),
            );
            let e = contour.nearest(p);
            let brute = brute_distance(&contour, p);
            assert!(
                (e.signed_distance.abs() - brute).abs() < 1e-9,
                "{shape:?} at {p:?}"
            );
            assert_eq!(
                e.signed_distance < 0.0,
                brute_inside(&contour, p),
                "{shape:?} sign at {p:?}"
            );
            assert!((e.point - p).norm() - brute < 1e-9);
            assert!((e.normal.norm() - 1.0).abs() < 1e-9);
        }
    }
}

#[test]
fn arc_length_walks_the_edge() {
    let s = square();
    let (p, n) = s.at_arc_length(12.5);
    assert!((p - v(10.0, 2.5)).norm() < 1e-12);
    assert!((n - v(1.0, 0.0)).norm() < 1e-12);
    let (p, _) = s.at_arc_length(-2.5);
    assert!(
        (p - v(0.0, 2.5)).norm() < 1e-12,
        "wraps negative arc lengths"
    );
    let (p, _) = s.at_arc_length(45.0);
    assert!((p - v(5.0, 0.0)).norm() < 1e-12, "wraps past the perimeter");
    let pts = s.resample(8);
    assert_eq!(pts.len(), 8);
    assert_eq!(pts[0], v(0.0, 0.0));
    assert!((pts[3] - v(10.0, 5.0)).norm() < 1e-12);
    assert!(s.resample(0).is_empty());
    // nearest() reports the arc length at_arc_length() inverts.
    let e = s.nearest(v(3.0, 12.0));
    assert!((s.at_arc_length(e.arc_length).0 - e.point).norm() < 1e-12);
}

#[test]
fn nearest_is_fast() {
    let contour = builtin_shape(BuiltinShape::Flower);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let pts: Vec<Vec2> = (0..100_000)
        .map(|_| {
            v(
                rng.random_range(-60.0..75.0),
                rng.random_range(-120.0..15.0),
            )
        })
        .collect();
    let start = std::time::Instant::now();
    let total: f64 = pts.iter().map(|p| contour.signed_distance(*p)).sum();
    let elapsed = start.elapsed();
    eprintln!(
        "100k nearest queries on the flower ({} vertices): {elapsed:?} (checksum {total:.1})",
        contour.vertices().len()
    );
    assert!(
        elapsed.as_secs_f64() < 2.0,
        "nearest is too slow: {elapsed:?}"
    );
}
