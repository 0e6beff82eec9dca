//! Reading contours from CSV text: accepted variants and every error.
use tactrace_geometry::{parse_contour_csv, GeometryError};

#[test]
fn accepts_header_comments_and_separators() {
    let text = "# a 10 mm square\nx_mm,y_mm\n0,0\n\n10;0\n10 10  # corner\n0\t10\n0,0\n";
    let c = parse_contour_csv(text).unwrap();
    assert_eq!(c.vertices().len(), 4);
    assert!((c.area() - 100.0).abs() < 1e-12);
}

#[test]
fn small_closing_gap_is_closed_implicitly() {
    // Dense circle without a repeated point: gap = one segment.
    let text: String = (0..100)
        .map(|i| {
            let t = i as f64 / 100.0 * std::f64::consts::TAU;
            format!("{},{}\n", 20.0 * t.cos(), 20.0 * t.sin())
        })
        .collect();
    let c = parse_contour_csv(&text).unwrap();
    assert_eq!(c.vertices().len(), 100);
    // A coarse triangle: the gap is one segment, under 1.5 longest segments.
    assert!(parse_contour_csv("0,0\n10,0\n5,8\n").is_ok());
}

#[test]
fn open_outline_is_rejected() {
    // Short sides and a long gap: 5.83 mm against 1.5 x the 1 mm longest
    // segment (the 1 mm floor does not apply above it).
    let text = "0,0\n1,0\n2,0\n3,0\n3,1\n3,2\n3,3\n3,4\n3,5\n";
    match parse_contour_csv(text) {
        Err(GeometryError::NotClosed {
            gap_mm,
            tolerance_mm,
        }) => {
            assert!((gap_mm - 34f64.sqrt()).abs() < 1e-12);
            assert!((tolerance_mm - 1.5).abs() < 1e-12);
        }
        other => panic!("expected NotClosed, got {other:?}"),
    }
}

#[test]
fn bad_lines_report_their_line_number() {
    let err = parse_contour_csv("x,y\n0,0\n1,zero\n1,1\n").unwrap_err();
    assert!(
        matches!(err, GeometryError::BadLine { line: 3, .. }),
        "{err}"
    );
    let err = parse_contour_csv("0,0\n1,NaN\n1,1\n").unwrap_err();
    assert!(
        matches!(err, GeometryError::BadLine { line: 2, .. }),
        "{err}"
    );
    let err = parse_contour_csv("0,0\n1,0,5\n1,1\n").unwrap_err();
    assert!(
        matches!(err, GeometryError::BadLine { line: 2, .. }),
        "{err}"
    );
    let err = parse_contour_csv("nan,0\n1,0\n1,1\n").unwrap_err();
    assert!(
        matches!(err, GeometryError::BadLine { line: 1, .. }),
        "a NaN first line is data, not a header"
    );
}

#[test]
fn too_few_degenerate_and_crossing_outlines() {
    let err = parse_contour_csv("x,y\n0,0\n1,1\n0,0\n").unwrap_err();
    assert!(
        matches!(err, GeometryError::TooFewPoints { points: 2, min: 3 }),
        "{err}"
    );
    let err = parse_contour_csv("").unwrap_err();
    assert!(matches!(err, GeometryError::TooFewPoints { points: 0, .. }));
    let err = parse_contour_csv("0,0\n1,0\n2,0\n0,0\n").unwrap_err();
    assert!(matches!(err, GeometryError::Degenerate), "{err}");
    let err = parse_contour_csv("0,0\n2,2\n2,0\n0,2\n0,0\n").unwrap_err();
    assert!(
        matches!(err, GeometryError::SelfIntersecting { .. }),
        "{err}"
    );
}
