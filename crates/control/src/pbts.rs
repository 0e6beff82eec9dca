//! Pose-based tactile servo (PBTS) control, report ch. 5.1 with the ERRATA.
//!
//! # Frames and signs
//! The sensor frame S sits at the centre-bottom of the dome: x along the
//! edge normal pointing out of the object, y along the edge (x, y, z right
//! handed with z up, so +y runs counter-clockwise around the object seen
//! from above), z up. The pose model measures
//! - `r`: the signed x coordinate of the sensor centre relative to the edge,
//!   mm; r > 0 when the centre is outside the object;
//! - `theta`: the sensor's yaw relative to the edge-aligned frame, degrees
//!   (positive = turned counter-clockwise from the outward normal).
//!
//! so s(m) = (r, 0, 0, 0, 0, theta) (eq. 5.3). With the reference
//! s* = (0, 1, 0, 0, 0, 0) (eq. 5.4) the error e = s* - s(m) (eq. 5.2)
//! makes the move -Kp r along x (back onto the edge), -Kp theta about z
//! (re-aligned with the normal) and +Kp 1 mm along y (the tangential step).
//!
//! # Control law
//! delta_s = Kp e + Ki F(sum e) + Kd (e - e_prev) (eq. 5.5), with gains
//! diagonal (eq. 5.6) and F clipping each component of the running sum to
//! +-`integral_clip` (the anti-windup; ERRATA: +-5 mm in x, +-45 deg about z).
//! Following the ERRATA, the default K_i has a zero y entry (the report's
//! K_i y = 1 would integrate the constant 1 mm y error into an ever-growing
//! step). The derivative term is the report's further work, off by default;
//! it is zero on the first step after a reset (no derivative kick).
//! The move delta_s is applied in the sensor frame by [`next_pose`]
//! (eq. 5.7-5.8).
use crate::policy::{ContactTypicality, CurvatureEstimate, PolicyConfig};
use crate::ControlError;
use serde::{Deserialize, Serialize};
use tactrace_arm::Pose;

/// The pose model's prediction for one tap.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SensedPose {
    /// Signed distance of the sensor centre from the edge along the
    /// outward normal, mm (positive outside the object).
    pub r_mm: f64,
    /// Sensor yaw relative to the edge normal, degrees.
    pub theta_deg: f64,
}

impl SensedPose {
    /// s(m) = (r, 0, 0, 0, 0, theta), eq. 5.3 (mm, mm, mm, deg, deg, deg).
    pub fn as_vector(self) -> [f64; 6] {
        [self.r_mm, 0.0, 0.0, 0.0, 0.0, self.theta_deg]
    }
}

/// Reference, gains and anti-windup bounds; all vectors are
/// (x, y, z mm; rx, ry, rz deg) in the sensor frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PbtsConfig {
    /// Reference pose s*, eq. 5.4; `reference[1]` is the tangential step, mm.
    pub reference: [f64; 6],
    /// Proportional gains, diagonal of K_p (eq. 5.6).
    pub kp: [f64; 6],
    /// Integral gains, diagonal of K_i (eq. 5.6 with the ERRATA's K_i y = 0).
    pub ki: [f64; 6],
    /// Derivative gains (further work; zero = PI control as in the report).
    pub kd: [f64; 6],
    /// Anti-windup F: each integral component is clipped to +-this.
    pub integral_clip: [f64; 6],
    /// Curvature compensation and adaptive step (issue 12; off by default).
    pub policy: PolicyConfig,
}

impl Default for PbtsConfig {
    fn default() -> Self {
        Self {
            reference: [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            kp: [0.5, 1.0, 0.0, 0.0, 0.0, 0.5],
            ki: [0.3, 0.0, 0.0, 0.0, 0.0, 0.1],
            kd: [0.0; 6],
            integral_clip: [5.0, 5.0, 5.0, 45.0, 45.0, 45.0],
            policy: PolicyConfig::default(),
        }
    }
}

impl PbtsConfig {
    /// The report's controller (ch. 5.1 with the ERRATA; the policy off):
    /// the [`Default`], what `reproduce` and a real rig run.
    pub fn report() -> Self {
        Self::default()
    }

    /// The controller tuned in simulation (issue 12, docs/control.md
    /// "Tuned defaults"): `tactrace tune --trials 300 --seed 1` from the
    /// report's controller on the training contours, then a refining
    /// `--config configs/tune-refine.toml --trials 150 --seed 2` from that,
    /// with a PDenNN trained on the disk (docs/results.md); retuned the
    /// same refining way (seed 3) when the simulated sensor became the
    /// transfer-fitted one (issue 11). The simulated world's default.
    pub fn tuned() -> Self {
        Self {
            reference: [0.0, TUNED[0], 0.0, 0.0, 0.0, 0.0],
            kp: [TUNED[1], 1.0, 0.0, 0.0, 0.0, TUNED[4]],
            ki: [TUNED[2], 0.0, 0.0, 0.0, 0.0, TUNED[5]],
            kd: [TUNED[3], 0.0, 0.0, 0.0, 0.0, TUNED[6]],
            integral_clip: [5.0, 5.0, 5.0, 45.0, 45.0, 45.0],
            policy: PolicyConfig {
                curvature_offset_mm2: TUNED[7],
                max_offset_mm: TUNED[8],
                curvature_smoothing: TUNED[9],
                step_curvature_mm: TUNED[10],
                step_angle_deg: TUNED[11],
                min_step_fraction: TUNED[12],
                step_contact: 0.0,
            },
        }
    }

    /// The report's eq. 5.6 as printed (K_i y = 1); see the ERRATA for why
    /// it is not the default.
    pub fn as_printed() -> Self {
        Self {
            ki: [0.3, 1.0, 0.0, 0.0, 0.0, 0.1],
            ..Self::default()
        }
    }

    /// Check that every value is finite and the clip bounds non-negative.
    pub fn validate(&self) -> Result<(), ControlError> {
        let vectors = [
            ("reference", &self.reference),
            ("kp", &self.kp),
            ("ki", &self.ki),
            ("kd", &self.kd),
            ("integral_clip", &self.integral_clip),
        ];
        for (field, values) in vectors {
            if let Some(index) = values.iter().position(|v| !v.is_finite()) {
                return Err(ControlError::NonFinite { field, index });
            }
        }
        if let Some(index) = self.integral_clip.iter().position(|v| *v < 0.0) {
            return Err(ControlError::NegativeClip {
                field: "integral_clip",
                index,
                value: self.integral_clip[index],
            });
        }
        match self.policy.problem() {
            Some(reason) => Err(ControlError::Policy { reason }),
            None => Ok(()),
        }
    }
}

/// [`PbtsConfig::tuned`]'s values, rounded to 4 significant digits:
/// retuned on the transfer-fitted sensor (issue 11) by a refining search
/// from the previous tuned values (`tactrace tune --config
/// configs/tune-refine.toml --trials 150 --seed 3`, docs/results.md):
/// step (mm), Kp x, Ki x, Kd x, Kp rz, Ki rz, Kd rz, then the policy's
/// curvature_offset_mm2, max_offset_mm, curvature_smoothing,
/// step_curvature_mm, step_angle_deg, min_step_fraction.
const TUNED: [f64; 13] = [
    0.7110, 0.1292, 0.04531, 0.03255, 0.6294, 0.09844, 0.3677, 5.893, 1.903, 0.9044, 14.18, 61.27,
    0.2203,
];

/// The discrete PI(D) controller of eq. 5.5; keeps only the running
/// integral and the previous error.
#[derive(Debug, Clone, PartialEq)]
pub struct PbtsController {
    config: PbtsConfig,
    integral: [f64; 6],
    previous_error: Option<[f64; 6]>,
    curvature: CurvatureEstimate,
    contact: ContactTypicality,
    /// Novelty of the latest contact ([`PbtsController::observe_contact`]).
    contact_novelty: f64,
}

impl PbtsController {
    /// A controller with zero integral. Call [`PbtsConfig::validate`] (or use
    /// [`PbtsController::try_new`]) on user settings: with non-finite gains
    /// the moves are non-finite (and refused by the arm); a negative clip
    /// bound acts as its absolute value.
    pub fn new(config: PbtsConfig) -> Self {
        Self {
            config,
            integral: [0.0; 6],
            previous_error: None,
            curvature: CurvatureEstimate::default(),
            contact: ContactTypicality::default(),
            contact_novelty: 0.0,
        }
    }

    /// A controller from validated settings.
    pub fn try_new(config: PbtsConfig) -> Result<Self, ControlError> {
        config.validate()?;
        Ok(Self::new(config))
    }

    /// The settings in force.
    pub fn config(&self) -> &PbtsConfig {
        &self.config
    }

    /// The clipped running sum F(sum e) after the last step. Components
    /// with a zero integral gain are not accumulated and stay 0.
    pub fn integral(&self) -> [f64; 6] {
        self.integral
    }

    /// The smoothed edge curvature estimated from the moves and
    /// predictions so far, 1/mm (0 while the policy is off).
    pub fn curvature_per_mm(&self) -> f64 {
        self.curvature.kappa_per_mm
    }

    /// Forget the integral, the previous error and the curvature estimate.
    pub fn reset(&mut self) {
        self.integral = [0.0; 6];
        self.previous_error = None;
        self.curvature = CurvatureEstimate::default();
        self.contact = ContactTypicality::default();
        self.contact_novelty = 0.0;
    }

    /// Take the mean pin displacement (px) of the tap the next step
    /// answers: the policy's step shortens for contacts unlike the run's
    /// usual ones (`policy.step_contact`). Without it the novelty is 0.
    pub fn observe_contact(&mut self, mean_displacement_px: f64) {
        self.contact_novelty = self.contact.novelty(mean_displacement_px);
    }

    /// One control step: the sensor-frame move delta_s (x, y, z mm; rx, ry,
    /// rz deg) for the latest prediction, eq. 5.2-5.6.
    ///
    /// A non-finite prediction leaves the state untouched and returns a
    /// pose of NaNs (which an arm refuses); see [`PbtsController::try_step`].
    pub fn step(&mut self, sensed: SensedPose) -> Pose {
        self.try_step(sensed)
            .unwrap_or_else(|_| Pose::from_array([f64::NAN; 6]))
    }

    /// [`PbtsController::step`] that reports a non-finite prediction as an error.
    pub fn try_step(&mut self, sensed: SensedPose) -> Result<Pose, ControlError> {
        if !(sensed.r_mm.is_finite() && sensed.theta_deg.is_finite()) {
            return Err(ControlError::NonFiniteInput {
                r_mm: sensed.r_mm,
                theta_deg: sensed.theta_deg,
            });
        }
        let c = &self.config;
        let mut error = self.error(sensed);
        if !c.policy.is_off() {
            self.curvature
                .observe(sensed.theta_deg, c.policy.curvature_smoothing);
            let kappa = self.curvature.kappa_per_mm;
            error[0] += c.policy.r_reference_mm(kappa);
            error[1] *= c
                .policy
                .step_fraction(kappa, sensed.theta_deg, self.contact_novelty);
        }
        let previous = self.previous_error.unwrap_or(error);
        let mut delta = [0.0; 6];
        for k in 0..6 {
            if c.ki[k] != 0.0 {
                self.integral[k] = anti_windup(self.integral[k] + error[k], c.integral_clip[k]);
            }
            delta[k] = c.kp[k] * error[k]
                + c.ki[k] * self.integral[k]
                + c.kd[k] * (error[k] - previous[k]);
        }
        self.previous_error = Some(error);
        self.curvature.moved(delta[0], delta[1], delta[5]);
        Ok(Pose::from_array(delta))
    }

    /// e = s* - s(m), eq. 5.2 with eq. 5.3 (before the policy's reference
    /// shift and step scaling).
    pub fn error(&self, sensed: SensedPose) -> [f64; 6] {
        let s = sensed.as_vector();
        std::array::from_fn(|k| self.config.reference[k] - s[k])
    }
}

/// F of eq. 5.5: clip to +-`bound` (a negative bound acts as its absolute value).
fn anti_windup(value: f64, bound: f64) -> f64 {
    let bound = bound.abs();
    value.max(-bound).min(bound)
}

/// The next commanded pose: the sensor-frame move `delta` applied at
/// `current` (work frame), eq. 5.7-5.8: position Q dtau Q* + tau and
/// orientation E(H(Q, dQ)), i.e. `current.compose(delta)`.
pub fn next_pose(current: Pose, delta: Pose) -> Pose {
    current.compose(delta)
}
