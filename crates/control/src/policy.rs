//! Beyond the report's fixed gains (issue 12): a curvature estimate from
//! the controller's own moves and predictions, the edge-position reference
//! shifted with it, and a tangential step that shortens on tight turns.
//!
//! # Why
//! A pose model trained on a gently curved edge (the disk, radius 55 mm)
//! reads a tight turn as a straight edge: its contact patch, about 10 mm
//! across, averages over the turn. Measured on the star
//! r = 35 + 7 cos 5 phi with the report's gains, the model says r = 0 while
//! the sensor is 2.8 mm outside a valley (concave radius 5.3 mm) and 1.5 mm
//! inside a tip (convex radius 8.1 mm): the error grows like c kappa with
//! c of 12-15 mm^2 (kappa the signed curvature, 1/mm, positive convex).
//!
//! # Curvature estimate (sensor data only)
//! The edge normal's heading in the work frame is the commanded yaw minus
//! the predicted theta. Between two taps it turns by
//! dpsi = rz(previous move) - (theta_k - theta_(k-1)) over the distance
//! ds = |(x, y)(previous move)|, so kappa_k = dpsi / ds. The estimate is
//! smoothed exponentially: kappa <- kappa + w (kappa_k - kappa).
//! Nothing here sees the true pose: only the commanded moves and the
//! predictions.
//!
//! # Use
//! - Reference shift: s*_x = clamp(c kappa, +-`max_offset_mm`), so the loop
//!   aims where the biased model's r = 0 is not the edge.
//! - Adaptive step: s*_y = step / (1 + L |kappa| + |theta| / theta_s),
//!   at least `min_step_fraction` of the step: short steps where the edge
//!   turns fast or the sensor is badly aligned (a corner just reached).
//!
//! All gains zero (the default): the report's PBTS exactly.
use serde::{Deserialize, Serialize};

/// Curvature compensation and adaptive step (the `[controller.policy]`
/// table); zero gains switch each part off.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PolicyConfig {
    /// c: the r reference moves by c kappa, mm^2 (0: off).
    pub curvature_offset_mm2: f64,
    /// The largest reference shift, mm.
    pub max_offset_mm: f64,
    /// w: weight of the newest tap in the smoothed curvature, in (0, 1].
    pub curvature_smoothing: f64,
    /// L: the step is divided by 1 + L |kappa|, mm (0: off).
    pub step_curvature_mm: f64,
    /// theta_s: the step is divided by 1 + |theta| / theta_s too, degrees
    /// (0: off).
    pub step_angle_deg: f64,
    /// The step never falls below this fraction of s*_y, in (0, 1].
    pub min_step_fraction: f64,
    /// k_c: the step is divided by 1 + k_c |ln(d / d_typ)| too, d the
    /// tap's mean pin displacement and d_typ its running geometric mean
    /// over the run: a contact unlike the usual ones (a corner, a lift-off)
    /// takes a short step (0: off).
    pub step_contact: f64,
}

impl Default for PolicyConfig {
    fn default() -> Self {
        Self {
            curvature_offset_mm2: 0.0,
            max_offset_mm: 3.0,
            curvature_smoothing: 0.3,
            step_curvature_mm: 0.0,
            step_angle_deg: 0.0,
            min_step_fraction: 0.2,
            step_contact: 0.0,
        }
    }
}

impl PolicyConfig {
    /// Whether every part is off (the report's controller).
    pub fn is_off(&self) -> bool {
        self.curvature_offset_mm2 == 0.0
            && self.step_curvature_mm == 0.0
            && self.step_angle_deg == 0.0
            && self.step_contact == 0.0
    }

    /// The settings as (name, value) for validation.
    pub(crate) fn values(&self) -> [(&'static str, f64); 7] {
        [
            ("policy.curvature_offset_mm2", self.curvature_offset_mm2),
            ("policy.max_offset_mm", self.max_offset_mm),
            ("policy.curvature_smoothing", self.curvature_smoothing),
            ("policy.step_curvature_mm", self.step_curvature_mm),
            ("policy.step_angle_deg", self.step_angle_deg),
            ("policy.min_step_fraction", self.min_step_fraction),
            ("policy.step_contact", self.step_contact),
        ]
    }

    /// Why the settings cannot work, if they cannot.
    pub(crate) fn problem(&self) -> Option<String> {
        if let Some((name, v)) = self.values().into_iter().find(|(_, v)| !v.is_finite()) {
            return Some(format!("{name} = {v} is not finite"));
        }
        if !(self.curvature_smoothing > 0.0 && self.curvature_smoothing <= 1.0) {
            return Some("policy.curvature_smoothing must be in (0, 1]".into());
        }
        if !(self.min_step_fraction > 0.0 && self.min_step_fraction <= 1.0) {
            return Some("policy.min_step_fraction must be in (0, 1]".into());
        }
        let negative = [
            ("policy.max_offset_mm", self.max_offset_mm),
            ("policy.step_curvature_mm", self.step_curvature_mm),
            ("policy.step_angle_deg", self.step_angle_deg),
            ("policy.step_contact", self.step_contact),
        ];
        negative
            .into_iter()
            .find(|(_, v)| *v < 0.0)
            .map(|(name, v)| format!("{name} = {v} must be >= 0"))
    }
}

/// Largest curvature the estimate keeps, 1/mm (a 0.5 mm radius): a turn
/// measured over a tiny move is noise.
const MAX_CURVATURE_PER_MM: f64 = 2.0;
/// Moves shorter than this (mm) say nothing about curvature.
const MIN_MOVE_MM: f64 = 0.05;

/// The smoothed curvature estimate; the controller keeps one.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CurvatureEstimate {
    /// Smoothed signed curvature, 1/mm (positive: convex, turning
    /// counter-clockwise as the sensor goes round).
    pub kappa_per_mm: f64,
    /// The last move (x, y mm; rz deg) and predicted theta (deg).
    last: Option<([f64; 3], f64)>,
    pending_theta: Option<f64>,
}

impl CurvatureEstimate {
    /// Take the latest predicted theta (deg), before the controller moves.
    pub fn observe(&mut self, theta_deg: f64, smoothing: f64) {
        if let (Some((mv, theta_prev)), true) = (self.last, self.pending_theta.is_none()) {
            let ds = mv[0].hypot(mv[1]);
            if ds >= MIN_MOVE_MM {
                let dpsi = (mv[2] - (theta_deg - theta_prev)).to_radians();
                let k = (dpsi / ds).clamp(-MAX_CURVATURE_PER_MM, MAX_CURVATURE_PER_MM);
                self.kappa_per_mm += smoothing * (k - self.kappa_per_mm);
            }
        }
        self.pending_theta = Some(theta_deg);
    }

    /// Record the move commanded after the last observation.
    pub fn moved(&mut self, x_mm: f64, y_mm: f64, rz_deg: f64) {
        if let Some(theta) = self.pending_theta.take() {
            self.last = Some(([x_mm, y_mm, rz_deg], theta));
        }
    }
}

/// Weight of the newest tap in the running mean of ln d.
const CONTACT_SMOOTHING: f64 = 0.1;

/// How unlike the run's usual contacts a tap is, from its mean pin
/// displacement d (px) alone: the controller keeps one.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactTypicality {
    /// Running mean of ln d over the contacts so far.
    log_mean: Option<f64>,
}

impl ContactTypicality {
    /// |ln(d / d_typ)| for this tap (0 for the first, or a non-positive
    /// d), then d joins the running mean.
    pub fn novelty(&mut self, d_px: f64) -> f64 {
        if !(d_px.is_finite() && d_px > 0.0) {
            return 0.0;
        }
        let ln = d_px.ln();
        let mean = self.log_mean.unwrap_or(ln);
        self.log_mean = Some(mean + CONTACT_SMOOTHING * (ln - mean));
        (ln - mean).abs()
    }
}

impl PolicyConfig {
    /// The r reference for the estimated curvature, mm.
    pub fn r_reference_mm(&self, kappa_per_mm: f64) -> f64 {
        (self.curvature_offset_mm2 * kappa_per_mm).clamp(-self.max_offset_mm, self.max_offset_mm)
    }

    /// The fraction of the tangential step to take, in
    /// [`min_step_fraction`](PolicyConfig::min_step_fraction), 1], for the
    /// curvature, the misalignment and the contact's novelty
    /// ([`ContactTypicality::novelty`]).
    pub fn step_fraction(&self, kappa_per_mm: f64, theta_deg: f64, novelty: f64) -> f64 {
        let angle = if self.step_angle_deg > 0.0 {
            theta_deg.abs() / self.step_angle_deg
        } else {
            0.0
        };
        let slow =
            1.0 + self.step_curvature_mm * kappa_per_mm.abs() + angle + self.step_contact * novelty;
        (1.0 / slow).clamp(self.min_step_fraction, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steady_turn_is_measured_as_its_curvature() {
        // Going round a circle of radius 10 mm with perfect alignment:
        // each 1 mm move turns the sensor by 1/10 rad, theta stays 0.
        let mut est = CurvatureEstimate::default();
        let turn = (0.1f64).to_degrees();
        for _ in 0..40 {
            est.observe(0.0, 0.3);
            est.moved(0.0, 1.0, turn);
        }
        assert!(
            (est.kappa_per_mm - 0.1).abs() < 1e-6,
            "{}",
            est.kappa_per_mm
        );
        // The same turn seen as theta growing instead (the sensor not
        // turning) is a turn of the edge too, the other way.
        let mut est = CurvatureEstimate::default();
        for k in 0..40 {
            est.observe(-(k as f64) * turn, 0.3);
            est.moved(0.0, 1.0, 0.0);
        }
        assert!(
            (est.kappa_per_mm - 0.1).abs() < 1e-6,
            "{}",
            est.kappa_per_mm
        );
    }

    #[test]
    fn the_step_shortens_with_curvature_and_misalignment() {
        let p = PolicyConfig {
            step_curvature_mm: 10.0,
            step_angle_deg: 10.0,
            min_step_fraction: 0.2,
            ..PolicyConfig::default()
        };
        assert_eq!(p.step_fraction(0.0, 0.0, 0.0), 1.0);
        assert!((p.step_fraction(0.1, 0.0, 0.0) - 0.5).abs() < 1e-12);
        assert!((p.step_fraction(-0.1, 10.0, 0.0) - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(p.step_fraction(5.0, 90.0, 0.0), 0.2);
        assert_eq!(PolicyConfig::default().step_fraction(1.0, 45.0, 0.0), 1.0);
        let contact = PolicyConfig {
            step_contact: 2.0,
            ..PolicyConfig::default()
        };
        assert!((contact.step_fraction(0.0, 0.0, 0.5) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_contact_unlike_the_usual_ones_is_novel() {
        let mut c = ContactTypicality::default();
        assert_eq!(c.novelty(5.0), 0.0);
        for _ in 0..50 {
            c.novelty(5.0);
        }
        assert!(c.novelty(5.0) < 1e-9, "the usual contact is not novel");
        let weak = c.novelty(2.5);
        assert!((weak - 2f64.ln()).abs() < 1e-9, "{weak}");
        assert_eq!(c.novelty(0.0), 0.0);
        assert!(PolicyConfig::default().is_off());
    }

    #[test]
    fn the_reference_shift_is_clipped() {
        let p = PolicyConfig {
            curvature_offset_mm2: 15.0,
            max_offset_mm: 2.0,
            ..PolicyConfig::default()
        };
        assert!((p.r_reference_mm(0.1) - 1.5).abs() < 1e-12);
        assert_eq!(p.r_reference_mm(-1.0), -2.0);
        assert!(p.problem().is_none());
        let bad = PolicyConfig {
            curvature_smoothing: 0.0,
            ..p
        };
        assert!(bad.problem().unwrap().contains("curvature_smoothing"));
    }
}
