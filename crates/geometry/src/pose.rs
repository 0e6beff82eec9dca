//! Rigid 6-DoF poses in millimetres and degrees.
//!
//! Convention (as the UR5/cri tool chain): position (x, y, z) in mm, then
//! extrinsic rotations about the fixed x, y and z axes in degrees
//! (roll `rx`, pitch `ry`, yaw `rz`), applied in that order.
use serde::{Deserialize, Serialize};

/// A pose of a frame relative to a base frame, mm and degrees.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pose {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub rx: f64,
    pub ry: f64,
    pub rz: f64,
}

impl std::fmt::Display for Pose {
    /// `(x, y, z) mm, (rx, ry, rz) deg`, three decimals (the precision
    /// given sets the decimals).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let d = f.precision().unwrap_or(3);
        write!(
            f,
            "({:.d$}, {:.d$}, {:.d$}) mm, ({:.d$}, {:.d$}, {:.d$}) deg",
            self.x, self.y, self.z, self.rx, self.ry, self.rz
        )
    }
}

impl Pose {
    /// A pose from its six components (mm, mm, mm, deg, deg, deg).
    pub fn new(x: f64, y: f64, z: f64, rx: f64, ry: f64, rz: f64) -> Self {
        Self {
            x,
            y,
            z,
            rx,
            ry,
            rz,
        }
    }
    /// A planar pose: position (x, y, z) and yaw `rz` only.
    pub fn planar(x: f64, y: f64, z: f64, rz: f64) -> Self {
        Self::new(x, y, z, 0.0, 0.0, rz)
    }
    /// The six components as an array [x, y, z, rx, ry, rz].
    pub fn to_array(self) -> [f64; 6] {
        [self.x, self.y, self.z, self.rx, self.ry, self.rz]
    }
    /// From an array [x, y, z, rx, ry, rz].
    pub fn from_array(a: [f64; 6]) -> Self {
        Self::new(a[0], a[1], a[2], a[3], a[4], a[5])
    }
    /// As an isometry (translation in mm, rotation as a unit quaternion).
    ///
    /// The rotation is `UnitQuaternion::from_euler_angles(rx, ry, rz)` in
    /// radians, i.e. R = Rz(rz) Ry(ry) Rx(rx): extrinsic x, then y, then z.
    pub fn to_isometry(self) -> nalgebra::Isometry3<f64> {
        let rotation = nalgebra::UnitQuaternion::from_euler_angles(
            self.rx.to_radians(),
            self.ry.to_radians(),
            self.rz.to_radians(),
        );
        nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::new(self.x, self.y, self.z),
            rotation,
        )
    }
    /// From an isometry (mm); angles in degrees.
    ///
    /// Angles come back in (-180, 180], with ry in [-90, 90] (the report's
    /// map E from a quaternion back to Euler angles, eq. 5.8).
    pub fn from_isometry(iso: &nalgebra::Isometry3<f64>) -> Self {
        let (rx, ry, rz) = iso.rotation.euler_angles();
        let t = iso.translation.vector;
        Self::new(
            t.x,
            t.y,
            t.z,
            rx.to_degrees(),
            ry.to_degrees(),
            rz.to_degrees(),
        )
    }
    /// `self` followed by `delta` expressed in `self`'s own frame
    /// (report eq. 5.7-5.8: a move in the sensor frame applied in the base frame).
    ///
    /// Eq. 5.8: position tau' = Q dtau Q* + tau and orientation
    /// E(H(Q, dQ)), i.e. the isometry product `self * delta`.
    pub fn compose(self, delta: Pose) -> Pose {
        Pose::from_isometry(&(self.to_isometry() * delta.to_isometry()))
    }
    /// The pose `other` expressed in the frame of `self` (inverse of compose).
    ///
    /// `self.compose(self.relative(other)) == other` up to rounding.
    pub fn relative(self, other: Pose) -> Pose {
        Pose::from_isometry(&(self.to_isometry().inverse() * other.to_isometry()))
    }
    /// Distance between positions, mm.
    pub fn distance(self, other: Pose) -> f64 {
        ((self.x - other.x).powi(2) + (self.y - other.y).powi(2) + (self.z - other.z).powi(2))
            .sqrt()
    }
    /// Angle of the rotation taking this orientation to `other`'s, degrees in [0, 180].
    pub fn angle_to(self, other: Pose) -> f64 {
        self.to_isometry()
            .rotation
            .angle_to(&other.to_isometry().rotation)
            .to_degrees()
    }
    /// True when all six components are finite.
    pub fn is_finite(self) -> bool {
        self.to_array().iter().all(|v| v.is_finite())
    }
}
