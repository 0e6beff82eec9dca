//! One simulated tap as a frame, as `tactrace sensor render` draws it (and
//! the Python package's `SimTacTip`): a tap on a contour at an edge point,
//! or a calibrated sensor's tap on a straight edge in its own label
//! convention. The pose is checked against the contact model's range.
use crate::error::{LabError, Result};
use tactrace_geometry::Contour;
use tactrace_sensor::{EdgeTap, Frame, Shear, TacTipModel};
use tactrace_servo::{pose_at_edge, RigConfig};
use tactrace_store::SensorFolder;

/// What a tap is made on.
#[derive(Debug, Clone)]
enum Target {
    /// A contour; depths in mm below its top face (default: the rig's
    /// nominal tap).
    Contour { contour: Contour, nominal_mm: f64 },
    /// A calibrated sensor's straight edge; "depth" is its vertical offset
    /// label (default 0).
    CalibratedEdge,
}

/// A TacTip model and the object it taps.
#[derive(Debug, Clone)]
pub struct TapRenderer {
    model: TacTipModel,
    target: Target,
}

/// Where a tap is, relative to the edge: position `r_mm`, sensor angle
/// `theta_deg`, `depth` (mm, or a calibrated sensor's offset label; `None`
/// for the default), the edge point's arc length `arc_mm` (contours only)
/// and an optional slide.
#[derive(Debug, Clone, Copy, Default)]
pub struct TapPose {
    pub r_mm: f64,
    pub theta_deg: f64,
    pub depth: Option<f64>,
    pub arc_mm: f64,
    pub shear: Option<Shear>,
}

impl TapRenderer {
    /// The rig's simulated TacTip over `contour`.
    pub fn simulated(rig: &RigConfig, contour: Contour) -> Result<Self> {
        Ok(Self {
            model: TacTipModel::new(rig.sensor.clone())?,
            target: Target::Contour {
                contour,
                nominal_mm: rig.tap.nominal_indentation_mm(),
            },
        })
    }

    /// A calibrated sensor (`tactrace calibrate`) on a straight edge, in
    /// its reference frame's pin layout with its field correction.
    pub fn calibrated(sensor: &SensorFolder) -> Result<Self> {
        let spec = &sensor.spec;
        let model = TacTipModel::with_rest_pins(spec.sensor.clone(), spec.reference_pins.clone())?
            .with_correction(sensor.field_correction()?)?;
        Ok(Self {
            model,
            target: Target::CalibratedEdge,
        })
    }

    /// The sensor model.
    pub fn model(&self) -> &TacTipModel {
        &self.model
    }

    /// The pins the camera sees for the tap `t` (px, in rest-pin order);
    /// refused when the pose is not finite or deeper than the contact model
    /// covers.
    pub fn pins(&self, t: &TapPose) -> Result<Vec<[f64; 2]>> {
        let deepest = self.model.config().mechanics.max_depth_mm;
        match &self.target {
            Target::Contour {
                contour,
                nominal_mm,
            } => {
                let depth = t.depth.unwrap_or(*nominal_mm);
                check_render_pose(t.r_mm, t.theta_deg, depth, t.arc_mm, deepest)?;
                let (edge, normal) = contour.at_arc_length(t.arc_mm);
                let pose = pose_at_edge(edge, normal, t.r_mm, t.theta_deg, -depth);
                Ok(self.model.pins(contour, pose, t.shear))
            }
            Target::CalibratedEdge => {
                let dz = t.depth.unwrap_or(0.0);
                if !(t.r_mm.is_finite() && t.theta_deg.is_finite() && dz.is_finite()) {
                    return Err(LabError::Config(
                        "--r, --theta and --depth must be numbers".into(),
                    ));
                }
                let cal = &self.model.config().calibration;
                let depth = cal.tap_depth_mm + cal.depth_per_offset * dz;
                if !(depth > 0.0 && depth <= deepest) {
                    return Err(LabError::Config(format!(
                        "--depth {dz} (the vertical offset label) makes the tap {depth:.2} mm \
                         deep; the contact model covers 0 to {deepest} mm"
                    )));
                }
                let tap = EdgeTap {
                    r_mm: t.r_mm,
                    theta_deg: t.theta_deg,
                    dz_mm: dz,
                    shear: t.shear,
                };
                Ok(self.model.seen_pins(self.model.edge_tap_pins(&tap)))
            }
        }
    }

    /// The frame of the tap `t`, without noise (as `sensor render`).
    pub fn render(&self, t: &TapPose) -> Result<Frame> {
        Ok(self.model.render(&self.pins(t)?, None))
    }
}

/// A rendered tap must lie within the contact model's range: deeper taps
/// would all be clipped to the same image.
fn check_render_pose(r: f64, theta: f64, depth: f64, arc: f64, max_depth: f64) -> Result<()> {
    for (name, v) in [
        ("--r", r),
        ("--theta", theta),
        ("--arc", arc),
        ("--depth", depth),
    ] {
        if !v.is_finite() {
            return Err(LabError::Config(format!(
                "{name} must be a finite number, got {v}"
            )));
        }
    }
    if !(0.0..=max_depth).contains(&depth) {
        return Err(LabError::Config(format!(
            "--depth {depth} mm is outside the contact model's range, 0 to {max_depth} mm \
             (mechanics.max_depth_mm of the rig configuration): deeper taps would all render \
             as the {max_depth} mm one"
        )));
    }
    Ok(())
}
