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
