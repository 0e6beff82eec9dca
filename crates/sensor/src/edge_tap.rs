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
    /// the calibrated shear angle offset (eq. S7d). A negative angle scale
    /// (the model turns against the labelled angle: its frame is the
    /// labels' mirror image) mirrors the slide too: y and the twist
    /// change sign and the turn is +theta.
    pub fn sensor_shear(&self, model: &TacTipModel) -> Option<Shear> {
        self.sensor_shear_with(&model.config().calibration)
    }

    /// As [`Self::sensor_shear`] with the calibration `cal`.
    pub(crate) fn sensor_shear_with(&self, cal: &Calibration) -> Option<Shear> {
        let sign = cal.shear_sign;
        let mirror = if cal.angle_scale < 0.0 { -1.0 } else { 1.0 };
        let turn = cal.shear_angle_offset_deg - mirror * self.theta_deg;
        let (s, c) = turn.to_radians().sin_cos();
        self.shear.map(|m| {
            let dy = mirror * m.dy_mm;
            Shear {
                dx_mm: sign * (c * m.dx_mm - s * dy),
                dy_mm: sign * (s * m.dx_mm + c * dy),
                drz_deg: sign * mirror * m.drz_deg,
            }
        })
    }

    /// Tip pose in the edge's frame (edge along x through the origin):
    /// the labelled pose moved by the pivot offset (eq. L3).
    pub fn tip_pose(&self, model: &TacTipModel) -> Pose {
        let cal = &model.config().calibration;
        let depth = cal.tap_depth_mm + cal.depth_per_offset * self.dz_mm;
        let yaw = cal.angle_scale * self.theta_deg + cal.angle_offset_deg;
        let pivot = cal.pivot_offset(yaw);
        Pose::planar(
            pivot[0],
            cal.edge_scale * self.r_mm + cal.edge_offset_mm + pivot[1],
            -depth,
            yaw,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EdgeLabels, LabelConvention, TacTipConfig};
    use tactrace_geometry::{Contour, Vec2};

    fn calibrations() -> Vec<Calibration> {
        let mut other = Calibration {
            object_side: 1.0,
            edge_scale: 1.3,
            angle_scale: 0.8,
            edge_offset_mm: -0.7,
            angle_offset_deg: 31.0,
            pivot_x_mm: 1.3,
            pivot_y_mm: -0.6,
            ..Calibration::default()
        };
        let default = Calibration::default();
        other.shear_angle_offset_deg = 0.0;
        vec![default, other]
    }

    /// The theory of the label convention (eq. L1): a labelled tap on the
    /// straight edge and a tap of the sensor at the mapped pose (mounted on
    /// the tool turned by the convention's mount) against a large object's
    /// straight side deform the skin identically.
    #[test]
    fn a_labelled_tap_is_the_tool_tap_at_its_mapped_pose() {
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
            let convention = LabelConvention::centred(cal.clone());
            for (r, t) in [(0.0, 0.0), (-3.0, 30.0), (2.0, -40.0)] {
                let tap = EdgeTap {
                    r_mm: r,
                    theta_deg: t,
                    ..EdgeTap::default()
                };
                let want = model.edge_tap_pins(&tap);
                let p = convention.to_pose(EdgeLabels {
                    r_mm: r,
                    theta_deg: t,
                    dz_mm: 0.0,
                });
                let sensor_yaw = -90.0 + p.theta_deg + convention.mount_yaw_deg;
                let n = Vec2::new(0.0, -1.0);
                let at = Vec2::new(0.0, -h) + n * p.r_mm;
                let tip = Pose::planar(at.x, at.y, -p.depth_mm, sensor_yaw);
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
