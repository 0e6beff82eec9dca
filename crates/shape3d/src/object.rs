//! The one trait every 3D object implements, with the generic answers
//! (closest point by projection along the distance's gradient, the column
//! top by sphere tracing) that analytic objects replace by exact ones.
use crate::{EdgeCurve, Vec3};

/// A solid in the world frame (mm, z up), seen through its surface.
///
/// The signed distance should be exact near the surface and never much
/// above the true distance elsewhere, as the default column top traces
/// spheres of that radius (docs/3d.md says where each object's is
/// approximate).
pub trait Object3d: Send + Sync + std::fmt::Debug {
    /// Signed distance of `p` from the surface, mm: negative inside the solid.
    fn signed_distance(&self, p: Vec3) -> f64;

    /// The surface point nearest `p`, mm. Default: `p` moved against the
    /// distance's gradient by the distance, repeated until it stays put.
    fn closest_point(&self, p: Vec3) -> Vec3 {
        let mut q = p;
        for _ in 0..8 {
            let d = self.signed_distance(q);
            if d.abs() < 1e-10 {
                break;
            }
            let g = numeric_gradient(self, q);
            q -= d * g;
        }
        q
    }

    /// Unit outward normal of the surface at the point nearest `p`.
    /// Default: the distance's gradient there.
    fn normal(&self, p: Vec3) -> Vec3 {
        numeric_gradient(self, self.closest_point(p))
    }

    /// The edge curve of an edged object (an extruded shape's top rim, a
    /// bowl's rim, a foil's edge), `None` for a smooth surface.
    fn edge(&self) -> Option<EdgeCurve> {
        None
    }

    /// Height (mm) along the unit `axis` of the object's upper surface over
    /// the column through `foot`: the largest t <= `max_mm` with
    /// `foot + t axis` in the solid, `f64::NEG_INFINITY` when the column
    /// misses it above -`max_mm`. The TacTip's 3D contact reads the
    /// indentation of each skin point from it (docs/3d.md, eq. C1).
    /// Default: sphere tracing down from `max_mm`.
    fn column_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        sphere_trace(self, foot, axis, max_mm, -max_mm)
    }

    /// As [`Self::column_top`] for the object's top face extended beyond
    /// its rim (the face [`Self::footprint_distance`] bounds): where the
    /// column meets the face's surface, inside the rim or not. Default:
    /// the column top (objects without an edged face).
    fn face_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        self.column_top(foot, axis, max_mm)
    }

    /// Signed distance (mm, negative inside) of `p`'s column from the
    /// boundary of the object's edged top face, for objects whose top
    /// face ends at a sharp rim (the TacTip anti-aliases its contact with
    /// it, eq. C2); `None` for objects without one.
    fn footprint_distance(&self, _p: Vec3) -> Option<f64> {
        None
    }
}

/// The gradient of `object`'s signed distance at `p` by central
/// differences (step 1e-5 mm), normalised.
pub fn numeric_gradient<O: Object3d + ?Sized>(object: &O, p: Vec3) -> Vec3 {
    let e = 1e-5;
    let d = |v: Vec3| object.signed_distance(p + v) - object.signed_distance(p - v);
    let g = Vec3::new(d(Vec3::x() * e), d(Vec3::y() * e), d(Vec3::z() * e));
    let n = g.norm();
    if n > 0.0 && n.is_finite() {
        g / n
    } else {
        Vec3::z()
    }
}

/// The column top of [`Object3d::column_top`] by sphere tracing the signed
/// distance down the column from `start` to `floor` (mm along the axis),
/// then bisection to 1e-9 mm; `start` when it is inside already.
pub(crate) fn sphere_trace<O: Object3d + ?Sized>(
    object: &O,
    foot: Vec3,
    axis: Vec3,
    start: f64,
    floor: f64,
) -> f64 {
    let at = |t: f64| object.signed_distance(foot + axis * t);
    let mut t = start;
    let mut d = at(t);
    if d <= 0.0 {
        return start;
    }
    let mut above = t;
    while t > floor {
        above = t;
        t -= d.max(1e-3);
        d = at(t);
        if d <= 0.0 {
            break;
        }
    }
    if d > 0.0 {
        return f64::NEG_INFINITY;
    }
    let (mut hi, mut lo) = (above, t);
    for _ in 0..60 {
        let mid = 0.5 * (hi + lo);
        if at(mid) <= 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-9 {
            break;
        }
    }
    lo
}
