//! A planar contour extruded from z = 0 up to a height: the report's
//! shapes as solids whose top rim is the 3D edge a sensor follows.
use crate::{EdgeCurve, EdgeSample, Object3d, Shape3dError, Vec3};
use tactrace_geometry::{Contour, Vec2};

/// Spacing of the rim samples of [`Extruded::edge`], mm.
const RIM_STEP_MM: f64 = 0.5;

/// The prism { (x, y) inside `contour`, 0 <= z <= height }.
#[derive(Debug, Clone)]
pub struct Extruded {
    contour: Contour,
    height: f64,
}

impl Extruded {
    /// `contour` extruded from z = 0 to z = `height_mm` (> 0, finite).
    pub fn new(contour: Contour, height_mm: f64) -> Result<Self, Shape3dError> {
        if !(height_mm > 0.0 && height_mm.is_finite()) {
            return Err(Shape3dError::Config {
                field: "height_mm",
                value: height_mm,
                reason: "an extruded shape's height must be positive",
            });
        }
        Ok(Self {
            contour,
            height: height_mm,
        })
    }

    /// The contour (the footprint, mm).
    pub fn contour(&self) -> &Contour {
        &self.contour
    }

    /// Height of the top face, mm.
    pub fn height(&self) -> f64 {
        self.height
    }

    /// The planar signed distance (footprint) and the vertical one (slab
    /// 0 <= z <= height), both negative inside.
    fn parts(&self, p: Vec3) -> (f64, f64) {
        let d2 = self.contour.signed_distance(Vec2::new(p.x, p.y));
        (d2, (p.z - self.height).max(-p.z))
    }

    fn clamp_z(&self, z: f64) -> f64 {
        z.clamp(0.0, self.height)
    }

    /// The nearer of the top (z = height) and bottom (z = 0) faces: its
    /// height and outward normal's z.
    fn nearer_face(&self, z: f64) -> (f64, f64) {
        if z >= 0.5 * self.height {
            (self.height, 1.0)
        } else {
            (0.0, -1.0)
        }
    }
}

impl Object3d for Extruded {
    /// Exact: the box-like combination of the footprint's and the slab's
    /// distances.
    fn signed_distance(&self, p: Vec3) -> f64 {
        let (d2, dz) = self.parts(p);
        d2.max(dz).min(0.0) + d2.max(0.0).hypot(dz.max(0.0))
    }

    fn closest_point(&self, p: Vec3) -> Vec3 {
        let (d2, dz) = self.parts(p);
        let edge = self.contour.nearest(Vec2::new(p.x, p.y)).point;
        if d2 > 0.0 || (dz <= 0.0 && d2 >= dz) {
            Vec3::new(edge.x, edge.y, self.clamp_z(p.z))
        } else {
            let (z, _) = if dz > 0.0 {
                (self.clamp_z(p.z), 0.0)
            } else {
                self.nearer_face(p.z)
            };
            Vec3::new(p.x, p.y, z)
        }
    }

    fn normal(&self, p: Vec3) -> Vec3 {
        let (d2, dz) = self.parts(p);
        let near = self.contour.nearest(Vec2::new(p.x, p.y));
        let wall = Vec3::new(near.normal.x, near.normal.y, 0.0);
        if d2 > 0.0 && dz > 0.0 {
            let q = self.closest_point(p);
            return (p - q).normalize();
        }
        if d2 > 0.0 || (dz <= 0.0 && d2 >= dz) {
            return wall;
        }
        let (_, nz) = if dz > 0.0 {
            if p.z > self.height {
                (0.0, 1.0)
            } else {
                (0.0, -1.0)
            }
        } else {
            self.nearer_face(p.z)
        };
        Vec3::new(0.0, 0.0, nz)
    }

    /// The top rim, counter-clockwise seen from above, every 0.5 mm of
    /// arc: normals [top face (0, 0, 1), side wall].
    fn edge(&self) -> Option<EdgeCurve> {
        let perimeter = self.contour.perimeter();
        let n = (perimeter / RIM_STEP_MM).ceil().max(3.0) as usize;
        let step = perimeter / n as f64;
        let samples = (0..n)
            .map(|k| {
                let (point, normal) = self.contour.at_arc_length(k as f64 * step);
                EdgeSample {
                    point: Vec3::new(point.x, point.y, self.height),
                    tangent: Vec3::new(-normal.y, normal.x, 0.0),
                    normals: [Vec3::z(), Vec3::new(normal.x, normal.y, 0.0)],
                }
            })
            .collect();
        Some(EdgeCurve {
            samples,
            closed: true,
        })
    }

    /// Where the column meets the top face when it does so inside the
    /// rim, else where it enters the side wall below (sphere tracing; the
    /// bottom face is never pressed from above).
    fn column_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        let face = self.face_top(foot, axis, max_mm);
        let hit = foot + axis * face;
        if !face.is_finite() || self.contour.signed_distance(Vec2::new(hit.x, hit.y)) <= 0.0 {
            return face;
        }
        if axis.x == 0.0 && axis.y == 0.0 {
            return f64::NEG_INFINITY; // a plumb column outside stays outside
        }
        crate::object::sphere_trace(self, foot, axis, face, -max_mm)
    }

    /// Exact: where the column meets the top face's plane (the face
    /// extended beyond the rim; [`Self::footprint_distance`] says where
    /// the face ends).
    fn face_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        if axis.z <= 0.0 {
            return f64::NEG_INFINITY;
        }
        ((self.height - foot.z) / axis.z).min(max_mm)
    }

    /// The contour's signed distance at `p`'s (x, y).
    fn footprint_distance(&self, p: Vec3) -> Option<f64> {
        Some(self.contour.signed_distance(Vec2::new(p.x, p.y)))
    }
}
