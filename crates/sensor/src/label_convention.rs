//! The label convention of a real labelled collection on a straight edge,
//! against the controller's frame: one mapping, both ways.
//!
//! The controller (`tactrace-control`) reads an edge pose as r = signed
//! distance of the sensor centre from the edge along the outward normal
//! (mm, positive outside) and theta = the tool's yaw from the outward
//! normal (deg). A real collection labels its taps in its own frame
//! (Bristol: r = pose_2, theta = pose_6, vertical offset pose_3), which the
//! sensor's [`Calibration`] ties to the simulated lattice in an edge frame
//! (edge along x, the object on the side `object_side` says, see
//! [`crate::EdgeTap::tip_pose`]):
//!
//! - y_edge = edge_scale r_label + edge_offset + p_y(yaw_edge), where p
//!   is the pivot offset turned by the yaw (eq. L3: the labelled pose is
//!   the point the arm turns about, the dome's centre sits off it), and
//!   the outward normal points along object_side y, so r_tool = object_side
//!   y_edge;
//! - yaw_edge = angle_scale theta_label + angle_offset, the outward normal
//!   has yaw object_side 90 deg in that frame, and the sensor sits on the
//!   tool turned by `mount_yaw_deg`: yaw_edge = theta_tool + mount_yaw +
//!   object_side 90;
//! - depth = tap_depth + depth_per_offset dz_label.
//!
//! The default mount, `angle_offset - object_side 90`, makes theta_label =
//! theta_tool / angle_scale: the controller's aligned pose (theta = 0) is
//! the middle of the collection's angle range. With no mount (0) the
//! Bristol label theta = 0 is 74 deg from the controller's theta = 0, out
//! of the collection's +-45 deg.
use crate::Calibration;

/// A tap's pose against the edge in the controller's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolEdgePose {
    /// Signed distance of the sensor centre from the edge along the outward
    /// normal, mm (positive outside the object).
    pub r_mm: f64,
    /// The tool's yaw from the outward normal, degrees.
    pub theta_deg: f64,
    /// Indentation of the dome, mm (positive in contact).
    pub depth_mm: f64,
}

/// A tap's labels in a collection's own convention.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EdgeLabels {
    /// Edge position label, mm (Bristol pose_2).
    pub r_mm: f64,
    /// Edge angle label, degrees (Bristol pose_6).
    pub theta_deg: f64,
    /// Vertical offset label, mm (Bristol pose_3).
    pub dz_mm: f64,
}

/// How a collection's labels and the controller's edge pose map onto each
/// other: the sensor's calibration and the sensor's mounting yaw on the tool.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelConvention {
    pub calibration: Calibration,
    /// The sensor's yaw on the tool, degrees.
    pub mount_yaw_deg: f64,
}

impl LabelConvention {
    /// The convention of `calibration` with the default mount: the
    /// controller's theta = 0 is the label theta = 0.
    pub fn centred(calibration: Calibration) -> Self {
        let mount_yaw_deg = calibration.angle_offset_deg - 90.0 * calibration.object_side.signum();
        Self {
            calibration,
            mount_yaw_deg,
        }
    }

    /// The labels a tap at `pose` carries.
    pub fn to_labels(&self, pose: ToolEdgePose) -> EdgeLabels {
        let c = &self.calibration;
        let side = c.object_side.signum();
        let y_edge = side * pose.r_mm;
        let yaw_edge = pose.theta_deg + self.mount_yaw_deg + 90.0 * side;
        let pivot = c.pivot_offset(yaw_edge)[1];
        EdgeLabels {
            r_mm: (y_edge - pivot - c.edge_offset_mm) / c.edge_scale,
            theta_deg: wrap_deg((yaw_edge - c.angle_offset_deg) / c.angle_scale),
            dz_mm: (pose.depth_mm - c.tap_depth_mm) / c.depth_per_offset,
        }
    }

    /// The controller's (r mm, theta deg) of the labels (r, theta) at the
    /// nominal depth; `None` (no convention: the labels are the
    /// controller's) gives them back.
    pub fn edge_pose_of(convention: Option<&Self>, r_mm: f64, theta_deg: f64) -> (f64, f64) {
        match convention {
            None => (r_mm, theta_deg),
            Some(c) => {
                let p = c.to_pose(EdgeLabels {
                    r_mm,
                    theta_deg,
                    dz_mm: 0.0,
                });
                (p.r_mm, p.theta_deg)
            }
        }
    }

    /// The pose of a tap labelled `labels` (the inverse of
    /// [`Self::to_labels`]).
    pub fn to_pose(&self, labels: EdgeLabels) -> ToolEdgePose {
        let c = &self.calibration;
        let side = c.object_side.signum();
        let yaw_edge = c.angle_scale * labels.theta_deg + c.angle_offset_deg;
        let y_edge = c.edge_scale * labels.r_mm + c.edge_offset_mm + c.pivot_offset(yaw_edge)[1];
        ToolEdgePose {
            r_mm: side * y_edge,
            theta_deg: wrap_deg(yaw_edge - self.mount_yaw_deg - 90.0 * side),
            depth_mm: c.tap_depth_mm + c.depth_per_offset * labels.dz_mm,
        }
    }
}

/// An angle in (-180, 180] degrees.
pub fn wrap_deg(a: f64) -> f64 {
    let w = (a + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 {
        180.0
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EdgeTap, TacTipConfig, TacTipModel};

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    #[test]
    fn labels_and_poses_round_trip_both_ways() {
        for side in [-1.0, 1.0] {
            let cal = Calibration {
                object_side: side,
                edge_scale: 0.9,
                angle_scale: 1.1,
                pivot_x_mm: 1.2,
                pivot_y_mm: -0.4,
                ..Calibration::default()
            };
            for conv in [
                LabelConvention::centred(cal.clone()),
                LabelConvention {
                    calibration: cal.clone(),
                    mount_yaw_deg: 0.0,
                },
            ] {
                for (r, t, d) in [(-4.0, -40.0, 5.5), (0.0, 0.0, 6.25), (3.3, 44.0, 7.1)] {
                    let pose = ToolEdgePose {
                        r_mm: r,
                        theta_deg: t,
                        depth_mm: d,
                    };
                    let back = conv.to_pose(conv.to_labels(pose));
                    assert!(close(back.r_mm, r) && close(back.theta_deg, t));
                    assert!(close(back.depth_mm, d));
                    let labels = EdgeLabels {
                        r_mm: r,
                        theta_deg: t,
                        dz_mm: d - 6.0,
                    };
                    let again = conv.to_labels(conv.to_pose(labels));
                    assert!(close(again.r_mm, labels.r_mm));
                    assert!(close(again.theta_deg, labels.theta_deg));
                    assert!(close(again.dz_mm, labels.dz_mm));
                }
            }
        }
    }

    /// Without a mount the tool is the simulated lattice: the pose of a
    /// labelled tap is the twin's tip pose (`EdgeTap::tip_pose`) seen from
    /// the outward normal, and the label theta = 0 is 90 deg plus the
    /// angle offset from the controller's theta = 0 (70.7 deg with the
    /// default calibration).
    #[test]
    fn the_unmounted_convention_is_the_twins_tip_pose() {
        let mut cfg = TacTipConfig::default();
        cfg.calibration.pivot_x_mm = 0.8;
        cfg.calibration.pivot_y_mm = 0.3;
        let model = TacTipModel::new(cfg).unwrap();
        let cal = model.config().calibration.clone();
        let conv = LabelConvention {
            calibration: cal.clone(),
            mount_yaw_deg: 0.0,
        };
        let tap = EdgeTap {
            r_mm: 1.5,
            theta_deg: 20.0,
            dz_mm: 0.4,
            shear: None,
        };
        let tip = tap.tip_pose(&model);
        let pose = conv.to_pose(EdgeLabels {
            r_mm: 1.5,
            theta_deg: 20.0,
            dz_mm: 0.4,
        });
        // object_side -1: the object on +y, the outward normal along -y.
        assert!(close(pose.r_mm, -tip.y));
        assert!(close(pose.theta_deg, tip.rz + 90.0));
        assert!(close(pose.depth_mm, -tip.z));
        let zero = conv.to_pose(EdgeLabels::default());
        let want = 90.0 + cal.angle_offset_deg;
        assert!((zero.theta_deg - want).abs() < 1e-9, "{}", zero.theta_deg);
        let centred = LabelConvention::centred(cal);
        assert!(close(centred.to_pose(EdgeLabels::default()).theta_deg, 0.0));
    }

    /// Eq. L3: turning about a pivot off the dome's axis moves the dome
    /// centre's distance from the edge by p_x sin(yaw) + p_y cos(yaw).
    #[test]
    fn a_pivot_offset_moves_the_dome_with_the_angle() {
        let plain = Calibration {
            pivot_x_mm: 0.0,
            pivot_y_mm: 0.0,
            ..Calibration::default()
        };
        let pivoted = Calibration {
            pivot_x_mm: 1.0,
            pivot_y_mm: 0.5,
            ..plain.clone()
        };
        for t in [-40.0, 0.0, 35.0] {
            let labels = EdgeLabels {
                r_mm: 1.0,
                theta_deg: t,
                dz_mm: 0.0,
            };
            let a = LabelConvention::centred(plain.clone()).to_pose(labels);
            let b = LabelConvention::centred(pivoted.clone()).to_pose(labels);
            let yaw = (t + plain.angle_offset_deg).to_radians();
            let shift = plain.object_side * (yaw.sin() + 0.5 * yaw.cos());
            assert!(close(b.r_mm - a.r_mm, shift), "theta {t}");
            assert!(close(b.theta_deg, a.theta_deg));
        }
    }

    #[test]
    fn angles_wrap_into_one_turn() {
        assert!(close(wrap_deg(190.0), -170.0));
        assert!(close(wrap_deg(-180.0), 180.0));
        assert!(close(wrap_deg(45.0), 45.0));
    }
}
