//! The built-in shapes against the appendix formulas (ERRATA for the trine).
use std::f64::consts::TAU;
use tactrace_geometry::{
    builtin_shape, BuiltinShape, Contour, ShapeSpec, Vec2, TRINE_ARC_T, TRINE_RADIUS_MM,
};

/// Arc length of the appendix curve by a very fine polyline (converges as
/// O(h^2); 10^6 pieces is far below the tolerances used here).
fn curve_length(shape: BuiltinShape, t0: f64, t1: f64) -> f64 {
    let n = 1_000_000;
    let mut prev = shape.curve_point(t0);
    let mut total = 0.0;
    for k in 1..=n {
        let p = shape.curve_point(t0 + (t1 - t0) * k as f64 / n as f64);
        total += (p - prev).norm();
        prev = p;
    }
    total
}

fn reference_perimeter(shape: BuiltinShape) -> f64 {
    match shape {
        BuiltinShape::Trine => {
            let (t0, t1) = TRINE_ARC_T;
            2.0 * TRINE_RADIUS_MM + curve_length(shape, t0, t1)
        }
        _ => curve_length(shape, 0.0, TAU),
    }
}

#[test]
fn perimeters_match_the_formulas() {
    let disk = builtin_shape(BuiltinShape::Disk);
    assert!(
        (disk.perimeter() - TAU * 55.2).abs() < 0.005,
        "disk {}",
        disk.perimeter()
    );
    assert!((disk.area() - std::f64::consts::PI * 55.2 * 55.2).abs() < 0.5);
    for shape in BuiltinShape::ALL {
        let polygon = builtin_shape(shape).perimeter();
        let reference = reference_perimeter(shape);
        let c = builtin_shape(shape);
        eprintln!("{shape:?}: {} vertices, perimeter {polygon:.3} mm (formula {reference:.3}), area {:.1} mm^2", c.vertices().len(), c.area());
        assert!(
            (polygon - reference).abs() < 0.01,
            "{shape:?}: {polygon} vs {reference}"
        );
    }
    let trine = builtin_shape(BuiltinShape::Trine).perimeter();
    assert!((trine - TRINE_RADIUS_MM * (2.0 + TRINE_ARC_T.1 - TRINE_ARC_T.0)).abs() < 0.01);
}

#[test]
fn polygons_stay_within_a_hundredth_of_a_millimetre() {
    for shape in BuiltinShape::ALL {
        let contour = builtin_shape(shape);
        let (t0, t1) = shape.parameter_range();
        let worst = (0..=20_000)
            .map(|k| {
                contour
                    .signed_distance(shape.curve_point(t0 + (t1 - t0) * k as f64 / 20_000.0))
                    .abs()
            })
            .fold(0.0, f64::max);
        assert!(
            worst < 0.01,
            "{shape:?}: curve is {worst} mm from the polygon"
        );
        let longest = contour
            .vertices()
            .iter()
            .zip(contour.vertices().iter().cycle().skip(1))
            .map(|(a, b)| (b - a).norm())
            .fold(0.0, f64::max);
        if shape != BuiltinShape::Trine {
            assert!(longest <= 0.2 + 1e-9, "{shape:?}: longest edge {longest}");
        }
    }
}

#[test]
fn built_in_shapes_are_valid_simple_polygons() {
    for shape in BuiltinShape::ALL {
        let contour = builtin_shape(shape);
        let checked = Contour::new(contour.vertices().to_vec()).expect("valid polygon");
        assert_eq!(checked, contour, "{shape:?} already counter-clockwise");
    }
}

#[test]
fn teardrop_point_is_vertex_zero() {
    let tear = builtin_shape(BuiltinShape::Teardrop);
    assert_eq!(tear.vertices()[0], Vec2::new(-64.0, -38.0));
    let (min, _) = tear.bounds();
    assert_eq!(min.x, -64.0, "the point is the leftmost extreme");
}

#[test]
fn trine_is_a_sector_about_its_apex() {
    let trine = builtin_shape(BuiltinShape::Trine);
    let apex = Vec2::new(-37.0, -8.0);
    assert_eq!(trine.vertices()[0], apex);
    // Every other vertex lies on the arc of radius 76 about the apex.
    for p in &trine.vertices()[1..] {
        assert!(((p - apex).norm() - 76.0).abs() < 1e-9);
    }
    let start = BuiltinShape::Trine.curve_point(TRINE_ARC_T.0);
    let end = BuiltinShape::Trine.curve_point(TRINE_ARC_T.1);
    assert!((start - Vec2::new(38.04, 4.16)).norm() < 0.05, "{start:?}");
    assert!((end - Vec2::new(-46.69, -83.39)).norm() < 0.05, "{end:?}");
    assert!(trine.contains(apex + 0.5 * ((start - apex) + (end - apex)).normalize() * 40.0));
}

#[test]
fn shape_spec_parses_names_and_paths() {
    assert_eq!(
        ShapeSpec::parse("Disk"),
        ShapeSpec::Builtin(BuiltinShape::Disk)
    );
    assert_eq!(
        ShapeSpec::parse(" TEARDROP "),
        ShapeSpec::Builtin(BuiltinShape::Teardrop)
    );
    let file = ShapeSpec::parse("shapes/star.csv");
    assert_eq!(file, ShapeSpec::File("shapes/star.csv".into()));
    assert_eq!(file.name(), "star");
    assert_eq!(ShapeSpec::parse("flower").name(), "flower");
    let toml_like: ShapeSpec = serde_json_like("\"trine\"");
    assert_eq!(toml_like, ShapeSpec::Builtin(BuiltinShape::Trine));
}

/// Deserialise through serde's value-free path (a JSON string) without a
/// JSON dependency: use the `IntoDeserializer` for &str.
fn serde_json_like(quoted: &str) -> ShapeSpec {
    use serde::de::IntoDeserializer;
    let inner = quoted.trim_matches('"');
    let de: serde::de::value::StrDeserializer<serde::de::value::Error> = inner.into_deserializer();
    serde::Deserialize::deserialize(de).expect("deserialises")
}
