//! Round solids with closed-form geometry: a dome (a ball whose top is
//! at the origin) and a cylinder lying on its side (its top line through
//! the origin). Curved surfaces of one and two signs of curvature the
//! other objects lack: convex in every direction (the dome) and in one
//! (the cylinder).
use crate::{Object3d, Shape3dError, Vec3};

/// Check a radius: positive and finite.
fn check_radius(
    field: &'static str,
    radius_mm: f64,
    what: &'static str,
) -> Result<(), Shape3dError> {
    if radius_mm > 0.0 && radius_mm.is_finite() {
        Ok(())
    } else {
        Err(Shape3dError::Config {
            field,
            value: radius_mm,
            reason: what,
        })
    }
}

/// The upper of the two parameters t where |f + t a|^2 = r^2 (a, f the
/// column's direction and foot relative to the centre, both projected
/// where the solid is invariant), kept at most `max_mm`;
/// `f64::NEG_INFINITY` when the column misses or meets it below -`max_mm`.
fn upper_root(f: Vec3, a: Vec3, r: f64, max_mm: f64) -> f64 {
    let aa = a.norm_squared();
    let b = a.dot(&f);
    let c = f.norm_squared() - r * r;
    if aa <= 1e-300 {
        return if c <= 0.0 { max_mm } else { f64::NEG_INFINITY };
    }
    let disc = b * b - aa * c;
    if disc < 0.0 {
        return f64::NEG_INFINITY;
    }
    let t = (-b + disc.sqrt()) / aa;
    if t < -max_mm {
        f64::NEG_INFINITY
    } else {
        t.min(max_mm)
    }
}

/// The ball of radius `radius` centred at (0, 0, -radius): its top at the
/// origin, outward normal (p - c) / |p - c|, curvature 1 / radius in
/// every direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Dome {
    radius: f64,
}

impl Dome {
    /// A dome of radius `radius_mm` (> 0).
    pub fn new(radius_mm: f64) -> Result<Self, Shape3dError> {
        check_radius("radius_mm", radius_mm, "a dome's radius must be positive")?;
        Ok(Self { radius: radius_mm })
    }

    fn centre(&self) -> Vec3 {
        Vec3::new(0.0, 0.0, -self.radius)
    }
}

impl Object3d for Dome {
    /// Exact: |p - c| - r.
    fn signed_distance(&self, p: Vec3) -> f64 {
        (p - self.centre()).norm() - self.radius
    }

    /// Exact: c + r (p - c) / |p - c| (the top for the centre itself).
    fn closest_point(&self, p: Vec3) -> Vec3 {
        self.centre() + self.normal(p) * self.radius
    }

    fn normal(&self, p: Vec3) -> Vec3 {
        let d = p - self.centre();
        if d.norm() > 1e-12 {
            d.normalize()
        } else {
            Vec3::z()
        }
    }

    /// Exact: where the column leaves the ball going up (the upper root
    /// of the line-sphere intersection).
    fn column_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        upper_root(foot - self.centre(), axis, self.radius, max_mm)
    }
}

/// The solid cylinder of radius `radius` whose axis is the horizontal
/// line through (0, 0, -radius) along `azimuth` (deg from +x): its top
/// line runs through the origin; curvature 1 / radius across the axis, 0
/// along it. Infinite along its axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Cylinder {
    radius: f64,
    axis: Vec3,
}

impl Cylinder {
    /// A cylinder of radius `radius_mm` (> 0) lying along `azimuth_deg`.
    pub fn new(radius_mm: f64, azimuth_deg: f64) -> Result<Self, Shape3dError> {
        check_radius(
            "radius_mm",
            radius_mm,
            "a cylinder's radius must be positive",
        )?;
        if !azimuth_deg.is_finite() {
            return Err(Shape3dError::Config {
                field: "azimuth_deg",
                value: azimuth_deg,
                reason: "must be finite",
            });
        }
        let (s, c) = azimuth_deg.to_radians().sin_cos();
        Ok(Self {
            radius: radius_mm,
            axis: Vec3::new(c, s, 0.0),
        })
    }

    /// The part of `v` across the axis.
    fn across(&self, v: Vec3) -> Vec3 {
        v - self.axis * self.axis.dot(&v)
    }

    fn centre(&self) -> Vec3 {
        Vec3::new(0.0, 0.0, -self.radius)
    }
}

impl Object3d for Cylinder {
    /// Exact: the distance from the axis less the radius.
    fn signed_distance(&self, p: Vec3) -> f64 {
        self.across(p - self.centre()).norm() - self.radius
    }

    /// Exact: `p` moved across the axis onto the cylinder.
    fn closest_point(&self, p: Vec3) -> Vec3 {
        let d = p - self.centre();
        self.centre() + self.axis * self.axis.dot(&d) + self.normal(p) * self.radius
    }

    fn normal(&self, p: Vec3) -> Vec3 {
        let d = self.across(p - self.centre());
        if d.norm() > 1e-12 {
            d.normalize()
        } else {
            Vec3::z()
        }
    }

    /// Exact: the upper root of the column meeting the cylinder, both
    /// seen across the axis.
    fn column_top(&self, foot: Vec3, axis: Vec3, max_mm: f64) -> f64 {
        upper_root(
            self.across(foot - self.centre()),
            self.across(axis),
            self.radius,
            max_mm,
        )
    }
}
