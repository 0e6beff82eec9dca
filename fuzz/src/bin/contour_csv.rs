//! afl target: arbitrary text as a contour CSV; a parsed contour is then
//! walked (perimeter, a point by arc length).
fn main() {
    afl::fuzz!(|data: &[u8]| {
        let Ok(text) = std::str::from_utf8(data) else {
            return;
        };
        if let Ok(c) = tactrace_geometry::parse_contour_csv(text) {
            let p = c.perimeter();
            assert!(p.is_finite() && p > 0.0, "perimeter {p}");
            let _ = c.at_arc_length(0.37 * p);
        }
    });
}
