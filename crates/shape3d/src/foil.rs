//! A foil: a thin plate whose outline is a disk, bent into a cylinder, so
//! that its edge is a curve that leaves every plane (a turbine blade's
//! edge, in the simplest form).
use crate::{EdgeCurve, EdgeSample, Object3d, Shape3dError, Vec3};

/// Edge samples of [`Foil::edge`].
const EDGE_SAMPLES: usize = 720;

/// The plate of thickness `thickness` about the cylinder of radius `bend`
/// whose axis is the line (x, z) = (0, -bend) along y (the mid-surface
/// z = sqrt(bend^2 - x^2) - bend, highest along the y axis), cut by the
/// vertical cylinder x^2 + y^2 <= outline^2.
#[derive(Debug, Clone, PartialEq)]
pub struct Foil {
    outline: f64,
    bend: f64,
    thickness: f64,
}

impl Foil {
    /// A foil of outline radius `outline_radius_mm`, bent to
    /// `bend_radius_mm` (> outline), `thickness_mm` thick (> 0, < outline).
    pub fn new(
        outline_radius_mm: f64,
        bend_radius_mm: f64,
        thickness_mm: f64,
    ) -> Result<Self, Shape3dError> {
        let bad = |field, value, reason| Shape3dError::Config {
            field,
            value,
            reason,
        };
        if !(outline_radius_mm > 0.0 && outline_radius_mm.is_finite()) {
            return Err(bad(
                "outline_radius_mm",
                outline_radius_mm,
                "must be positive",
            ));
        }
        if !(bend_radius_mm > outline_radius_mm && bend_radius_mm.is_finite()) {
            return Err(bad(
                "bend_radius_mm",
                bend_radius_mm,
                "a foil's bend radius must exceed its outline radius",
            ));
        }
        if !(thickness_mm > 0.0 && thickness_mm < outline_radius_mm) {
            return Err(bad(
                "thickness_mm",
                thickness_mm,
                "must be positive and less than the outline radius",
            ));
        }
        Ok(Self {
            outline: outline_radius_mm,
            bend: bend_radius_mm,
            thickness: thickness_mm,
        })
    }

    /// Distance from the bend axis, and the plate's and the outline's
    /// signed distances (negative inside).
    fn parts(&self, p: Vec3) -> (f64, f64, f64) {
        let r = p.x.hypot(p.z + self.bend);
        let shell = (r - self.bend).abs() - 0.5 * self.thickness;
        (r, shell, p.x.hypot(p.y) - self.outline)
    }

    /// Height of the upper face over (x, y) (ignoring the outline), mm.
    fn upper(&self, x: f64) -> f64 {
        let top = self.bend + 0.5 * self.thickness;
        (top * top - x * x).max(0.0).sqrt() - self.bend
    }
}

impl Object3d for Foil {
    /// The box-like combination of the plate's and the outline's
    /// distances: exact on and near the faces, approximate by the angle
    /// between the faces (a few degrees) beyond the edge.
    fn signed_distance(&self, p: Vec3) -> f64 {
        let (_, shell, disk) = self.parts(p);
        shell.max(disk).min(0.0) + shell.max(0.0).hypot(disk.max(0.0))
    }

    fn normal(&self, p: Vec3) -> Vec3 {
        let q = self.closest_point(p);
        let (r, shell, disk) = self.parts(q);
        if disk >= shell {
            return Vec3::new(q.x, q.y, 0.0).normalize();
        }
        let radial = Vec3::new(q.x, 0.0, q.z + self.bend) / r;
        if r >= self.bend {
            radial
        } else {
            -radial
        }
    }

    /// The rim of the upper face, counter-clockwise seen from above:
    /// normals [upper face, outline wall].
    fn edge(&self) -> Option<EdgeCurve> {
        let top = self.bend + 0.5 * self.thickness;
        let samples = (0..EDGE_SAMPLES)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / EDGE_SAMPLES as f64;
                let (s, c) = a.sin_cos();
                let (x, y) = (self.outline * c, self.outline * s);
                let z = self.upper(x);
                let dz = x * self.outline * s / (z + self.bend);
                let face = Vec3::new(x, 0.0, z + self.bend) / top;
                EdgeSample {
                    point: Vec3::new(x, y, z),
                    tangent: Vec3::new(-self.outline * s, self.outline * c, dz).normalize(),
                    normals: [face, Vec3::new(c, s, 0.0)],
                }
            })
            .collect();
        Some(EdgeCurve {
            samples,
            closed: true,
        })
    }

    /// Where the column meets the upper face inside the outline, else
    /// where it enters the plate's edge below (sphere tracing).
    fn column_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        let face = self.face_top(foot, axis, max_mm);
        let hit = foot + axis * face;
        if face.is_finite() && hit.x.hypot(hit.y) <= self.outline {
            return face;
        }
        let start = if face.is_finite() { face } else { max_mm };
        crate::object::sphere_trace(self, foot, axis, start, -max_mm)
    }

    /// Exact: where the column meets the upper face (extended beyond the
    /// outline; [`Self::footprint_distance`] says where the foil ends).
    fn face_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        // |(fx + t ax, fz + bend + t az)| = top, the upper root.
        let top = self.bend + 0.5 * self.thickness;
        let (fx, fz) = (foot.x, foot.z + self.bend);
        let a = axis.x * axis.x + axis.z * axis.z;
        let b = axis.x * fx + axis.z * fz;
        let c = fx * fx + fz * fz - top * top;
        let disc = b * b - a * c;
        if a <= 0.0 || disc < 0.0 {
            return f64::NEG_INFINITY;
        }
        ((-b + disc.sqrt()) / a).min(max_mm)
    }

    /// The outline's signed distance at `p`'s (x, y).
    fn footprint_distance(&self, p: Vec3) -> Option<f64> {
        Some(p.x.hypot(p.y) - self.outline)
    }
}
