//! The real edge data set's labels (edge position r = pose_2, angle
//! theta = pose_6, vertical offset pose_3, shear move_1/2/6) mapped onto the
//! model through [`Calibration`](crate::Calibration), so simulated taps can
//! be compared with, or stand in for, the real frames.
use crate::{Calibration, Shear, TacTipModel};
use tactrace_geometry::{Pose, Vec2};

/// One labelled tap on the straight edge of a large square object.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EdgeTap {
    /// Edge position, mm (pose_2).
    pub r_mm: f64,
    /// Edge angle, degrees (pose_6).
    pub theta_deg: f64,
    /// Vertical offset of the tap, mm (pose_3).
    pub dz_mm: f64,
    /// Shear perturbation (move_1, move_2 in the work frame, mm; move_6,
    /// deg), if any.
    pub shear: Option<Shear>,
}

impl EdgeTap {
    /// The slide in the sensor frame: the labelled work-frame move times
    /// the calibrated sign, turned by -theta into the sensor's axes and by
    /// the calibrated shear angle offset (eq. S7d).
    pub fn sensor_shear(&self, model: &TacTipModel) -> Option<Shear> {
        self.sensor_shear_with(&model.config().calibration)
    }

    /// As [`Self::sensor_shear`] with the calibration `cal`.
    pub(crate) fn sensor_shear_with(&self, cal: &Calibration) -> Option<Shear> {
        let sign = cal.shear_sign;
        let turn = cal.shear_angle_offset_deg - self.theta_deg;
        let (s, c) = turn.to_radians().sin_cos();
        self.shear.map(|m| Shear {
            dx_mm: sign * (c * m.dx_mm - s * m.dy_mm),
            dy_mm: sign * (s * m.dx_mm + c * m.dy_mm),
            drz_deg: sign * m.drz_deg,
        })
    }

    /// Tip pose in the edge's frame (edge along x through the origin).
    pub fn tip_pose(&self, model: &TacTipModel) -> Pose {
        let cal = &model.config().calibration;
        let depth = cal.tap_depth_mm + cal.depth_per_offset * self.dz_mm;
        Pose::planar(
            0.0,
            cal.edge_scale * self.r_mm + cal.edge_offset_mm,
            -depth,
            cal.angle_scale * self.theta_deg + cal.angle_offset_deg,
        )
    }
}

impl TacTipModel {
    /// Pin centres (px) for a labelled tap on the straight edge: the object
    /// is the half-plane on the calibrated side of the line y = 0.
    pub fn edge_tap_pins(&self, tap: &EdgeTap) -> Vec<[f64; 2]> {
        let side = self.config().calibration.object_side;
        let sd = move |p: Vec2| side * p.y;
        self.pins_sdf(&sd, tap.tip_pose(self), tap.sensor_shear(self))
    }

    /// Contact state of a labelled tap without its slide (eqs. S4-S6).
    pub(crate) fn edge_contact(&self, tap: &EdgeTap) -> crate::contact::ContactField {
        let side = self.config().calibration.object_side;
        let sd = move |p: Vec2| side * p.y;
        self.contact_field(&sd, tap.tip_pose(self))
    }
}

/// An edge pose in the servo loop's convention (report ch. 5, the
/// simulated rig's collection): `r_mm` along the contour's outward normal
/// (positive: the sensor centre outside the object), `theta_deg` the
/// sensor's yaw from that normal, in (-180, 180].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopEdgePose {
    pub r_mm: f64,
    pub theta_deg: f64,
}

/// `deg` wrapped into (-180, 180].
fn wrap_deg(deg: f64) -> f64 {
    let w = deg.rem_euclid(360.0);
    if w > 180.0 {
        w - 360.0
    } else {
        w
    }
}

impl Calibration {
    /// The loop's edge pose of a tap labelled (`r_mm`, `theta_deg`) in this
    /// sensor's label convention (docs/calibration.md, eq. L1): the tip
    /// sits at y0 = edge_scale r + edge_offset from the edge, whose outward
    /// normal is `object_side` times the edge frame's y axis, so
    /// r_loop = side y0 and theta_loop = angle_scale theta + angle_offset
    /// - side 90 deg.
    pub fn loop_pose(&self, r_mm: f64, theta_deg: f64) -> LoopEdgePose {
        let side = self.object_side;
        let y0 = self.edge_scale * r_mm + self.edge_offset_mm;
        let yaw = self.angle_scale * theta_deg + self.angle_offset_deg;
        LoopEdgePose {
            r_mm: side * y0,
            theta_deg: wrap_deg(yaw - side * 90.0),
        }
    }

    /// The labels (r mm, theta deg) this sensor's convention gives the
    /// loop's edge pose `pose`: the inverse of [`Self::loop_pose`] (eq. L1).
    pub fn labels_of(&self, pose: LoopEdgePose) -> (f64, f64) {
        let side = self.object_side;
        let y0 = pose.r_mm / side;
        let yaw = wrap_deg(pose.theta_deg + side * 90.0 - self.angle_offset_deg);
        (
            (y0 - self.edge_offset_mm) / self.edge_scale,
            wrap_deg(yaw) / self.angle_scale,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TacTipConfig;
    use tactrace_geometry::Contour;

    fn calibrations() -> Vec<Calibration> {
        let mut other = Calibration {
            object_side: 1.0,
            edge_scale: 1.3,
            angle_scale: 0.8,
            edge_offset_mm: -0.7,
            angle_offset_deg: 31.0,
            ..Calibration::default()
        };
        let default = Calibration::default();
        other.shear_angle_offset_deg = 0.0;
        vec![default, other]
    }

    #[test]
    fn labels_and_loop_poses_round_trip() {
        for cal in calibrations() {
            for (r, t) in [(0.0, 0.0), (-4.9, 44.0), (3.2, -45.0), (5.0, 12.5)] {
                let (r2, t2) = cal.labels_of(cal.loop_pose(r, t));
                assert!(
                    (r2 - r).abs() < 1e-9 && (t2 - t).abs() < 1e-9,
                    "{r},{t} -> {r2},{t2}"
                );
            }
        }
    }

    /// The theory: a labelled tap on the straight edge and a tap at the
    /// mapped loop pose against a large object's straight side deform the
    /// skin identically.
    #[test]
    fn a_labelled_tap_is_the_loop_tap_at_its_mapped_pose() {
        // A 400 mm square: its bottom side, y = -200, has outward normal -y.
        let h = 200.0;
        let square = Contour::new(vec![
            Vec2::new(-h, -h),
            Vec2::new(h, -h),
            Vec2::new(h, h),
            Vec2::new(-h, h),
        ])
        .unwrap();
        for cal in calibrations() {
            let cfg = TacTipConfig {
                calibration: cal.clone(),
                ..TacTipConfig::default()
            };
            let model = TacTipModel::new(cfg).unwrap();
            for (r, t) in [(0.0, 0.0), (-3.0, 30.0), (2.0, -40.0)] {
                let tap = EdgeTap {
                    r_mm: r,
                    theta_deg: t,
                    ..EdgeTap::default()
                };
                let want = model.edge_tap_pins(&tap);
                let p = cal.loop_pose(r, t);
                let normal_yaw = -90.0_f64;
                let n = Vec2::new(0.0, -1.0);
                let at = Vec2::new(0.0, -h) + n * p.r_mm;
                let depth = cal.tap_depth_mm;
                let tip = Pose::planar(at.x, at.y, -depth, normal_yaw + p.theta_deg);
                let got = model.pins(&square, tip, None);
                let worst = want
                    .iter()
                    .zip(&got)
                    .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                    .fold(0.0, f64::max);
                assert!(worst < 1e-6, "label ({r}, {t}): pins differ by {worst} px");
            }
        }
    }
}
