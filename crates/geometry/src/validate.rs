//! Checks that make a vertex list a valid simple polygon: enough distinct
//! points, non-zero area, no two edges touching except neighbours at their
//! shared vertex.
//!
//! The crossing test uses exact orientation signs (touching counts as
//! crossing) and the segment tree to visit only nearby edge pairs, so it
//! stays fast on outlines with many thousands of vertices.
use crate::segtree::{SegTree, Segment};
use crate::{GeometryError, Vec2};

/// Twice the signed area (shoelace): positive for counter-clockwise.
pub(crate) fn twice_signed_area(vertices: &[Vec2]) -> f64 {
    let n = vertices.len();
    (0..n)
        .map(|i| {
            let (a, b) = (vertices[i], vertices[(i + 1) % n]);
            a.x * b.y - b.x * a.y
        })
        .sum()
}

/// Remove consecutive duplicates (and a closing copy of the first point).
pub(crate) fn dedup_closed(mut vertices: Vec<Vec2>) -> Vec<Vec2> {
    vertices.dedup();
    while vertices.len() > 1 && vertices.first() == vertices.last() {
        vertices.pop();
    }
    vertices
}

/// Area below which a polygon counts as degenerate, relative to its extent.
fn area_tolerance(vertices: &[Vec2]) -> f64 {
    let mut min = Vec2::repeat(f64::INFINITY);
    let mut max = Vec2::repeat(f64::NEG_INFINITY);
    for v in vertices {
        min = min.inf(v);
        max = max.sup(v);
    }
    1e-12 * (max - min).norm_squared()
}

/// Check a deduplicated vertex list; returns twice its signed area.
pub(crate) fn check_polygon(vertices: &[Vec2]) -> Result<f64, GeometryError> {
    if let Some(index) = vertices
        .iter()
        .position(|v| !(v.x.is_finite() && v.y.is_finite()))
    {
        return Err(GeometryError::NonFinite { index });
    }
    if vertices.len() < 3 {
        return Err(GeometryError::TooFewPoints {
            points: vertices.len(),
            min: 3,
        });
    }
    let area2 = twice_signed_area(vertices);
    if area2.abs() <= 2.0 * area_tolerance(vertices) {
        // A zero-area outline that is not a line folds over itself
        // (a symmetric bow tie): report the crossing, it says more.
        if !all_collinear(vertices) {
            check_simple(vertices)?;
        }
        return Err(GeometryError::Degenerate);
    }
    check_simple(vertices)?;
    Ok(area2)
}

/// All vertices on one line (within rounding of the outline's extent).
fn all_collinear(vertices: &[Vec2]) -> bool {
    let a = vertices[0];
    let Some(b) = vertices
        .iter()
        .copied()
        .max_by(|p, q| (p - a).norm_squared().total_cmp(&(q - a).norm_squared()))
    else {
        return true;
    };
    let span = (b - a).norm();
    vertices
        .iter()
        .all(|&p| orient(a, b, p).abs() <= 1e-9 * span * span)
}

/// Error on the first pair of edges that touch (other than neighbours at
/// their shared vertex).
fn check_simple(vertices: &[Vec2]) -> Result<(), GeometryError> {
    let n = vertices.len();
    let segments: Vec<Segment> = (0..n)
        .map(|i| Segment::new(vertices[i], vertices[(i + 1) % n]))
        .collect();
    let tree = SegTree::build(&segments);
    let mut candidates = Vec::new();
    for (i, seg) in segments.iter().enumerate() {
        let (min, max) = (seg.a.inf(&seg.end()), seg.a.sup(&seg.end()));
        tree.overlapping(min, max, &mut candidates);
        for &j in candidates.iter().filter(|&&j| j > i) {
            if edges_conflict(&segments, i, j) {
                return Err(GeometryError::SelfIntersecting { a: i, b: j });
            }
        }
    }
    Ok(())
}

/// Whether edges `i < j` conflict: neighbours fold back onto each other,
/// others touch at all.
fn edges_conflict(segments: &[Segment], i: usize, j: usize) -> bool {
    let n = segments.len();
    let (s, t) = (&segments[i], &segments[j]);
    if j == i + 1 {
        return folds_back(s, t);
    }
    if i == 0 && j == n - 1 {
        return folds_back(t, s);
    }
    segments_touch(s.a, s.end(), t.a, t.end())
}

/// Consecutive edges `s` then `t` (sharing `s.end() == t.a`) that run back
/// along each other overlap in more than the shared vertex.
fn folds_back(s: &Segment, t: &Segment) -> bool {
    let cross = s.d.x * t.d.y - s.d.y * t.d.x;
    cross == 0.0 && s.d.dot(&t.d) < 0.0
}

/// Orientation of `c` relative to the line `a -> b`: >0 left, <0 right.
fn orient(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// `p`, known collinear with `a -> b`, lies within the segment's box.
fn within(a: Vec2, b: Vec2, p: Vec2) -> bool {
    p.x >= a.x.min(b.x) && p.x <= a.x.max(b.x) && p.y >= a.y.min(b.y) && p.y <= a.y.max(b.y)
}

/// Closed segments `ab` and `cd` share at least one point.
pub(crate) fn segments_touch(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    let straddle = |u: f64, v: f64| (u > 0.0 && v < 0.0) || (u < 0.0 && v > 0.0);
    if straddle(d1, d2) && straddle(d3, d4) {
        return true;
    }
    (d1 == 0.0 && within(c, d, a))
        || (d2 == 0.0 && within(c, d, b))
        || (d3 == 0.0 && within(a, b, c))
        || (d4 == 0.0 && within(a, b, d))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> Vec2 {
        Vec2::new(x, y)
    }

    #[test]
    fn crossing_and_touching_segments() {
        assert!(segments_touch(
            v(0.0, 0.0),
            v(2.0, 2.0),
            v(0.0, 2.0),
            v(2.0, 0.0)
        ));
        assert!(
            segments_touch(v(0.0, 0.0), v(2.0, 0.0), v(1.0, 0.0), v(1.0, 3.0)),
            "T junction"
        );
        assert!(
            segments_touch(v(0.0, 0.0), v(2.0, 0.0), v(1.0, 0.0), v(3.0, 0.0)),
            "collinear overlap"
        );
        assert!(
            !segments_touch(v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0), v(3.0, 0.0)),
            "collinear apart"
        );
        assert!(
            !segments_touch(v(0.0, 0.0), v(1.0, 1.0), v(0.0, 1.0), v(0.4, 0.6)),
            "near miss"
        );
    }

    #[test]
    fn bow_tie_is_rejected() {
        let bow = [v(0.0, 0.0), v(1.0, 1.0), v(1.0, 0.0), v(0.0, 1.0)];
        assert!(matches!(
            check_polygon(&bow),
            Err(GeometryError::SelfIntersecting { .. })
        ));
    }

    #[test]
    fn spike_is_rejected() {
        // A square with an edge that runs out and straight back.
        let spike = [
            v(0.0, 0.0),
            v(2.0, 0.0),
            v(3.0, 0.0),
            v(2.0, 0.0),
            v(2.0, 2.0),
            v(0.0, 2.0),
        ];
        assert!(check_polygon(&spike).is_err());
    }
}
