//! The servo loop of report ch. 5: tap, perceive, control, move; repeat.
//!
//! [`servo_loop`] is one function over an injected arm, sensor, perception
//! (pin extraction + pose model) and controller. It reports every step to
//! [`StepSink`]s (trajectory file, progress bar, in-memory history).
//!
//! Invariant: the loop sees only the arm's own commanded pose and the
//! sensor's frames. It never reads the true pose of the sensor relative to
//! the object; loop closure is detected from the commanded trajectory alone.
//!
//! A fault during the run (a frame that cannot be read or has too few pins,
//! a non-finite prediction, an arm that stops answering) ends the run
//! safely with [`Ending::Fault`] and its reason: the steps so far are kept.
use crate::error::{Result, ServoError};
use crate::metrics::ClosureDetector;
use crate::perception::{Percept, Perception};
use crate::rig::{tap, TapConfig};
use serde::{Deserialize, Serialize};
use tactrace_arm::{Arm, ArmError, Pose};
use tactrace_control::{PbtsController, SensedPose};
use tactrace_geometry::Vec2;
use tactrace_sensor::TactileSensor;

/// When to stop, and when a tap counts as contact (the `[follow]` table).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoopConfig {
    /// Fixed number of steps (the report's counts); `None`: until the loop closes.
    pub steps: Option<usize>,
    /// Step cap when running until closure, so a lost run stays finite.
    pub max_steps: usize,
    /// Closure: a commanded move passes within this distance of the start, mm...
    pub close_radius_mm: f64,
    /// ...after having been at least this far from it, mm.
    pub min_excursion_mm: f64,
    /// Consecutive taps without contact before stopping safely.
    pub max_no_contact: usize,
    /// Mean pin displacement (px) below which a tap counts as no contact.
    pub contact_threshold_px: f64,
    /// Seed of the tap-depth variation.
    pub seed: u64,
}

impl Default for LoopConfig {
    fn default() -> Self {
        Self {
            steps: None,
            max_steps: 1500,
            close_radius_mm: 3.0,
            min_excursion_mm: 20.0,
            max_no_contact: 3,
            contact_threshold_px: 0.5,
            seed: 1,
        }
    }
}

impl LoopConfig {
    /// Reject a configuration that cannot run.
    pub fn validate(&self) -> Result<()> {
        if self.steps == Some(0) || self.max_steps == 0 {
            return Err(ServoError::Config(
                "the number of steps must be at least 1".into(),
            ));
        }
        if !(self.close_radius_mm > 0.0 && self.min_excursion_mm > self.close_radius_mm) {
            return Err(ServoError::Config(
                "need 0 < close_radius_mm < min_excursion_mm".into(),
            ));
        }
        if self.max_no_contact == 0 {
            return Err(ServoError::Config(
                "max_no_contact must be at least 1".into(),
            ));
        }
        if !(self.contact_threshold_px.is_finite() && self.contact_threshold_px >= 0.0) {
            return Err(ServoError::Config(
                "contact_threshold_px must be a finite number >= 0".into(),
            ));
        }
        Ok(())
    }

    /// The most steps a run can take.
    pub fn step_limit(&self) -> usize {
        self.steps.unwrap_or(self.max_steps)
    }
}

/// One step of the loop as the sinks see it.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StepRecord {
    pub step: usize,
    /// Commanded pose at which the tap was made.
    pub pose: Pose,
    pub percept: Percept,
    /// The move commanded in the sensor frame.
    pub delta: Pose,
}

/// Receives every step of the servo loop.
pub trait StepSink {
    /// Record one step; an error stops the run.
    fn on_step(
        &mut self,
        rec: &StepRecord,
    ) -> std::result::Result<(), Box<dyn std::error::Error + Send + Sync>>;
}

impl StepSink for Vec<StepRecord> {
    fn on_step(
        &mut self,
        rec: &StepRecord,
    ) -> std::result::Result<(), Box<dyn std::error::Error + Send + Sync>> {
        self.push(*rec);
        Ok(())
    }
}

/// A sink that calls a closure (progress bars).
pub struct FnSink<F: FnMut(&StepRecord)>(pub F);

impl<F: FnMut(&StepRecord)> StepSink for FnSink<F> {
    fn on_step(
        &mut self,
        r: &StepRecord,
    ) -> std::result::Result<(), Box<dyn std::error::Error + Send + Sync>> {
        (self.0)(r);
        Ok(())
    }
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    /// Came back to the start: the loop is closed.
    Closed,
    /// Ran the requested number of steps.
    StepsDone,
    /// Hit the step cap without closing.
    StepCap,
    /// Lost contact with the object and stopped.
    LostContact,
    /// The arm's limiter refused the next move (workspace box or step size)
    /// and the run stopped there.
    Refused,
    /// A fault (frame, pins, prediction, arm) stopped the run safely.
    Fault,
}

impl std::fmt::Display for Ending {
    /// How the run ended, in words (`lost contact`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Ending::Closed => "closed",
            Ending::StepsDone => "steps done",
            Ending::StepCap => "step cap",
            Ending::LostContact => "lost contact",
            Ending::Refused => "refused move",
            Ending::Fault => "fault",
        })
    }
}

impl Ending {
    /// Whether the run did what was asked (closed the loop or ran the
    /// requested steps); anything else is a failed run.
    pub fn succeeded(self) -> bool {
        matches!(self, Ending::Closed | Ending::StepsDone)
    }
}

/// Summary of a run.
#[derive(Debug, Clone, Serialize)]
pub struct LoopSummary {
    pub steps: usize,
    pub ending: Ending,
    pub closed: bool,
    /// Why the run ended, for people.
    pub message: String,
}

impl LoopSummary {
    pub(crate) fn new(steps: usize, ending: Ending, message: String) -> Self {
        Self {
            steps,
            ending,
            closed: ending == Ending::Closed,
            message,
        }
    }
}

/// Follow the contour from the arm's current pose (above the object,
/// roughly on an edge), tapping as `tap` says. Only the commanded pose and
/// the frames are used.
pub fn servo_loop(
    arm: &mut dyn Arm,
    sensor: &mut dyn TactileSensor,
    perception: &Perception,
    controller: &mut PbtsController,
    cfg: &LoopConfig,
    tap_cfg: &TapConfig,
    sinks: &mut [&mut dyn StepSink],
) -> Result<LoopSummary> {
    use rand::{Rng, SeedableRng};
    cfg.validate()?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(cfg.seed);
    let limit = cfg.step_limit();
    let mut closure = ClosureDetector::new(cfg.close_radius_mm, cfg.min_excursion_mm);
    let mut no_contact = 0usize;
    let fault = |step: usize, what: &str, e: &dyn std::error::Error| {
        let message = format!(
            "stopped safely at step {step}: {what}: {}",
            crate::error::error_chain(e)
        );
        Ok(LoopSummary::new(step, Ending::Fault, message))
    };
    for step in 0..limit {
        let pose = arm.pose();
        let depth = tap_cfg.depth_mm + rng.random_range(-1.0..=1.0) * tap_cfg.depth_jitter_mm;
        let frame = match tap(arm, sensor, depth) {
            Ok(f) => f,
            Err(e) => return fault(step, "the tap failed", &e),
        };
        let percept = match perception.perceive(&frame) {
            Ok(p) => p,
            Err(e) => return fault(step, "the frame could not be read", &e),
        };
        if percept.contact && !(percept.r_mm.is_finite() && percept.theta_deg.is_finite()) {
            let e = ServoError::NonFinitePrediction {
                step,
                r_mm: percept.r_mm,
                theta_deg: percept.theta_deg,
            };
            return fault(step, "perception", &e);
        }
        no_contact = if percept.contact { 0 } else { no_contact + 1 };
        let delta = if percept.contact {
            controller.observe_contact(percept.mean_displacement_px);
            controller.step(SensedPose {
                r_mm: percept.r_mm,
                theta_deg: percept.theta_deg,
            })
        } else {
            Pose::default()
        };
        let rec = StepRecord {
            step,
            pose,
            percept,
            delta,
        };
        for sink in sinks.iter_mut() {
            sink.on_step(&rec)
                .map_err(|source| ServoError::Sink { step, source })?;
        }
        if no_contact >= cfg.max_no_contact {
            let message = format!(
                "lost the object: {no_contact} taps in a row without contact; stopped at step {step}"
            );
            return Ok(LoopSummary::new(step + 1, Ending::LostContact, message));
        }
        if closure.observe(Vec2::new(pose.x, pose.y)) && cfg.steps.is_none() {
            let message = format!("the loop closed after {} steps", step + 1);
            return Ok(LoopSummary::new(step + 1, Ending::Closed, message));
        }
        if step + 1 < limit {
            match arm.move_to(tactrace_control::next_pose(pose, delta)) {
                Ok(()) => {}
                Err(
                    e @ (ArmError::OutsideWorkspace { .. }
                    | ArmError::StepTooLarge { .. }
                    | ArmError::RotationTooLarge { .. }
                    | ArmError::TiltTooLarge { .. }
                    | ArmError::NonFinitePose { .. }),
                ) => {
                    let message = format!("stopped safely at step {step}: {e}");
                    return Ok(LoopSummary::new(step + 1, Ending::Refused, message));
                }
                Err(e) => return fault(step + 1, "the arm failed", &e),
            }
        }
    }
    Ok(if cfg.steps.is_some() {
        LoopSummary::new(
            limit,
            Ending::StepsDone,
            format!("ran the {limit} requested steps"),
        )
    } else {
        let message = format!("reached the step cap of {limit} without closing the loop");
        LoopSummary::new(limit, Ending::StepCap, message)
    })
}
