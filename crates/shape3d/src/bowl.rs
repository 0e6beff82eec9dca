//! A bowl: a spherical cavity cut into the flat top (z = 0) of a block,
//! followed on its inside surface and along its rim.
use crate::{EdgeCurve, EdgeSample, Object3d, Shape3dError, Vec3};

/// Rim samples of [`Bowl::edge`].
const RIM_SAMPLES: usize = 720;

/// The block z <= 0 minus the ball of radius `sphere` centred at
/// (0, 0, c), c = sqrt(sphere^2 - rim^2) > 0: a cavity of depth
/// sphere - c whose rim is the circle of radius `rim` in the plane z = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Bowl {
    sphere: f64,
    rim: f64,
    centre: Vec3,
}

impl Bowl {
    /// A bowl of inside radius `sphere_radius_mm` whose rim has radius
    /// `rim_radius_mm` (0 < rim < sphere).
    pub fn new(sphere_radius_mm: f64, rim_radius_mm: f64) -> Result<Self, Shape3dError> {
        if !(rim_radius_mm > 0.0 && rim_radius_mm.is_finite()) {
            return Err(Shape3dError::Config {
                field: "rim_radius_mm",
                value: rim_radius_mm,
                reason: "a bowl's rim radius must be positive",
            });
        }
        if !(sphere_radius_mm > rim_radius_mm && sphere_radius_mm.is_finite()) {
            return Err(Shape3dError::Config {
                field: "sphere_radius_mm",
                value: sphere_radius_mm,
                reason: "a bowl's sphere must be wider than its rim",
            });
        }
        let c = (sphere_radius_mm.powi(2) - rim_radius_mm.powi(2)).sqrt();
        Ok(Self {
            sphere: sphere_radius_mm,
            rim: rim_radius_mm,
            centre: Vec3::new(0.0, 0.0, c),
        })
    }

    /// Depth of the cavity below the rim's plane, mm.
    pub fn depth(&self) -> f64 {
        self.sphere - self.centre.z
    }

    /// True when the sphere, rather than the top face, is the nearer part
    /// of the surface to `p`.
    fn on_sphere(&self, p: Vec3) -> bool {
        self.sphere - (p - self.centre).norm() >= p.z
    }
}

impl Object3d for Bowl {
    /// max(z, R - |p - C|): exact below the rim's plane and over the flat
    /// top away from the cavity, a distance bound elsewhere.
    fn signed_distance(&self, p: Vec3) -> f64 {
        p.z.max(self.sphere - (p - self.centre).norm())
    }

    fn normal(&self, p: Vec3) -> Vec3 {
        let q = self.closest_point(p);
        if self.on_sphere(q) && q.z < -1e-9 {
            (self.centre - q) / self.sphere
        } else {
            Vec3::z()
        }
    }

    /// The rim circle, counter-clockwise seen from above: normals [top
    /// face (0, 0, 1), the sphere's (into the cavity)].
    fn edge(&self) -> Option<EdgeCurve> {
        let samples = (0..RIM_SAMPLES)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / RIM_SAMPLES as f64;
                let (s, c) = a.sin_cos();
                let point = Vec3::new(self.rim * c, self.rim * s, 0.0);
                EdgeSample {
                    point,
                    tangent: Vec3::new(-s, c, 0.0),
                    normals: [Vec3::z(), (self.centre - point) / self.sphere],
                }
            })
            .collect();
        Some(EdgeCurve {
            samples,
            closed: true,
        })
    }

    /// Exact: the top face's plane, or where the column leaves the ball
    /// going down when it crosses the plane inside the rim.
    fn column_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        if axis.z <= 0.0 {
            return f64::NEG_INFINITY;
        }
        let t_plane = -foot.z / axis.z;
        let on_plane = foot + axis * t_plane;
        if (on_plane - self.centre).norm() >= self.sphere {
            return t_plane.min(max_mm);
        }
        let f = foot - self.centre;
        let b = axis.dot(&f);
        let disc = b * b - (f.norm_squared() - self.sphere * self.sphere);
        (-b - disc.max(0.0).sqrt()).min(max_mm)
    }
}
