//! Tilt of the tool: the angle between its z axis and the work frame's,
//! and the least rotation that levels a pose to a largest tilt.
//!
//! A planar pose (rx = ry = 0) has zero tilt whatever its yaw; a 6-DoF
//! pose tilts by acos(cos rx cos ry) (extrinsic x-y-z angles).
use nalgebra::{Unit, UnitQuaternion, Vector3};
use tactrace_geometry::Pose;

/// The angle between the tool's z axis and the work frame's z axis, degrees
/// in [0, 180].
pub fn tilt_deg(pose: Pose) -> f64 {
    let axis = pose.to_isometry().rotation * Vector3::z();
    axis.z.clamp(-1.0, 1.0).acos().to_degrees()
}

/// `pose` with its orientation turned the least way (about the horizontal
/// axis normal to the tool's z axis) so that its tilt is at most
/// `max_deg`; its position unchanged. A pose within the bound is returned
/// as is. A tool pointing straight down (tilt 180 deg, no unique least
/// rotation) is turned about the work frame's x axis.
pub fn level_to(pose: Pose, max_deg: f64) -> Pose {
    let tilt = tilt_deg(pose);
    if tilt <= max_deg {
        return pose;
    }
    let iso = pose.to_isometry();
    let axis = iso.rotation * Vector3::z();
    let hinge = Unit::try_new(axis.cross(&Vector3::z()), 1e-12).unwrap_or(Vector3::x_axis());
    let turn = UnitQuaternion::from_axis_angle(&hinge, (tilt - max_deg).to_radians());
    let (rx, ry, rz) = (turn * iso.rotation).euler_angles();
    Pose {
        rx: rx.to_degrees(),
        ry: ry.to_degrees(),
        rz: rz.to_degrees(),
        ..pose
    }
}
