//! Parameters of the simulated TacTip, grouped as the physics is: skin
//! geometry, internal camera, contact mechanics, nuisance, and the
//! calibration that maps the real data set's labels onto the model.
//!
//! Defaults are fitted to the real 127-pin frames in `shared/data`
//! (see docs/sensor-model.md); every field can be overridden from TOML.
use crate::SensorError;
use serde::{Deserialize, Serialize};

/// Everything the simulated TacTip needs; `Default` is the calibrated preset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct TacTipConfig {
    pub geometry: SkinGeometry,
    pub camera: CameraConfig,
    pub mechanics: Mechanics,
    pub nuisance: Nuisance,
    pub calibration: Calibration,
}

/// The hemispherical skin and its pins (docs/sensor-model.md, eqs. S1
/// and S1r).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SkinGeometry {
    /// Radius of the hemispherical dome, mm (the skin is ~40 mm across).
    pub dome_radius_mm: f64,
    /// Pin spacing along the skin surface, mm: the lattice spacing, or
    /// the step between rings.
    pub pin_spacing_mm: f64,
    /// Rings round the centre pin, 6n pins on ring n: 6 give 127 pins,
    /// 10 give 331.
    pub rings: usize,
    /// Pin radius on the skin, mm (sets the rendered disc size).
    pub pin_radius_mm: f64,
    /// How the pins are laid out: a hexagonal lattice (eq. S1) or
    /// concentric circles (eq. S1r).
    pub layout: PinLayout,
    /// Concentric circles only: the angle of ring k's first pin from the
    /// sensor's x axis, degrees, innermost ring first, one per ring
    /// (empty: every ring starts on the x axis).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ring_phase_deg: Vec<f64>,
}

/// The pin layout of the skin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PinLayout {
    /// A hexagonal lattice, ring n a hexagon of 6n pins (eq. S1; the
    /// 127-pin TacTip).
    #[default]
    Hex,
    /// Concentric circles, ring k of radius k s holding 6k pins evenly
    /// spaced and turned by its phase (eq. S1r; the 331-pin TacTip).
    Rings,
}

impl PinLayout {
    /// What the layout is, for messages.
    pub fn describe(self) -> &'static str {
        match self {
            PinLayout::Hex => "hexagonal lattice",
            PinLayout::Rings => "concentric rings",
        }
    }
}

impl Default for SkinGeometry {
    fn default() -> Self {
        Self {
            dome_radius_mm: 20.0,
            pin_spacing_mm: 4.243,
            rings: 6,
            pin_radius_mm: 0.8,
            layout: PinLayout::Hex,
            ring_phase_deg: Vec::new(),
        }
    }
}

/// The camera inside the sensor, looking along the dome's axis at the skin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraConfig {
    /// Frame width, px.
    pub width: u32,
    /// Frame height, px.
    pub height: u32,
    /// Image position of the dome's axis (the centre pin at rest), px.
    pub centre_px: [f64; 2],
    /// Pinhole focal length, px.
    pub focal_px: f64,
    /// Height of the camera's optical centre above the dome's lowest point, mm.
    pub height_mm: f64,
    /// Angle of the sensor's x axis in the image (from the image x axis
    /// towards the image y axis), degrees.
    pub rotation_deg: f64,
    /// True when the sensor's y axis appears mirrored in the image.
    pub mirror: bool,
    /// Binarise the frame as the real camera pipeline does (the Bristol
    /// frames are thresholded white pins on black): grey levels above this
    /// value become 255, the rest 0, after any image noise. `None` keeps
    /// the anti-aliased grey frame.
    pub binarise_above: Option<u8>,
}

impl Default for CameraConfig {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            centre_px: [126.88, 128.99],
            focal_px: 78.05,
            height_mm: 29.06,
            rotation_deg: 179.51,
            mirror: true,
            binarise_above: Some(127),
        }
    }
}

/// Contact mechanics (docs/sensor-model.md, eqs. S4-S8a), fitted to the
/// real edge frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Mechanics {
    /// Width of the Gaussian that spreads indentation into the skin's
    /// upward push (and the contact weight), mm.
    pub kernel_width_mm: f64,
    /// Fraction of the smoothed indentation that lifts pins towards the
    /// camera (0 = no perspective effect, 1 = skin follows the object).
    pub lift_gain: f64,
    /// Core radius of the sideways gel-flow kernel, mm.
    pub flow_core_mm: f64,
    /// Screening 1 / lambda of the sideways gel flow, per mm: the gel is
    /// bonded to the rigid core, so a source's push decays as
    /// exp(-rho / lambda) beyond the plain 2-D source (eq. S6a); 0 = an
    /// unscreened source.
    pub flow_screening_per_mm: f64,
    /// Thickness of the gel layer carrying the displaced volume, mm
    /// (smaller = larger pin motion).
    pub layer_thickness_mm: f64,
    /// Quadrature spacing of the contact patch on the skin, mm.
    pub patch_grid_mm: f64,
    /// Spacing of the grid where the object's signed distance is sampled, mm.
    pub distance_grid_mm: f64,
    /// Deepest indentation the model resolves, mm (deeper is clipped).
    pub max_depth_mm: f64,
    /// Slip limit L_ref, mm: the largest lag of the skin behind a slide
    /// before it slips, at the reference contact load of 1000 mm^3
    /// (eq. S7a).
    pub shear_limit_mm: f64,
    /// Exponent beta of the slip limit's growth with the contact load
    /// P (indented volume): L = L_ref (P / 1000 mm^3)^beta (eq. S7a).
    pub slip_load_exponent: f64,
    /// Stick gain kappa: lag of the skin per mm of slide while it sticks
    /// (eq. S7b).
    pub stick_gain: f64,
    /// Reach S_T of the skin lag along the skin from the pole, mm: a pin
    /// carries the share max(0, 1 - (s / S_T)^2) of it (eq. S7c).
    pub slip_profile_mm: f64,
    /// Share alpha of the skin lag that follows the contact pressure
    /// (D_i / max D) instead of the radial profile (eq. S7e).
    pub stick_share: f64,
    /// Gain rho_in on the slide's component along the edge normal when it
    /// goes into the object (eq. S7f; 1 = isotropic).
    pub edge_gain_in: f64,
    /// Gain rho_out on that component when the slide leaves the object
    /// (eq. S7f).
    pub edge_gain_out: f64,
    /// Unsaturated lag gamma of the pressed skin along the edge normal
    /// per mm of normal slide (eq. S7g).
    pub edge_bite: f64,
    /// Twist (deg) at which the skin's rotational drag saturates.
    pub shear_limit_deg: f64,
    /// Smoothed indentation (mm) at which a pin counts as half in contact.
    pub contact_scale_mm: f64,
    /// Distance along the skin from the pole (mm) at which the sensor body
    /// holds the skin still: pin motion is scaled by 1 - (s / S)^2, zero
    /// beyond S (eq. S8a). A very large value switches the clamp off.
    pub rim_clamp_mm: f64,
    /// Compliance C of the dome and its mount: indentation depth lost per
    /// 1000 mm^3 of indented volume, mm. The contact load pushes the sensor
    /// back, so a wide contact indents less deeply than the commanded depth:
    /// d + C V(d) / 1000 mm^3 = d_cmd (eq. S4a). 0 = rigid.
    pub compliance_mm: f64,
    /// Which law turns a slide made in contact into skin slip: the lumped
    /// lag of eq. S7 or the bristles along the slide's path (eqs. B1-B3).
    pub slip_law: SlipLaw,
    /// Brush slip ratio zeta: the largest stuck displacement of the skin
    /// per mm of local indentation before it slips, mm/mm (eq. B2).
    pub brush_slip_ratio: f64,
    /// Brush local gain g_l: the share of the spread bristle field a pin
    /// shows (eq. B3).
    pub brush_local_gain: f64,
    /// Brush skin gain g_w: whole-membrane drag (mm) per mm of bristle
    /// displacement over 100 mm^2 of contact (eq. B3; profile of eq. S7c).
    pub brush_skin_gain: f64,
    /// Steps the slide's path is replayed in (eq. B1; numerical).
    pub brush_steps: usize,
    /// How the pressed skin spreads its share of the lag to the pins
    /// (eq. S7e): the smoothed pressure D_i / max D, or the tangential
    /// point-load response of an elastic half-space (Cerruti, eq. S7h).
    pub slip_spread: SlipSpread,
    /// Poisson's ratio nu of the Cerruti spread (eq. S7h): 0 isotropic,
    /// 0.5 (incompressible) twice the response along the load as across.
    pub slip_poisson: f64,
    /// Core radius of the Cerruti spread, mm (eq. S7h; regularises 1/r).
    pub slip_core_mm: f64,
}

/// How the pressed skin's share of the lag reaches the pins (eq. S7e/h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SlipSpread {
    /// In proportion to the smoothed pressure D_i / max D (eq. S7e).
    #[default]
    Pressure,
    /// The tangential-load response of an elastic half-space summed over
    /// the pressed patch (eq. S7h).
    Cerruti,
}

/// The slip law of a slide made in contact (docs/sensor-model.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SlipLaw {
    /// The lumped stick-slip lag of the whole skin (eq. S7).
    #[default]
    Lag,
    /// Bristles carried along the slide's path and capped by friction
    /// (eqs. B1-B3).
    Brush,
}

impl Default for Mechanics {
    /// Fitted to the real edge frames by the transfer fit, stage 7
    /// (docs/sensor-model.md, "Transfer fit"; `tactrace sim-fit`); the
    /// grids, `max_depth_mm` and the unused laws' settings are numerical
    /// settings, not fitted.
    fn default() -> Self {
        Self {
            kernel_width_mm: 5.2439,
            lift_gain: 0.417,
            flow_core_mm: 0.1913,
            flow_screening_per_mm: 0.0282,
            layer_thickness_mm: 7.2428,
            patch_grid_mm: 1.0,
            distance_grid_mm: 3.0,
            max_depth_mm: 8.0,
            shear_limit_mm: 0.9348,
            slip_load_exponent: 1.5181,
            stick_gain: 2.3464,
            slip_profile_mm: 36.2505,
            stick_share: 0.688,
            edge_gain_in: 1.8193,
            edge_gain_out: 1.9287,
            edge_bite: 0.0,
            shear_limit_deg: 0.1982,
            contact_scale_mm: 0.0374,
            rim_clamp_mm: 28.8466,
            compliance_mm: 0.3161,
            slip_law: SlipLaw::Lag,
            brush_slip_ratio: 0.3,
            brush_local_gain: 0.5,
            brush_skin_gain: 0.5,
            brush_steps: 8,
            slip_spread: SlipSpread::Pressure,
            slip_poisson: 0.5,
            slip_core_mm: 2.0,
        }
    }
}

/// Measurement nuisance added when rendering with a random generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Nuisance {
    /// Standard deviation of independent pin-centre jitter, px.
    pub pin_jitter_px: f64,
    /// Standard deviation of additive Gaussian image noise, grey levels.
    pub image_noise_std: f64,
}

impl Default for Nuisance {
    fn default() -> Self {
        Self {
            pin_jitter_px: 0.0,
            image_noise_std: 0.0,
        }
    }
}

/// How the real edge data set's labels map onto the model
/// (used by [`crate::EdgeTap`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Calibration {
    /// Added to the labelled angle (pose_6), degrees.
    pub angle_offset_deg: f64,
    /// Added to the labelled edge position (pose_2), mm.
    pub edge_offset_mm: f64,
    /// Model angle per degree of labelled angle (1 = the label's scale).
    pub angle_scale: f64,
    /// Model edge position per mm of labelled edge position.
    pub edge_scale: f64,
    /// Indentation depth at zero vertical offset (pose_3 = 0), mm.
    pub tap_depth_mm: f64,
    /// Depth change per mm of labelled vertical offset (sign included).
    pub depth_per_offset: f64,
    /// +1 when the object lies on the sensor's -y side at zero angle.
    pub object_side: f64,
    /// The slide the sensor made is `shear_sign` times the labelled move
    /// (move_1, move_2, move_6); -1 when the label is where the tap began
    /// relative to the final pose.
    pub shear_sign: f64,
    /// Angle (deg) by which the slide, turned into the sensor frame, is
    /// turned further: the arm's tool axes against the pin lattice's
    /// (eq. S7d).
    pub shear_angle_offset_deg: f64,
    /// Offset of the dome's axis from the point the labelled pose turns
    /// about (the arm's tool centre point), sensor frame, mm: the dome
    /// centre is the labelled position plus this offset turned by the
    /// sensor's yaw, so its distance from the edge changes with the angle
    /// (eq. L3). 0 = the labelled pose is the dome's centre.
    pub pivot_x_mm: f64,
    /// The pivot offset's sensor-frame y component, mm (eq. L3).
    pub pivot_y_mm: f64,
}

impl Calibration {
    /// The dome centre's offset from the labelled pose at the edge-frame
    /// yaw `yaw_deg` (eq. L3): the pivot offset turned by the yaw, mm.
    pub fn pivot_offset(&self, yaw_deg: f64) -> [f64; 2] {
        let (s, c) = yaw_deg.to_radians().sin_cos();
        [
            c * self.pivot_x_mm - s * self.pivot_y_mm,
            s * self.pivot_x_mm + c * self.pivot_y_mm,
        ]
    }
}

impl Default for Calibration {
    /// Orientation conventions found on the real data; offsets, pivot and
    /// tap depth fitted with the mechanics by the transfer fit, stage 7
    /// (docs/sensor-model.md, "Transfer fit").
    fn default() -> Self {
        Self {
            angle_offset_deg: -17.2919,
            edge_offset_mm: 2.2635,
            angle_scale: 1.0,
            edge_scale: 1.0,
            tap_depth_mm: 7.0472,
            depth_per_offset: -1.4934,
            object_side: -1.0,
            shear_sign: 1.0,
            shear_angle_offset_deg: 14.966,
            pivot_x_mm: 1.1958,
            pivot_y_mm: 0.6531,
        }
    }
}

fn positive(field: &'static str, value: f64) -> Result<(), SensorError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(SensorError::InvalidConfig {
            field,
            value,
            reason: "must be a positive finite number",
        })
    }
}

fn non_negative(field: &'static str, value: f64) -> Result<(), SensorError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(SensorError::InvalidConfig {
            field,
            value,
            reason: "must be a finite number >= 0",
        })
    }
}

fn finite(field: &'static str, value: f64) -> Result<(), SensorError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(SensorError::InvalidConfig {
            field,
            value,
            reason: "must be finite",
        })
    }
}

impl TacTipConfig {
    /// Check every field's range; the model calls this on construction.
    pub fn validate(&self) -> Result<(), SensorError> {
        let (g, c, m, n, k) = (
            &self.geometry,
            &self.camera,
            &self.mechanics,
            &self.nuisance,
            &self.calibration,
        );
        positive("geometry.dome_radius_mm", g.dome_radius_mm)?;
        if g.dome_radius_mm > MAX_DOME_RADIUS_MM {
            return Err(SensorError::TooLarge {
                field: "geometry.dome_radius_mm",
                value: g.dome_radius_mm,
                reason: format!(
                    "must be at most {MAX_DOME_RADIUS_MM} mm (a TacTip's dome is about 20 mm; \
                     the contact patch grows with it)"
                ),
            });
        }
        positive("geometry.pin_spacing_mm", g.pin_spacing_mm)?;
        positive("geometry.pin_radius_mm", g.pin_radius_mm)?;
        if g.rings == 0 || g.rings > 20 {
            return Err(SensorError::InvalidConfig {
                field: "geometry.rings",
                value: g.rings as f64,
                reason: "must be between 1 and 20",
            });
        }
        check_phases(g)?;
        let outer = g.rings as f64 * g.pin_spacing_mm / g.dome_radius_mm;
        if outer >= std::f64::consts::FRAC_PI_2 {
            return Err(SensorError::InvalidConfig {
                field: "geometry.pin_spacing_mm",
                value: g.pin_spacing_mm,
                reason: "outer ring reaches past the dome's equator",
            });
        }
        for (field, v) in [("camera.width", c.width), ("camera.height", c.height)] {
            if v == 0 || v > 4096 {
                return Err(SensorError::InvalidConfig {
                    field,
                    value: v as f64,
                    reason: "must be between 1 and 4096 px",
                });
            }
        }
        finite("camera.centre_px[0]", c.centre_px[0])?;
        finite("camera.centre_px[1]", c.centre_px[1])?;
        positive("camera.focal_px", c.focal_px)?;
        positive("camera.height_mm", c.height_mm)?;
        finite("camera.rotation_deg", c.rotation_deg)?;
        let rim_height = g.dome_radius_mm * (1.0 - outer.cos());
        if c.height_mm <= rim_height {
            return Err(SensorError::InvalidConfig {
                field: "camera.height_mm",
                value: c.height_mm,
                reason: "camera must sit above the outer pin ring",
            });
        }
        positive("mechanics.kernel_width_mm", m.kernel_width_mm)?;
        non_negative("mechanics.lift_gain", m.lift_gain)?;
        positive("mechanics.flow_core_mm", m.flow_core_mm)?;
        positive("mechanics.layer_thickness_mm", m.layer_thickness_mm)?;
        positive("mechanics.patch_grid_mm", m.patch_grid_mm)?;
        positive("mechanics.distance_grid_mm", m.distance_grid_mm)?;
        positive("mechanics.max_depth_mm", m.max_depth_mm)?;
        if m.max_depth_mm >= g.dome_radius_mm {
            return Err(SensorError::InvalidConfig {
                field: "mechanics.max_depth_mm",
                value: m.max_depth_mm,
                reason: "must be below the dome radius",
            });
        }
        positive("mechanics.shear_limit_mm", m.shear_limit_mm)?;
        finite("mechanics.slip_load_exponent", m.slip_load_exponent)?;
        non_negative("mechanics.stick_gain", m.stick_gain)?;
        positive("mechanics.slip_profile_mm", m.slip_profile_mm)?;
        finite("mechanics.stick_share", m.stick_share)?;
        non_negative("mechanics.edge_gain_in", m.edge_gain_in)?;
        non_negative("mechanics.edge_gain_out", m.edge_gain_out)?;
        finite("mechanics.edge_bite", m.edge_bite)?;
        positive("mechanics.shear_limit_deg", m.shear_limit_deg)?;
        positive("mechanics.contact_scale_mm", m.contact_scale_mm)?;
        positive("mechanics.rim_clamp_mm", m.rim_clamp_mm)?;
        non_negative("mechanics.compliance_mm", m.compliance_mm)?;
        non_negative("mechanics.flow_screening_per_mm", m.flow_screening_per_mm)?;
        non_negative("mechanics.brush_slip_ratio", m.brush_slip_ratio)?;
        finite("mechanics.brush_local_gain", m.brush_local_gain)?;
        finite("mechanics.brush_skin_gain", m.brush_skin_gain)?;
        if !(0.0..=0.5).contains(&m.slip_poisson) {
            return Err(SensorError::InvalidConfig {
                field: "mechanics.slip_poisson",
                value: m.slip_poisson,
                reason: "must be between 0 and 0.5",
            });
        }
        positive("mechanics.slip_core_mm", m.slip_core_mm)?;
        if m.brush_steps == 0 || m.brush_steps > 1000 {
            return Err(SensorError::InvalidConfig {
                field: "mechanics.brush_steps",
                value: m.brush_steps as f64,
                reason: "must be between 1 and 1000",
            });
        }
        non_negative("nuisance.pin_jitter_px", n.pin_jitter_px)?;
        non_negative("nuisance.image_noise_std", n.image_noise_std)?;
        finite("calibration.angle_offset_deg", k.angle_offset_deg)?;
        finite("calibration.edge_offset_mm", k.edge_offset_mm)?;
        finite("calibration.angle_scale", k.angle_scale)?;
        finite("calibration.edge_scale", k.edge_scale)?;
        finite("calibration.tap_depth_mm", k.tap_depth_mm)?;
        finite("calibration.depth_per_offset", k.depth_per_offset)?;
        finite("calibration.object_side", k.object_side)?;
        finite("calibration.shear_sign", k.shear_sign)?;
        finite(
            "calibration.shear_angle_offset_deg",
            k.shear_angle_offset_deg,
        )?;
        self.check_sizes()
    }

    /// The tables the contact model allocates, bounded: the patch's kernel
    /// weights (points x pins, eqs. S5-S6) and the distance grid of a tap
    /// (docs/sensor-model.md). Called by [`Self::validate`] once the
    /// values are in range.
    fn check_sizes(&self) -> Result<(), SensorError> {
        let (g, m) = (&self.geometry, &self.mechanics);
        // The patch's radius along the skin: the dome within
        // `max_depth_mm` of its lowest point; horizontal reaches are less.
        let reach = g.dome_radius_mm * (1.0 - m.max_depth_mm / g.dome_radius_mm).acos();
        // Either layout holds 1 + 3n(n + 1) pins (eqs. S1, S1r).
        let rings = g.rings as f64;
        let pins = 3.0 * rings * rings + 3.0 * rings + 1.0;
        // ContactModel::new: a hexagonal lattice of ceil(reach / h) + 1 rings.
        let patch_rings = (reach / m.patch_grid_mm).ceil() + 1.0;
        let lattice = 3.0 * patch_rings * patch_rings + 3.0 * patch_rings + 1.0;
        if lattice * pins > MAX_KERNEL_WEIGHTS {
            let most = largest_rings(MAX_KERNEL_WEIGHTS / pins);
            return Err(SensorError::TooLarge {
                field: "mechanics.patch_grid_mm",
                value: m.patch_grid_mm,
                reason: format!(
                    "the contact patch (out to {reach:.1} mm from the pole along the skin) \
                     would hold {lattice:.3e} points x {pins} pins = {:.3e} kernel weights, more \
                     than the {MAX_KERNEL_WEIGHTS:.0e} allowed: use a grid of at least \
                     {:.3} mm",
                    lattice * pins,
                    round_up(reach / (most - 1.0)),
                ),
            });
        }
        // DistanceGrid::new: (2 (ceil(reach / s) + 1) + 1)^2 nodes a tap.
        let side = 2.0 * ((reach / m.distance_grid_mm).ceil() + 1.0) + 1.0;
        if side * side > MAX_DISTANCE_NODES {
            let half = ((MAX_DISTANCE_NODES.sqrt() - 1.0) / 2.0).floor() - 1.0;
            return Err(SensorError::TooLarge {
                field: "mechanics.distance_grid_mm",
                value: m.distance_grid_mm,
                reason: format!(
                    "the distance grid over the contact (out to {reach:.1} mm) would hold \
                     {:.3e} nodes a tap, more than the {MAX_DISTANCE_NODES:.0e} allowed: use \
                     a grid of at least {:.3} mm",
                    side * side,
                    round_up(reach / half),
                ),
            });
        }
        Ok(())
    }
}

/// The ring phases: only for concentric rings, one per ring, finite.
fn check_phases(g: &SkinGeometry) -> Result<(), SensorError> {
    let field = "geometry.ring_phase_deg";
    let count = g.ring_phase_deg.len();
    if count == 0 {
        return Ok(());
    }
    if g.layout != PinLayout::Rings {
        return Err(SensorError::InvalidConfig {
            field,
            value: count as f64,
            reason: "ring phases are for a rings layout (layout = \"rings\") only",
        });
    }
    if count != g.rings {
        return Err(SensorError::InvalidConfig {
            field,
            value: count as f64,
            reason: "must give one phase per ring (as many as geometry.rings)",
        });
    }
    for &v in &g.ring_phase_deg {
        finite(field, v)?;
    }
    Ok(())
}

/// The largest dome radius accepted, mm.
pub const MAX_DOME_RADIUS_MM: f64 = 500.0;

/// The most kernel weights (contact patch points x pins) the contact
/// model may tabulate: 2e7, 240 MB of tables (the defaults use 1.6e5).
pub const MAX_KERNEL_WEIGHTS: f64 = 2e7;

/// The most nodes of a tap's distance grid: 4e6, 32 MB (the defaults use
/// 289).
pub const MAX_DISTANCE_NODES: f64 = 4e6;

/// The most hexagonal rings whose lattice (3 n^2 + 3 n + 1 points) holds at
/// most `points` points.
fn largest_rings(points: f64) -> f64 {
    ((-3.0 + (9.0 - 12.0 * (1.0 - points)).sqrt()) / 6.0).floor()
}

/// `v` rounded up at the third decimal (a grid spacing that fits).
fn round_up(v: f64) -> f64 {
    (v * 1000.0).ceil() / 1000.0
}
