//! Closed planar contours: the edge a tactile sensor follows.
//!
//! A [`Contour`] is a validated simple polygon with everything the
//! simulation asks of it precomputed: edge vectors, outward normals,
//! cumulative arc length and a segment tree, so that the hot query
//! ([`Contour::nearest`], ~10^5 calls per run) is exact and O(log n).
use crate::segtree::{Hit, SegTree, Segment};
use crate::validate::{check_polygon, dedup_closed};
use crate::{GeometryError, Vec2};

/// The nearest point of a contour's edge to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgePoint {
    /// Closest point on the edge, mm.
    pub point: Vec2,
    /// Unit outward normal of the edge at `point`.
    pub normal: Vec2,
    /// Signed distance of the query point to the edge, mm: negative inside.
    pub signed_distance: f64,
    /// Arc length from the contour's first vertex to `point`, mm.
    pub arc_length: f64,
}

/// Distances below this (mm) count as "on the edge" when choosing a normal.
const ON_EDGE_MM: f64 = 1e-9;

/// A simple closed polygon, counter-clockwise, in millimetres.
///
/// Invariant: at least 3 distinct vertices, counter-clockwise orientation,
/// no self-intersection, the last vertex is not a copy of the first.
#[derive(Clone, PartialEq)]
pub struct Contour {
    pub(crate) vertices: Vec<Vec2>,
    /// Edge `i` runs from vertex `i` to vertex `i + 1` (wrapping).
    segments: Vec<Segment>,
    /// Arc length at the start of each edge; `cum[0] == 0`.
    cum: Vec<f64>,
    perimeter: f64,
    area: f64,
    /// Outward pseudo-normal at each vertex: the normalised sum of the two
    /// adjacent edge normals (decides inside/outside when a vertex is nearest).
    vertex_normals: Vec<Vec2>,
    tree: SegTree,
}

impl std::fmt::Debug for Contour {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (min, max) = self.bounds();
        f.debug_struct("Contour")
            .field("vertices", &self.vertices.len())
            .field("perimeter_mm", &self.perimeter)
            .field("area_mm2", &self.area)
            .field("bounds", &((min.x, min.y), (max.x, max.y)))
            .finish()
    }
}

/// Largest vertex coordinate [`Contour::new`] accepts, mm (1 km): keeps the
/// perimeter and every arc length finite (a vertex at 1e308 made them
/// infinite and a follow run sized a buffer by them).
pub const MAX_COORDINATE_MM: f64 = 1e6;

impl Contour {
    /// Build from vertices (either orientation; a repeated closing point is
    /// dropped). Errors on fewer than 3 points, zero area, self-intersection, or a
    /// coordinate beyond [`MAX_COORDINATE_MM`].
    ///
    /// Consecutive duplicate vertices are merged. A clockwise list is
    /// reversed, keeping its first vertex first.
    pub fn new(vertices: Vec<Vec2>) -> Result<Self, GeometryError> {
        if let Some(index) = vertices
            .iter()
            .position(|v| !(v.x.is_finite() && v.y.is_finite()))
        {
            return Err(GeometryError::NonFinite { index });
        }
        if let Some(index) = vertices.iter().position(|v| v.amax() > MAX_COORDINATE_MM) {
            return Err(GeometryError::OutOfRange {
                index,
                limit_mm: MAX_COORDINATE_MM,
            });
        }
        let vertices = dedup_closed(vertices);
        let area2 = check_polygon(&vertices)?;
        Ok(Self::build(orient_ccw(vertices, area2)))
    }

    /// Build from vertices already known to form a simple polygon (built-in
    /// shapes, checked by the tests); only the orientation is fixed.
    pub(crate) fn from_trusted(vertices: Vec<Vec2>) -> Self {
        let vertices = dedup_closed(vertices);
        let area2 = crate::validate::twice_signed_area(&vertices);
        Self::build(orient_ccw(vertices, area2))
    }

    fn build(vertices: Vec<Vec2>) -> Self {
        let n = vertices.len();
        let segments: Vec<Segment> = (0..n)
            .map(|i| Segment::new(vertices[i], vertices[(i + 1) % n]))
            .collect();
        let mut cum = Vec::with_capacity(n);
        let mut total = 0.0;
        for seg in &segments {
            cum.push(total);
            total += seg.len;
        }
        let vertex_normals = (0..n)
            .map(|i| {
                let sum = segments[(i + n - 1) % n].normal + segments[i].normal;
                let norm = sum.norm();
                if norm > 1e-12 {
                    sum / norm
                } else {
                    segments[i].normal
                }
            })
            .collect();
        let area = 0.5 * crate::validate::twice_signed_area(&vertices).abs();
        let tree = SegTree::build(&segments);
        Self {
            vertices,
            segments,
            cum,
            perimeter: total,
            area,
            vertex_normals,
            tree,
        }
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Vec2] {
        &self.vertices
    }
    /// Total edge length, mm.
    pub fn perimeter(&self) -> f64 {
        self.perimeter
    }
    /// Enclosed area, mm^2 (positive).
    pub fn area(&self) -> f64 {
        self.area
    }
    /// True when `p` lies strictly inside.
    pub fn contains(&self, p: Vec2) -> bool {
        self.signed_distance(p) < 0.0
    }
    /// Signed distance from `p` to the edge, mm: negative inside.
    pub fn signed_distance(&self, p: Vec2) -> f64 {
        self.nearest(p).signed_distance
    }
    /// Nearest edge point, its outward normal and the signed distance.
    ///
    /// The normal is the direction from the edge point towards `p` (away
    /// from `p` when inside) when `p` is off the edge, else the edge normal
    /// (the vertex pseudo-normal at a vertex). A non-finite `p` gives a
    /// NaN distance.
    pub fn nearest(&self, p: Vec2) -> EdgePoint {
        match self.tree.nearest(&self.segments, p) {
            Some(hit) => self.edge_point(p, hit),
            None => EdgePoint {
                point: p,
                normal: Vec2::zeros(),
                signed_distance: f64::NAN,
                arc_length: f64::NAN,
            },
        }
    }

    fn edge_point(&self, p: Vec2, hit: Hit) -> EdgePoint {
        let seg = &self.segments[hit.segment];
        let n = self.segments.len();
        let feature_normal = if hit.t <= 0.0 {
            self.vertex_normals[hit.segment]
        } else if hit.t >= 1.0 {
            self.vertex_normals[(hit.segment + 1) % n]
        } else {
            seg.normal
        };
        let offset = p - hit.point;
        let outside = offset.dot(&feature_normal) >= 0.0;
        let distance = hit.dist2.sqrt();
        let signed_distance = if outside { distance } else { -distance };
        let normal = if distance > ON_EDGE_MM {
            offset / signed_distance
        } else {
            feature_normal
        };
        let mut arc_length = self.cum[hit.segment] + hit.t * seg.len;
        if arc_length >= self.perimeter {
            arc_length -= self.perimeter;
        }
        EdgePoint {
            point: hit.point,
            normal,
            signed_distance,
            arc_length,
        }
    }

    /// The point at arc length `s` (mm, wrapped modulo the perimeter) and
    /// the unit outward normal there (of the edge containing the point).
    pub fn at_arc_length(&self, s: f64) -> (Vec2, Vec2) {
        let s = if s.is_finite() {
            s.rem_euclid(self.perimeter)
        } else {
            0.0
        };
        // Last edge whose start is at or before s.
        let i = self.cum.partition_point(|&c| c <= s).saturating_sub(1);
        let seg = &self.segments[i];
        let t = if seg.len > 0.0 {
            ((s - self.cum[i]) / seg.len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (seg.point_at(t), seg.normal)
    }
    /// `n` points evenly spaced by arc length, starting at the first vertex.
    pub fn resample(&self, n: usize) -> Vec<Vec2> {
        let step = self.perimeter / n.max(1) as f64;
        (0..n)
            .map(|k| self.at_arc_length(k as f64 * step).0)
            .collect()
    }
    /// Axis-aligned bounding box: (min, max), mm.
    pub fn bounds(&self) -> (Vec2, Vec2) {
        let mut min = Vec2::repeat(f64::INFINITY);
        let mut max = Vec2::repeat(f64::NEG_INFINITY);
        for v in &self.vertices {
            min = min.inf(v);
            max = max.sup(v);
        }
        (min, max)
    }
    /// Arc length (mm) at the start of each vertex, for plotting and metrics.
    pub fn vertex_arc_lengths(&self) -> &[f64] {
        &self.cum
    }
}

/// Reverse a clockwise list (given twice its signed area), keeping vertex 0 first.
fn orient_ccw(mut vertices: Vec<Vec2>, area2: f64) -> Vec<Vec2> {
    if area2 < 0.0 {
        vertices[1..].reverse();
    }
    vertices
}
