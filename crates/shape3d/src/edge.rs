//! The edge curve of an edged object: points along it with the curve's
//! tangent and the normals of the two faces that meet there.
use crate::Vec3;
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion};
use tactrace_geometry::Pose;

/// One sample of an edge curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeSample {
    /// Point on the edge, mm.
    pub point: Vec3,
    /// Unit tangent of the curve (the direction of travel).
    pub tangent: Vec3,
    /// Unit outward normals of the two faces meeting at the edge (for an
    /// extruded shape: its top face, then its side wall).
    pub normals: [Vec3; 2],
}

impl EdgeSample {
    /// The edge's own frame (the frame of the edge_3d / edge_5d tasks'
    /// poses): origin at the edge point, z along the pressed face's
    /// normal (`normals[0]`), x across the edge out of the object (the
    /// other face's normal made perpendicular to z), y = z x x (along the
    /// edge, the tangent's direction for an extruded rim).
    pub fn frame(&self) -> Isometry3<f64> {
        let z = self.normals[0].normalize();
        let across = self.normals[1] - z * self.normals[1].dot(&z);
        let x = if across.norm() > 1e-9 {
            across.normalize()
        } else {
            self.tangent.cross(&z).normalize()
        };
        let y = z.cross(&x);
        let rotation = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, z]));
        Isometry3::from_parts(
            Translation3::from(self.point),
            UnitQuaternion::from_rotation_matrix(&rotation),
        )
    }

    /// The world pose of a pose given in the edge's [`frame`](Self::frame)
    /// (mm, deg: x across the edge, positive off the object; z along the
    /// face normal, negative = into the object; rx, ry the tilt, rz the
    /// turn about the face normal).
    pub fn pose(&self, local: Pose) -> Pose {
        Pose::from_isometry(&(self.frame() * local.to_isometry()))
    }
}

/// A sampled edge curve, in order of travel.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeCurve {
    /// The samples, mm.
    pub samples: Vec<EdgeSample>,
    /// True when the curve closes (the last sample joins the first).
    pub closed: bool,
}

impl EdgeCurve {
    /// Length of the polyline through the samples, mm (closing segment
    /// included when closed).
    pub fn length(&self) -> f64 {
        let s = &self.samples;
        let open: f64 = s.windows(2).map(|w| (w[1].point - w[0].point).norm()).sum();
        match (self.closed, s.first(), s.last()) {
            (true, Some(a), Some(b)) => open + (a.point - b.point).norm(),
            _ => open,
        }
    }

    /// Distance from `p` to the polyline through the samples, mm.
    pub fn distance(&self, p: Vec3) -> f64 {
        let s = &self.samples;
        let mut best = s.first().map_or(f64::INFINITY, |a| (p - a.point).norm());
        let mut segment = |a: Vec3, b: Vec3| {
            let ab = b - a;
            let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-300)).clamp(0.0, 1.0);
            best = best.min((p - (a + ab * t)).norm());
        };
        for w in s.windows(2) {
            segment(w[0].point, w[1].point);
        }
        if let (true, Some(a), Some(b)) = (self.closed, s.first(), s.last()) {
            segment(b.point, a.point);
        }
        best
    }
}
