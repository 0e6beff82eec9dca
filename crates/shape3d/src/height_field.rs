//! Smooth surfaces z = f(x, y) with the solid below them: the tilted ramp,
//! the saddle, the wave and the quadric patch (any two principal
//! curvatures at the origin). The closest point is found by Newton's method
//! on the squared distance to the graph, so the signed distance is exact.
use crate::{Object3d, Shape3dError, Vec3};

/// A height-field surface z = f(x, y) (mm), solid below: built by
/// [`HeightField::ramp`], [`HeightField::saddle`], [`HeightField::wave`]
/// or [`HeightField::quadric`].
#[derive(Debug, Clone, PartialEq)]
pub struct HeightField {
    kind: Kind,
}

/// The surfaces, in the units their formulas use.
#[derive(Debug, Clone, PartialEq)]
enum Kind {
    /// The plane z = height + tan(slope) (x cos(azimuth) + y sin(azimuth)):
    /// rising by `slope` towards `azimuth` (a flat floor at slope 0).
    Ramp {
        height: f64,
        tan: f64,
        dir: [f64; 2],
    },
    /// The saddle z = (x^2 - y^2) / (2 R): curvature 1/R along x, -1/R
    /// along y at the origin.
    Saddle { radius: f64 },
    /// The wave z = A sin(2 pi s / L), s = x cos(azimuth) + y sin(azimuth).
    Wave {
        amplitude: f64,
        wavenumber: f64,
        dir: [f64; 2],
    },
    /// The quadric z = (k1 u^2 + k2 v^2) / 2 with u = x cos(a) + y sin(a),
    /// v = -x sin(a) + y cos(a): level at the origin, `k` its second
    /// derivatives there along `dir` = (cos a, sin a) and across
    /// (negative where the patch is convex).
    Quadric { k: [f64; 2], dir: [f64; 2] },
}

/// The largest |curvature| of a quadric patch, 1/mm (a 20 mm radius).
pub const MAX_QUADRIC_CURVATURE: f64 = 1.0 / 20.0;

fn unit(azimuth_deg: f64) -> [f64; 2] {
    let (s, c) = azimuth_deg.to_radians().sin_cos();
    [c, s]
}

fn check(
    field: &'static str,
    value: f64,
    ok: bool,
    reason: &'static str,
) -> Result<(), Shape3dError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(Shape3dError::Config {
            field,
            value,
            reason,
        })
    }
}

impl HeightField {
    /// A plane through (0, 0, `height_mm`) rising by `slope_deg` (|slope|
    /// < 60 deg) towards `azimuth_deg`.
    pub fn ramp(height_mm: f64, slope_deg: f64, azimuth_deg: f64) -> Result<Self, Shape3dError> {
        check("height_mm", height_mm, true, "must be finite")?;
        check(
            "slope_deg",
            slope_deg,
            slope_deg.abs() < 60.0,
            "a ramp's slope must be within +-60 deg",
        )?;
        check("azimuth_deg", azimuth_deg, true, "must be finite")?;
        Ok(Self {
            kind: Kind::Ramp {
                height: height_mm,
                tan: slope_deg.to_radians().tan(),
                dir: unit(azimuth_deg),
            },
        })
    }

    /// The saddle of curvature radius `radius_mm` (>= 20 mm).
    pub fn saddle(radius_mm: f64) -> Result<Self, Shape3dError> {
        check(
            "radius_mm",
            radius_mm,
            radius_mm >= 20.0,
            "a saddle's radius must be at least 20 mm",
        )?;
        Ok(Self {
            kind: Kind::Saddle { radius: radius_mm },
        })
    }

    /// The wave of amplitude `amplitude_mm` and wavelength `wavelength_mm`
    /// along `azimuth_deg`; its steepest slope 2 pi A / L must stay below 1.
    pub fn wave(
        amplitude_mm: f64,
        wavelength_mm: f64,
        azimuth_deg: f64,
    ) -> Result<Self, Shape3dError> {
        check(
            "amplitude_mm",
            amplitude_mm,
            amplitude_mm >= 0.0,
            "must not be negative",
        )?;
        check(
            "wavelength_mm",
            wavelength_mm,
            wavelength_mm > 0.0,
            "must be positive",
        )?;
        let k = std::f64::consts::TAU / wavelength_mm;
        check(
            "amplitude_mm",
            amplitude_mm,
            amplitude_mm * k < 1.0,
            "the wave's steepest slope 2 pi A / L must be below 1",
        )?;
        check("azimuth_deg", azimuth_deg, true, "must be finite")?;
        Ok(Self {
            kind: Kind::Wave {
                amplitude: amplitude_mm,
                wavenumber: k,
                dir: unit(azimuth_deg),
            },
        })
    }

    /// The quadric patch z = (k1 u^2 + k2 v^2) / 2, u along `azimuth_deg`
    /// and v across it: level at the origin with the principal curvatures
    /// `curvatures_per_mm` = [k1, k2] there (1/mm; positive: convex, the
    /// surface falling away from its tangent plane like a dome's; each
    /// |k| at most 1/20 mm, the saddle's bound). A sphere's or a
    /// cylinder's top to second order, a saddle for k1 = -k2.
    pub fn quadric(curvatures_per_mm: [f64; 2], azimuth_deg: f64) -> Result<Self, Shape3dError> {
        for k in curvatures_per_mm {
            check(
                "curvatures_per_mm",
                k,
                k.abs() <= MAX_QUADRIC_CURVATURE,
                "a quadric's curvatures must be within +-1/20 per mm",
            )?;
        }
        check("azimuth_deg", azimuth_deg, true, "must be finite")?;
        let [k1, k2] = curvatures_per_mm;
        Ok(Self {
            // z = -(k u^2) / 2 falls away for a convex k > 0.
            kind: Kind::Quadric {
                k: [-k1, -k2],
                dir: unit(azimuth_deg),
            },
        })
    }

    /// f(x, y), mm.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        self.derivatives(x, y).0
    }

    /// The largest curvature of the surface, 1/mm (0 for the ramp, 1/R
    /// for the saddle, A (2 pi / L)^2 for the wave, the larger |k| of a
    /// quadric).
    pub fn max_curvature(&self) -> f64 {
        match self.kind {
            Kind::Ramp { .. } => 0.0,
            Kind::Saddle { radius } => 1.0 / radius,
            Kind::Wave {
                amplitude,
                wavenumber,
                ..
            } => amplitude * wavenumber * wavenumber,
            Kind::Quadric { k, .. } => k[0].abs().max(k[1].abs()),
        }
    }

    /// f, its gradient [f_x, f_y] and Hessian [f_xx, f_xy, f_yy] (mm,
    /// unitless, 1/mm).
    pub fn derivatives(&self, x: f64, y: f64) -> (f64, [f64; 2], [f64; 3]) {
        match self.kind {
            Kind::Ramp { height, tan, dir } => (
                height + tan * (x * dir[0] + y * dir[1]),
                [tan * dir[0], tan * dir[1]],
                [0.0; 3],
            ),
            Kind::Saddle { radius } => (
                (x * x - y * y) / (2.0 * radius),
                [x / radius, -y / radius],
                [1.0 / radius, 0.0, -1.0 / radius],
            ),
            Kind::Wave {
                amplitude,
                wavenumber: k,
                dir,
            } => {
                let (s, c) = (k * (x * dir[0] + y * dir[1])).sin_cos();
                let g = amplitude * k * c;
                let h = -amplitude * k * k * s;
                (
                    amplitude * s,
                    [g * dir[0], g * dir[1]],
                    [
                        h * dir[0] * dir[0],
                        h * dir[0] * dir[1],
                        h * dir[1] * dir[1],
                    ],
                )
            }
            Kind::Quadric { k, dir: [c, s] } => {
                let u = x * c + y * s;
                let v = -x * s + y * c;
                (
                    0.5 * (k[0] * u * u + k[1] * v * v),
                    [k[0] * u * c - k[1] * v * s, k[0] * u * s + k[1] * v * c],
                    [
                        k[0] * c * c + k[1] * s * s,
                        (k[0] - k[1]) * c * s,
                        k[0] * s * s + k[1] * c * c,
                    ],
                )
            }
        }
    }

    /// Unit upward normal of the graph at (x, y): (-f_x, -f_y, 1) / norm.
    pub fn surface_normal(&self, x: f64, y: f64) -> Vec3 {
        let (_, g, _) = self.derivatives(x, y);
        Vec3::new(-g[0], -g[1], 1.0).normalize()
    }

    /// The graph point (u, v, f(u, v)) nearest `p`: Newton's method on
    /// E = |(u, v, f) - p|^2 / 2 from (x, y), damped towards a gradient
    /// step where the Hessian is not positive definite.
    fn foot(&self, p: Vec3) -> Vec3 {
        let (mut u, mut v) = (p.x, p.y);
        for _ in 0..50 {
            let (f, g, h) = self.derivatives(u, v);
            let r = f - p.z;
            let grad = [u - p.x + r * g[0], v - p.y + r * g[1]];
            let mut a = 1.0 + g[0] * g[0] + r * h[0];
            let b = g[0] * g[1] + r * h[1];
            let mut c = 1.0 + g[1] * g[1] + r * h[2];
            let mut det = a * c - b * b;
            while a <= 0.0 || det <= 1e-12 {
                a += 1.0;
                c += 1.0;
                det = a * c - b * b;
            }
            let du = (c * grad[0] - b * grad[1]) / det;
            let dv = (a * grad[1] - b * grad[0]) / det;
            u -= du;
            v -= dv;
            if du.abs().max(dv.abs()) < 1e-13 {
                break;
            }
        }
        Vec3::new(u, v, self.height(u, v))
    }
}

impl Object3d for HeightField {
    /// Exact: the distance to the nearest graph point, negative below the
    /// graph.
    fn signed_distance(&self, p: Vec3) -> f64 {
        let d = (p - self.foot(p)).norm();
        if p.z < self.height(p.x, p.y) {
            -d
        } else {
            d
        }
    }

    fn closest_point(&self, p: Vec3) -> Vec3 {
        self.foot(p)
    }

    fn normal(&self, p: Vec3) -> Vec3 {
        let q = self.foot(p);
        self.surface_normal(q.x, q.y)
    }

    /// Exact to 1e-12 mm: Newton's method on foot + t axis meeting the
    /// graph, from the vertical estimate, kept within [-max, max].
    fn column_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        if axis.z <= 0.0 {
            return f64::NEG_INFINITY;
        }
        let gap = |t: f64| {
            let q = foot + axis * t;
            let (f, g, _) = self.derivatives(q.x, q.y);
            (f - q.z, g[0] * axis.x + g[1] * axis.y - axis.z)
        };
        let mut t = (self.height(foot.x, foot.y) - foot.z) / axis.z;
        for _ in 0..40 {
            let (r, slope) = gap(t);
            if r.abs() < 1e-12 || slope >= 0.0 {
                break;
            }
            let step = r / slope;
            t = (t - step).clamp(-2.0 * max_mm.abs() - 1.0, 2.0 * max_mm.abs() + 1.0);
            if step.abs() < 1e-12 {
                break;
            }
        }
        t.min(max_mm)
    }
}
