//! Feature frames on a surface and the true label of a sensor pose: what a
//! surface_3d collection places its taps by and what a run is scored by.
//!
//! A feature frame F has its origin on the surface, its z axis along the
//! outward normal there and its x, y axes turned from a given frame's the
//! least way (the rotation taking that frame's z onto the normal). A label
//! is (x, y, z mm; rx, ry, rz deg) of the sensor frame in F with z the
//! *depth* (positive into the surface), rotations extrinsic x-y-z, as the
//! field's labels and `tactrace_control::se3` take them.
use crate::{Object3d, Vec3};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use tactrace_geometry::Pose;

/// Height of the start of the downward search for the surface, mm above
/// the point asked about.
const SEARCH_MM: f64 = 500.0;

/// The surface point over (x, y): the top of the solid on the vertical
/// column there; `None` when the column misses the object.
pub fn surface_point(object: &dyn Object3d, x: f64, y: f64) -> Option<Vec3> {
    let top = object.column_top(Vec3::new(x, y, 0.0), Vec3::z(), SEARCH_MM);
    top.is_finite().then(|| Vec3::new(x, y, top))
}

/// The feature frame at surface point `q`: z along the outward normal,
/// x and y those of `heading` (a rotation) turned the least way so its z
/// meets the normal. `None` where the normal points down (no least turn).
pub fn feature_frame(
    object: &dyn Object3d,
    q: Vec3,
    heading: UnitQuaternion<f64>,
) -> Option<Isometry3<f64>> {
    let n = object.normal(q);
    let axis = heading * Vec3::z();
    let align = UnitQuaternion::rotation_between(&axis, &n)?;
    Some(Isometry3::from_parts(
        Translation3::from(q),
        align * heading,
    ))
}

/// The sensor frame of label `s` in the frame `frame`: `frame * T(s)`
/// with the depth `s[2]` taken downwards (z = -depth).
pub fn pose_of_label(frame: &Isometry3<f64>, s: [f64; 6]) -> Pose {
    let local = Pose::new(s[0], s[1], -s[2], s[3], s[4], s[5]).to_isometry();
    Pose::from_isometry(&(frame * local))
}

/// The true label of a sensor at `pose` (its pole and axes, object frame)
/// on a smooth surface: its pose in the feature frame at the nearest
/// surface point, its x, y turned about the normal so that rz is 0 (as a
/// collection's labels), x and y about 0 up to the curvature's offset.
/// `None` where the normal points against the sensor's axis.
pub fn true_label(object: &dyn Object3d, pose: Pose) -> Option<[f64; 6]> {
    let sensor = pose.to_isometry();
    let p = sensor.translation.vector;
    let q = object.closest_point(p);
    let frame = feature_frame(object, q, sensor.rotation)?;
    let s = Pose::from_isometry(&(frame.inverse() * sensor));
    // Turn the frame about the normal by the label's yaw: with extrinsic
    // x-y-z angles R = Rz Ry Rx, so the turned frame sees rz = 0 and the
    // same rx, ry (the collection's labels have rz = 0).
    let yaw = Pose::new(0.0, 0.0, 0.0, 0.0, 0.0, s.rz).to_isometry();
    let s = Pose::from_isometry(&((frame * yaw).inverse() * sensor));
    Some([s.x, s.y, -s.z, s.rx, s.ry, s.rz])
}

/// The angle (deg) between the sensor's axis at `pose` and the surface's
/// outward normal at the point nearest its pole.
pub fn normal_error_deg(object: &dyn Object3d, pose: Pose) -> f64 {
    let sensor = pose.to_isometry();
    let p = sensor.translation.vector;
    let n = object.normal(object.closest_point(p));
    (sensor.rotation * Vec3::z()).angle(&n).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::HeightField;

    /// A label placed on a ramp by its feature frame reads back as itself.
    #[test]
    fn label_round_trips_through_the_feature_frame() {
        let ramp = HeightField::ramp(2.0, 20.0, 30.0).unwrap();
        let q = surface_point(&ramp, 5.0, -3.0).unwrap();
        assert!(ramp.signed_distance(q).abs() < 1e-9);
        let frame = feature_frame(&ramp, q, UnitQuaternion::identity()).unwrap();
        let s = [0.0, 0.0, 3.0, 10.0, -7.0, 0.0];
        let pose = pose_of_label(&frame, s);
        let back = true_label(&ramp, pose).unwrap();
        for k in 0..6 {
            assert!((back[k] - s[k]).abs() < 1e-6, "{k}: {back:?}");
        }
        let level = pose_of_label(&frame, [0.0, 0.0, 3.0, 0.0, 0.0, 0.0]);
        assert!(normal_error_deg(&ramp, level) < 1e-6);
        assert!((ramp.signed_distance(Vec3::new(level.x, level.y, level.z)) + 3.0).abs() < 1e-9);
    }
}
