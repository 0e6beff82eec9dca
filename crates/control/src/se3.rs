//! Pose-based tactile servoing in SE(3): the controller of the field's
//! surface and edge tasks, with the report's planar loop as its special case.
//!
//! # Poses and the error
//! A prediction s and the reference s* are six components (x, y, z mm;
//! rx, ry, rz deg) of the sensor's pose relative to the feature frame F
//! (origin on the surface or edge, z along the outward normal), with two
//! conventions of the field's labels: the rotations are extrinsic x-y-z
//! Euler angles (as [`Pose`]) and z is the *depth*, positive into the
//! surface, so the sensor frame sits at z = -depth in F. Components a
//! [`Task`] does not sense are 0 in s ([`Task::fill`]).
//!
//! The error is the relative transform of the prediction from the
//! reference, E = T(s*)^-1 T(s) (the predicted pose seen from the
//! reference's frame), negated: e = -(t_E, rotvec(R_E)), translation in mm
//! and the rotation vector in degrees. With an unrotated reference this is
//! e = (t* - t, -rotvec(R)): in the plane (s = (r, 0, 0, 0, 0, theta),
//! s* = (0, 1, 0, 0, 0, 0)) exactly the report's e = s* - s (eq. 5.2-5.3).
//! The z component is along the sensor frame's z (up): depth minus the
//! reference depth. An unsensed component's error is the reference's own
//! (the error for a zero prediction): zero where the reference is zero,
//! the constant tangential step where it is not (y).
//!
//! # Control law and the move
//! u = Kp e + Ki F(sum e) + Kd (e - e_prev), per component, F clipping each
//! component of the running sum (anti-windup), as eq. 5.5; a component
//! with a zero integral gain is not accumulated. The servo transform T(u)
//! (translation u[0..3] mm, rotation the rotation vector u[3..6] deg) is
//! applied in the sensor frame: the new pose = current * T(u), a
//! quaternion composition (eq. 5.7-5.8).
//!
//! # Bounded moves and a held heading
//! Two optional settings beyond the field's controller. `move_clip`
//! bounds each component of u to +-its value (mm, deg) after the law: a
//! controller's choice of how far one step may go (a misread tap then
//! turns or shifts the sensor by at most the bound, and the next tap
//! corrects it), apart from the arm's step limits, which stay the safety
//! check. `heading_deg` (tasks that do not sense rz: surface_3d) is a
//! direction of travel in the work frame's xy plane: the rz error is then
//! the angle about the sensor's axis from its y axis (the tangential step)
//! to the line of the sensor's plane that runs over that direction seen
//! from above, read from the commanded pose ([`heading_error_deg`]), with
//! the rz gains.
//!
//! # The curvature policy in the edge's plane
//! `policy` (the `[controller.policy]` table, off by default) is the 2D
//! controller's ([`crate::policy`]) acting on the edge tasks' plane: the
//! predicted rz stands for the report's theta (eq. 5.3) and the move's x,
//! y and rz for the planar move, so the curvature estimate, the x
//! reference shift c kappa and the shortened tangential step are the 2D
//! ones. The step's contact term takes the tap's mean pin displacement
//! ([`Se3Controller::observe_contact`]). Off, every move is bit for bit
//! the controller's without it.
use crate::pbts::PbtsConfig;
use crate::policy::{ContactTypicality, CurvatureEstimate, PolicyConfig};
use crate::task::{Task, COMPONENTS};
use crate::ControlError;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use tactrace_arm::Pose;

/// Anti-windup bounds of every preset: 5 mm, 45 deg (as the report's).
const CLIP: [f64; 6] = [5.0, 5.0, 5.0, 45.0, 45.0, 45.0];

/// The edge presets' bound on a move: 20 deg of turn about the sensor's
/// axis a step (a tap whose rz is read half a turn away would otherwise
/// turn the sensor by about 90 deg); the other bounds (5 mm, 45 deg) are
/// above what the presets' gains can ask for.
pub const EDGE_MOVE_CLIP: [f64; 6] = [5.0, 5.0, 5.0, 45.0, 45.0, 20.0];

/// The SE(3) controller's settings; vectors are (x, y, z mm; rx, ry, rz
/// deg). Built by a preset, [`Se3Config::new`] or deserialised (checked
/// the same way; unknown fields refused, `kd` optional).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawSe3Config")]
pub struct Se3Config {
    /// The components the pose model senses.
    pub task: Task,
    /// The reference pose s* (z as depth, mm).
    pub reference: [f64; 6],
    /// Proportional gains.
    pub kp: [f64; 6],
    /// Integral gains.
    pub ki: [f64; 6],
    /// Derivative gains (0 for the PI controller of the field).
    pub kd: [f64; 6],
    /// Each integral component is clipped to +-this (anti-windup).
    pub integral_clip: [f64; 6],
    /// Each component of the move u is clipped to +-this (mm, deg);
    /// `None`: unbounded (the presets).
    pub move_clip: Option<[f64; 6]>,
    /// The direction of travel to hold, deg from the work frame's +x
    /// (only for a task that does not sense rz); `None`: the heading is
    /// never turned.
    pub heading_deg: Option<f64>,
    /// The 2D curvature policy in the edge's plane (edge tasks only; off
    /// by default): see the module header.
    pub policy: PolicyConfig,
}

/// The serialised form, checked on the way in.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSe3Config {
    task: Task,
    reference: [f64; 6],
    kp: [f64; 6],
    ki: [f64; 6],
    #[serde(default)]
    kd: [f64; 6],
    integral_clip: [f64; 6],
    #[serde(default)]
    move_clip: Option<[f64; 6]>,
    #[serde(default)]
    heading_deg: Option<f64>,
    #[serde(default)]
    policy: PolicyConfig,
}

impl TryFrom<RawSe3Config> for Se3Config {
    type Error = ControlError;

    fn try_from(r: RawSe3Config) -> Result<Self, ControlError> {
        let config = Self {
            task: r.task,
            reference: r.reference,
            kp: r.kp,
            ki: r.ki,
            kd: r.kd,
            integral_clip: r.integral_clip,
            move_clip: r.move_clip,
            heading_deg: r.heading_deg,
            policy: r.policy,
        };
        config.validate()?;
        Ok(config)
    }
}

impl Se3Config {
    /// A checked PI configuration (no derivative term).
    pub fn new(
        task: Task,
        reference: [f64; 6],
        kp: [f64; 6],
        ki: [f64; 6],
        integral_clip: [f64; 6],
    ) -> Result<Self, ControlError> {
        let config = Self {
            task,
            reference,
            kp,
            ki,
            kd: [0.0; 6],
            integral_clip,
            move_clip: None,
            heading_deg: None,
            policy: PolicyConfig::default(),
        };
        config.validate()?;
        Ok(config)
    }

    /// The preset of `task` (see each preset).
    pub fn for_task(task: Task) -> Self {
        match task {
            Task::Edge2d => Self::edge_2d(),
            Task::Surface3d => Self::surface_3d(),
            Task::Edge3d => Self::edge_3d(),
            Task::Edge5d => Self::edge_5d(),
        }
    }

    /// The report's planar controller ([`PbtsConfig::report`]): a 1 mm
    /// step, Kp (0.5, 1, 0.5) and Ki (0.3, 0, 0.1) on (x, y, rz).
    pub fn edge_2d() -> Self {
        Self::planar(&PbtsConfig::report()).expect("the report's controller is planar")
    }

    /// The anchors' surface_3d controller: a 1 mm step at 3 mm depth,
    /// reference (0, 1, 3, 0, 0, 0), Kp (1, 1, .5, .5, .5, 1),
    /// Ki (0, 0, .3, .1, .1, 0).
    pub fn surface_3d() -> Self {
        Self::preset(
            Task::Surface3d,
            [1.0, 1.0, 0.5, 0.5, 0.5, 1.0],
            [0.0, 0.0, 0.3, 0.1, 0.1, 0.0],
        )
    }

    /// edge_3d: the report's edge gains on x and rz with the surface
    /// gains on z (our choice, not tuned): 1 mm step at 3 mm depth, the
    /// turn bounded as edge_5d's.
    pub fn edge_3d() -> Self {
        Self {
            move_clip: Some(EDGE_MOVE_CLIP),
            ..Self::preset(
                Task::Edge3d,
                [0.5, 1.0, 0.5, 0.0, 0.0, 0.5],
                [0.3, 0.0, 0.3, 0.0, 0.0, 0.1],
            )
        }
    }

    /// edge_5d: the report's edge gains on x and rz with the anchors'
    /// surface gains on z, rx, ry (our choice, not tuned): 1 mm step at
    /// 3 mm depth; each step turns the heading by at most 20 deg
    /// ([`EDGE_MOVE_CLIP`]).
    pub fn edge_5d() -> Self {
        Self {
            move_clip: Some(EDGE_MOVE_CLIP),
            ..Self::preset(
                Task::Edge5d,
                [0.5, 1.0, 0.5, 0.5, 0.5, 0.5],
                [0.3, 0.0, 0.3, 0.1, 0.1, 0.1],
            )
        }
    }

    fn preset(task: Task, kp: [f64; 6], ki: [f64; 6]) -> Self {
        Self {
            task,
            reference: [0.0, 1.0, 3.0, 0.0, 0.0, 0.0],
            kp,
            ki,
            kd: [0.0; 6],
            integral_clip: CLIP,
            move_clip: None,
            heading_deg: None,
            policy: PolicyConfig::default(),
        }
    }

    /// The planar case of a 2D controller configuration: edge_2d with its
    /// reference, gains and clips. Refused when its curvature policy is
    /// on (the policy is a planar extension the SE(3) controller lacks).
    pub fn planar(pbts: &PbtsConfig) -> Result<Self, ControlError> {
        pbts.validate()?;
        if !pbts.policy.is_off() {
            return Err(ControlError::Policy {
                reason: "policy has no SE(3) form: turn it off for the planar case".into(),
            });
        }
        Ok(Self {
            task: Task::Edge2d,
            reference: pbts.reference,
            kp: pbts.kp,
            ki: pbts.ki,
            kd: pbts.kd,
            integral_clip: pbts.integral_clip,
            move_clip: None,
            heading_deg: None,
            policy: PolicyConfig::default(),
        })
    }

    /// Check that every value is finite, the clip bounds non-negative and
    /// a heading only set for a task that does not sense rz.
    pub fn validate(&self) -> Result<(), ControlError> {
        let heading = self.heading_deg.map(|h| [h]);
        let vectors = [
            ("reference", &self.reference[..]),
            ("kp", &self.kp[..]),
            ("ki", &self.ki[..]),
            ("kd", &self.kd[..]),
            ("integral_clip", &self.integral_clip[..]),
            (
                "move_clip",
                self.move_clip.as_ref().map_or(&[][..], |c| &c[..]),
            ),
            ("heading_deg", heading.as_ref().map_or(&[][..], |h| &h[..])),
        ];
        for (field, values) in vectors {
            if let Some(index) = values.iter().position(|v| !v.is_finite()) {
                return Err(ControlError::NonFinite { field, index });
            }
        }
        let clips = [
            ("integral_clip", Some(&self.integral_clip)),
            ("move_clip", self.move_clip.as_ref()),
        ];
        for (field, clip) in clips {
            if let Some(index) = clip.and_then(|c| c.iter().position(|v| *v < 0.0)) {
                let value = clip.map_or(0.0, |c| c[index]);
                return Err(ControlError::NegativeClip {
                    field,
                    index,
                    value,
                });
            }
        }
        if let Some(reason) = self.policy.problem() {
            return Err(ControlError::Policy { reason });
        }
        if !self.policy.is_off() && !self.task.sensed()[5] {
            return Err(ControlError::Policy {
                reason: format!(
                    "the curvature policy needs a task that senses rz; {} does not",
                    self.task
                ),
            });
        }
        if self.heading_deg.is_some() && self.task.sensed()[5] {
            return Err(ControlError::Policy {
                reason: format!(
                    "heading_deg is for tasks that do not sense rz; {} senses it",
                    self.task
                ),
            });
        }
        Ok(())
    }
}

/// The rigid transform of a label vector (z as depth): the sensor frame
/// in the feature frame.
pub fn label_to_isometry(s: [f64; 6]) -> Isometry3<f64> {
    Pose::new(s[0], s[1], -s[2], s[3], s[4], s[5]).to_isometry()
}

/// The SE(3) error of prediction `s` from reference `reference` (both
/// label vectors): -(t_E, rotvec(R_E) in deg) of E = T(s*)^-1 T(s).
pub fn se3_error(reference: [f64; 6], s: [f64; 6]) -> [f64; 6] {
    let e = label_to_isometry(reference).inverse() * label_to_isometry(s);
    let t = e.translation.vector;
    let r = e.rotation.scaled_axis();
    [
        -t.x,
        -t.y,
        -t.z,
        -r.x.to_degrees(),
        -r.y.to_degrees(),
        -r.z.to_degrees(),
    ]
}

/// The servo transform T(u): translation u[0..3] mm, rotation the
/// rotation vector u[3..6] deg.
pub fn servo_transform(u: [f64; 6]) -> Isometry3<f64> {
    let axis = Vector3::new(u[3], u[4], u[5]).map(f64::to_radians);
    Isometry3::from_parts(
        Translation3::new(u[0], u[1], u[2]),
        UnitQuaternion::from_scaled_axis(axis),
    )
}

/// The next commanded pose: the servo transform of `u` applied in the
/// sensor frame at `current` (work frame), current * T(u).
pub fn apply_servo(current: Pose, u: [f64; 6]) -> Pose {
    Pose::from_isometry(&(current.to_isometry() * servo_transform(u)))
}

/// The heading error of the sensor at `pose` (work frame) against the
/// direction of travel `heading_deg` (deg from the work frame's +x in its
/// xy plane): the signed angle, deg in (-180, 180], about the sensor's z
/// axis from its y axis to the direction in the sensor's plane that runs
/// over the heading seen from above (the plane's line within the vertical
/// plane through the heading, pointing along it). Turning the sensor by it
/// about its axis puts its tangential step over the heading. 0 when no
/// such direction exists (the axis level and across the heading).
pub fn heading_error_deg(pose: Pose, heading_deg: f64) -> f64 {
    let r = pose.to_isometry().rotation;
    let axis = r * Vector3::z();
    let y = r * Vector3::y();
    let h = heading_deg.to_radians();
    let d = Vector3::new(h.cos(), h.sin(), 0.0);
    let mut along = Vector3::z().cross(&d).cross(&axis);
    if along.norm() < 1e-9 {
        return 0.0;
    }
    if along.dot(&d) < 0.0 {
        along = -along;
    }
    y.cross(&along).dot(&axis).atan2(y.dot(&along)).to_degrees()
}

/// The discrete PI(D) controller in SE(3); keeps the running integral and
/// the previous error.
#[derive(Debug, Clone, PartialEq)]
pub struct Se3Controller {
    config: Se3Config,
    integral: [f64; 6],
    previous_error: Option<[f64; 6]>,
    curvature: CurvatureEstimate,
    contact: ContactTypicality,
    /// Novelty of the latest contact ([`Se3Controller::observe_contact`]).
    contact_novelty: f64,
}

impl Se3Controller {
    /// A controller with zero integral from checked settings.
    pub fn try_new(config: Se3Config) -> Result<Self, ControlError> {
        config.validate()?;
        Ok(Self {
            config,
            integral: [0.0; 6],
            previous_error: None,
            curvature: CurvatureEstimate::default(),
            contact: ContactTypicality::default(),
            contact_novelty: 0.0,
        })
    }

    /// The settings in force.
    pub fn config(&self) -> &Se3Config {
        &self.config
    }

    /// The clipped running sum of the errors after the last step.
    pub fn integral(&self) -> [f64; 6] {
        self.integral
    }

    /// The smoothed edge curvature estimated from the moves and
    /// predictions so far, 1/mm (0 while the policy is off).
    pub fn curvature_per_mm(&self) -> f64 {
        self.curvature.kappa_per_mm
    }

    /// Forget the integral, the previous error, the curvature estimate
    /// and the contacts seen.
    pub fn reset(&mut self) {
        self.integral = [0.0; 6];
        self.previous_error = None;
        self.curvature = CurvatureEstimate::default();
        self.contact = ContactTypicality::default();
        self.contact_novelty = 0.0;
    }

    /// Take the mean pin displacement (px) of the tap the next step
    /// answers, for the policy's contact term (`policy.step_contact`);
    /// without it the novelty is 0.
    pub fn observe_contact(&mut self, mean_displacement_px: f64) {
        self.contact_novelty = self.contact.novelty(mean_displacement_px);
    }

    /// The error of a prediction (see the module header): the SE(3) error
    /// of the task's components of `prediction`, the reference's own
    /// error on the unsensed components.
    pub fn error(&self, prediction: [f64; 6]) -> [f64; 6] {
        let task = self.config.task;
        let reference = self.config.reference;
        let sensed = task.sensed();
        let e = se3_error(reference, task.fill(prediction));
        let feed_forward = se3_error(reference, [0.0; 6]);
        std::array::from_fn(|k| if sensed[k] { e[k] } else { feed_forward[k] })
    }

    /// One control step: the move u (x, y, z mm; rotation vector deg) in
    /// the sensor frame for the latest prediction, each component within
    /// `move_clip`. A non-finite sensed component is an error and leaves
    /// the state untouched. A held heading needs the pose: see
    /// [`Se3Controller::step_at`] (here its error is 0).
    pub fn step(&mut self, prediction: [f64; 6]) -> Result<[f64; 6], ControlError> {
        self.check(prediction)?;
        let error = self.error(prediction);
        Ok(self.law_with_policy(prediction, error))
    }

    /// [`Se3Controller::step`] at the commanded pose `current` (work
    /// frame): with `heading_deg` set, the rz error is the heading's
    /// ([`heading_error_deg`] of `current`).
    pub fn step_at(
        &mut self,
        current: Pose,
        prediction: [f64; 6],
    ) -> Result<[f64; 6], ControlError> {
        self.check(prediction)?;
        let mut error = self.error(prediction);
        if let Some(heading) = self.config.heading_deg {
            error[5] = heading_error_deg(current, heading);
        }
        Ok(self.law_with_policy(prediction, error))
    }

    fn check(&self, prediction: [f64; 6]) -> Result<(), ControlError> {
        let sensed = self.config.task.sensed();
        match (0..6).find(|&k| sensed[k] && !prediction[k].is_finite()) {
            Some(k) => Err(ControlError::NonFinitePrediction {
                component: COMPONENTS[k],
                value: prediction[k],
            }),
            None => Ok(()),
        }
    }

    /// The law with the curvature policy in the edge's plane (module
    /// header): the predicted rz as theta, the x error shifted by the
    /// reference c kappa and the y step scaled, as the 2D controller's
    /// (`PbtsController::try_step`); the move then feeds the estimate.
    fn law_with_policy(&mut self, prediction: [f64; 6], mut error: [f64; 6]) -> [f64; 6] {
        let policy = &self.config.policy;
        if policy.is_off() {
            return self.law(error);
        }
        let theta = prediction[5];
        self.curvature.observe(theta, policy.curvature_smoothing);
        let kappa = self.curvature.kappa_per_mm;
        error[0] += policy.r_reference_mm(kappa);
        error[1] *= policy.step_fraction(kappa, theta, self.contact_novelty);
        let u = self.law(error);
        self.curvature.moved(u[0], u[1], u[5]);
        u
    }

    /// The PI(D) law on `error`, the move clipped.
    fn law(&mut self, error: [f64; 6]) -> [f64; 6] {
        let c = &self.config;
        let previous = self.previous_error.unwrap_or(error);
        let mut u = [0.0; 6];
        for k in 0..6 {
            if c.ki[k] != 0.0 {
                let bound = c.integral_clip[k].abs();
                self.integral[k] = (self.integral[k] + error[k]).clamp(-bound, bound);
            }
            u[k] = c.kp[k] * error[k]
                + c.ki[k] * self.integral[k]
                + c.kd[k] * (error[k] - previous[k]);
            if let Some(clip) = c.move_clip {
                u[k] = u[k].clamp(-clip[k], clip[k]);
            }
        }
        self.previous_error = Some(error);
        u
    }

    /// [`Se3Controller::step`] and the next commanded pose from `current`.
    pub fn next_pose(&mut self, current: Pose, prediction: [f64; 6]) -> Result<Pose, ControlError> {
        Ok(apply_servo(current, self.step_at(current, prediction)?))
    }
}
