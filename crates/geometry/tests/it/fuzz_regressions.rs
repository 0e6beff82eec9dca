//! Regression tests for inputs found by the mutation fuzz of the CLI
//! (tests/it/fuzz_inputs/mod.rs at the workspace root), one per bug.
use tactrace_geometry::{parse_contour_csv, GeometryError, MAX_COORDINATE_MM};

/// An ellipse outline with one coordinate replaced by `value`.
fn outline_with(value: &str) -> String {
    let mut s = String::from("x,y\n");
    for k in 0..40 {
        let a = k as f64 * std::f64::consts::TAU / 40.0;
        let (x, y) = (50.0 * a.cos(), 35.0 * a.sin());
        if k == 7 {
            s += &format!("{value},{y:.3}\n");
        } else {
            s += &format!("{x:.3},{y:.3}\n");
        }
    }
    s
}

/// A vertex at 1e308 (or 2^32) mm gave an infinite (or 1e10 mm) perimeter;
/// `follow` then sized a buffer by it: capacity overflow, or an abort.
#[test]
fn contour_vertex_at_1e308_is_out_of_range() {
    for value in ["1e308", "4294967296", "-1e7"] {
        let err = parse_contour_csv(&outline_with(value)).expect_err(value);
        assert!(
            matches!(err, GeometryError::OutOfRange { index: 7, .. }),
            "{value}: {err}"
        );
        assert!(err.to_string().contains("mm"), "{err}");
    }
    let near = format!("{}", MAX_COORDINATE_MM * 0.5);
    let c = parse_contour_csv(&outline_with(&near)).expect("inside the range");
    assert!(c.perimeter().is_finite());
}
