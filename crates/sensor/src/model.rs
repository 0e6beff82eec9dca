//! The simulated TacTip: pin layout, contact response and rendering in one
//! checked model, shared by simulated taps and (through measured rest pins)
//! the real sensor's geometry.
use crate::brush::{bristles, brush_slip, slide_path};
use crate::config::{Mechanics, SkinGeometry, TacTipConfig};
use crate::contact::{ContactField, ContactModel, Shear};
use crate::layout::{skin_pins, Projection};
use crate::render::{add_noise, draw_disc, jitter};
use crate::slip::{lag_profile, slip_field};
use crate::SlipLaw;
use crate::{Frame, SensorError};
use rand_chacha::ChaCha8Rng;
use tactrace_geometry::{Contour, Pose, Vec2};

/// A checked TacTip model: rest pins (px), their skin coordinates and the
/// precomputed contact response.
#[derive(Debug, Clone)]
pub struct TacTipModel {
    cfg: TacTipConfig,
    proj: Projection,
    /// Surface coordinates of each pin, mm (same order as `rest_px`).
    pins_g: Vec<[f64; 2]>,
    rest_px: Vec<[f64; 2]>,
    /// Model projection of each pin at rest (eq. S3), px.
    base_px: Vec<[f64; 2]>,
    /// Rim clamp factor of each pin, 1 - (s / S)^2 clipped at 0 (eq. S8a).
    clamp: Vec<f64>,
    radii_px: Vec<f64>,
    contact: ContactModel,
    lift_gain: f64,
    /// A calibrated sensor's correction of the pin field (`None`: the
    /// physics alone).
    correction: Option<std::sync::Arc<crate::FieldCorrection>>,
}

impl TacTipModel {
    /// Build the model from a configuration; rest pins are the projection of
    /// the skin's pin layout (eq. S1 or S1r, then S2-S3), centre first, ring
    /// by ring.
    pub fn new(cfg: TacTipConfig) -> Result<Self, SensorError> {
        cfg.validate()?;
        let proj = Projection::new(&cfg.geometry, &cfg.camera);
        let pins_g = skin_pins(&cfg.geometry);
        let rest_px = pins_g.iter().map(|g| proj.project(*g)).collect();
        Ok(Self::assemble(cfg, proj, pins_g, rest_px))
    }

    /// Rest layout taken from pin centres measured on a real undeformed
    /// frame (px), so simulated and real frames share one geometry. Each
    /// measured pin is matched to the nearest model pin of the configured
    /// layout (either kind); the output of [`Self::pins`] keeps the order
    /// of `rest_px`.
    pub fn with_rest_pins(cfg: TacTipConfig, rest_px: Vec<[f64; 2]>) -> Result<Self, SensorError> {
        cfg.validate()?;
        let proj = Projection::new(&cfg.geometry, &cfg.camera);
        let lattice = skin_pins(&cfg.geometry);
        let order = match_rest_pins(&proj, &lattice, &cfg.geometry, &rest_px)?;
        let pins_g = order.iter().map(|&k| lattice[k]).collect();
        Ok(Self::assemble(cfg, proj, pins_g, rest_px))
    }

    fn assemble(
        cfg: TacTipConfig,
        proj: Projection,
        pins_g: Vec<[f64; 2]>,
        rest_px: Vec<[f64; 2]>,
    ) -> Self {
        let radius = cfg.geometry.pin_radius_mm;
        let radii_px = pins_g.iter().map(|g| radius * proj.scale(*g)).collect();
        let contact = ContactModel::new(
            pins_g.clone(),
            &proj,
            cfg.geometry.dome_radius_mm,
            &cfg.mechanics,
        );
        let base_px = pins_g.iter().map(|g| proj.project(*g)).collect();
        let rim = cfg.mechanics.rim_clamp_mm;
        let clamp = pins_g
            .iter()
            .map(|g| (1.0 - (g[0].hypot(g[1]) / rim).powi(2)).max(0.0))
            .collect();
        Self {
            lift_gain: cfg.mechanics.lift_gain,
            cfg,
            proj,
            pins_g,
            rest_px,
            base_px,
            clamp,
            radii_px,
            contact,
            correction: None,
        }
    }

    /// The configuration the model was built from.
    pub fn config(&self) -> &TacTipConfig {
        &self.cfg
    }

    /// Rest pin centres, px, image coordinates.
    pub fn rest_pins(&self) -> &[[f64; 2]] {
        &self.rest_px
    }

    /// This model with a calibrated correction of its pin field (the pins
    /// must be the measured rest pins the correction was fitted against,
    /// in their order: [`Self::with_rest_pins`]).
    pub fn with_correction(mut self, c: crate::FieldCorrection) -> Result<Self, SensorError> {
        if c.pins() != self.rest_px.len() {
            return Err(SensorError::Correction {
                reason: format!(
                    "fitted for {} pins, the sensor has {}",
                    c.pins(),
                    self.rest_px.len()
                ),
            });
        }
        self.correction = Some(std::sync::Arc::new(c));
        Ok(self)
    }

    /// The pins a tap shows the camera: `pins` (from [`Self::pins`] or
    /// [`Self::edge_tap_pins`]) moved by the calibrated correction, if any.
    pub fn seen_pins(&self, pins: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
        match &self.correction {
            Some(c) => c.apply(&self.rest_px, &pins),
            None => pins,
        }
    }

    /// Rendered pin radii, px (grow outwards with the camera's perspective).
    pub fn pin_radii(&self) -> &[f64] {
        &self.radii_px
    }

    /// Frame size (width, height), px.
    pub fn image_size(&self) -> (u32, u32) {
        (self.cfg.camera.width, self.cfg.camera.height)
    }

    /// True pin centres (px) for the sensor tip at `tip` (work frame: x, y
    /// mm; z = height of the dome's lowest point above the object's top
    /// face, negative = indentation depth; rz = sensor yaw, deg) over the
    /// extruded `shape`. `shear` is an optional slide (sensor frame) made
    /// while in contact. Eqs. S4-S8a.
    pub fn pins(&self, shape: &Contour, tip: Pose, shear: Option<Shear>) -> Vec<[f64; 2]> {
        if tip.z >= 0.0 {
            return self.rest_px.clone();
        }
        self.pins_sdf(&|p| shape.signed_distance(p), tip, shear)
    }

    /// As [`Self::pins`] for any object given by its signed distance in the
    /// plane (mm, negative inside), e.g. an infinite straight edge.
    pub fn pins_sdf(
        &self,
        sd: &dyn Fn(Vec2) -> f64,
        tip: Pose,
        shear: Option<Shear>,
    ) -> Vec<[f64; 2]> {
        let field = self.contact.field(sd, tip);
        let mech = &self.cfg.mechanics;
        match (mech.slip_law, shear) {
            (SlipLaw::Brush, Some(s)) => {
                let slip = self.brush_slip(&self.path_contact(sd, tip, s), mech);
                self.compose_slip(&field, Some(&slip))
            }
            _ => self.compose(&field, mech, shear),
        }
    }

    /// The contact along the slide `shear` that ends at `tip` (eq. B1).
    pub(crate) fn path_contact(
        &self,
        sd: &dyn Fn(Vec2) -> f64,
        tip: Pose,
        shear: Shear,
    ) -> crate::contact::PathContact {
        let path = slide_path(tip, shear, self.cfg.mechanics.brush_steps);
        let mut contact = self.contact.path_contact(sd, &path);
        contact.path = path;
        contact
    }

    /// The pins' slip (mm on the skin) by the brush law (eqs. B1-B3) with
    /// the brush parameters of `mech`.
    pub(crate) fn brush_slip(
        &self,
        contact: &crate::contact::PathContact,
        mech: &Mechanics,
    ) -> Vec<[f64; 2]> {
        let b = bristles(
            &contact.horiz,
            &contact.pens,
            &contact.path,
            mech.brush_slip_ratio,
        );
        let (spread, total) = self.contact.spread_bristles(&b);
        let profile: Vec<f64> = self
            .pins_g
            .iter()
            .map(|g| lag_profile(mech, g[0].hypot(g[1])))
            .collect();
        brush_slip(
            &spread,
            total,
            &profile,
            (mech.brush_local_gain, mech.brush_skin_gain),
        )
    }

    /// Contact state of a tap without slip (eqs. S4-S6), for fits that
    /// vary only the slip law.
    pub(crate) fn contact_field(&self, sd: &dyn Fn(Vec2) -> f64, tip: Pose) -> ContactField {
        self.contact.field(sd, tip)
    }

    /// Pin centres (px) from a contact state and the slide: the gel flow
    /// and lift held by the rim clamp (eqs. S6, S8, S8a) plus the skin's
    /// stick-slip (eq. S7, with the slip parameters of `mech`).
    pub(crate) fn compose(
        &self,
        field: &ContactField,
        mech: &Mechanics,
        shear: Option<Shear>,
    ) -> Vec<[f64; 2]> {
        let slip = shear.map(|s| slip_field(mech, &self.pins_g, field.state(), s));
        self.compose_slip(field, slip.as_deref())
    }

    /// Pin centres (px) from a contact state and the pins' slip (mm on
    /// the skin): eqs. S6, S8, S8a plus the slip, which the rim clamp
    /// does not scale.
    pub(crate) fn compose_slip(
        &self,
        field: &ContactField,
        slip: Option<&[[f64; 2]]>,
    ) -> Vec<[f64; 2]> {
        let slip_of = |i: usize| slip.map_or([0.0; 2], |v| v[i]);
        self.rest_px
            .iter()
            .zip(self.pins_g.iter().zip(&self.base_px))
            .zip(field.disp.iter().zip(&field.smoothed))
            .zip(&self.clamp)
            .enumerate()
            .map(|(i, (((rest, (g, base)), (u, lift)), k))| {
                let w = slip_of(i);
                if u[0] == 0.0 && u[1] == 0.0 && *lift == 0.0 && w == [0.0; 2] {
                    return *rest;
                }
                let u = [k * u[0] + w[0], k * u[1] + w[1]];
                let lift = k * self.lift_gain * lift;
                let moved = self.proj.project_lifted([g[0] + u[0], g[1] + u[1]], lift);
                [rest[0] + moved[0] - base[0], rest[1] + moved[1] - base[1]]
            })
            .collect()
    }

    /// Render pins (one per rest pin, same order) as a frame of
    /// anti-aliased discs; with `rng`, add the configured pin jitter and
    /// image noise; then binarise when `camera.binarise_above` is set (the
    /// default, as the real frames are).
    pub fn render(&self, pins: &[[f64; 2]], rng: Option<&mut ChaCha8Rng>) -> Frame {
        let (w, h) = self.image_size();
        let mut frame = Frame::new(w, h);
        let nuisance = &self.cfg.nuisance;
        match rng {
            Some(rng) => {
                let moved = jitter(pins, nuisance.pin_jitter_px, rng);
                self.draw(&mut frame, &moved);
                if nuisance.image_noise_std > 0.0 {
                    add_noise(&mut frame, nuisance.image_noise_std, rng);
                }
            }
            None => self.draw(&mut frame, pins),
        }
        if let Some(level) = self.cfg.camera.binarise_above {
            for px in frame.iter_mut() {
                *px = if *px > level { 255 } else { 0 };
            }
        }
        frame
    }

    fn draw(&self, frame: &mut Frame, pins: &[[f64; 2]]) {
        let fallback = self.radii_px.first().copied().unwrap_or(2.0);
        for (i, p) in pins.iter().enumerate() {
            let r = self.radii_px.get(i).copied().unwrap_or(fallback);
            draw_disc(frame, *p, r);
        }
    }
}

/// For each measured rest pin, the index of the model pin it is (greedy
/// nearest pairs in the image; every pair must be closer than half the
/// local pin spacing). Either layout: no two pins are closer on the skin
/// than one spacing `s`, and each has a neighbour within 1.05 `s` (eq. S1:
/// the lattice, exactly `s`; eq. S1r: rings `s` apart, and on ring k the
/// chord 2 k s sin(30 / k deg) between `s` and pi `s` / 3).
pub(crate) fn match_rest_pins(
    proj: &Projection,
    layout: &[[f64; 2]],
    geometry: &SkinGeometry,
    rest_px: &[[f64; 2]],
) -> Result<Vec<usize>, SensorError> {
    let expected = layout.len();
    let mismatch = |reason: String| SensorError::RestPins {
        expected,
        got: rest_px.len(),
        reason,
    };
    if rest_px.len() != expected {
        return Err(mismatch("wrong number of pins".into()));
    }
    if let Some(i) = rest_px
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(mismatch(format!("pin {i} is not a finite position")));
    }
    let model: Vec<[f64; 2]> = layout.iter().map(|g| proj.project(*g)).collect();
    let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(expected * expected);
    for (i, p) in rest_px.iter().enumerate() {
        for (k, q) in model.iter().enumerate() {
            pairs.push(((p[0] - q[0]).hypot(p[1] - q[1]), i, k));
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut of_measured = vec![usize::MAX; expected];
    let mut taken = vec![false; expected];
    for (d, i, k) in pairs {
        if of_measured[i] != usize::MAX || taken[k] {
            continue;
        }
        let limit = 0.5 * proj.scale(layout[k]) * geometry.pin_spacing_mm;
        if d > limit {
            return Err(mismatch(format!(
                "measured pin {i} at ({:.1}, {:.1}) px is {d:.1} px from its nearest free model pin (limit {limit:.1} px); check the camera calibration and the pin layout (the model's is a {})",
                rest_px[i][0],
                rest_px[i][1],
                geometry.layout.describe()
            )));
        }
        of_measured[i] = k;
        taken[k] = true;
    }
    Ok(of_measured)
}
