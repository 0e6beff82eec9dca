//! The servo loop of report ch. 5: tap, perceive, control, move; repeat.
//!
//! [`follow`] is one function over an injected arm, sensor, perception
//! (pin extraction + pose model) and controller. It reports every step to
//! [`StepSink`]s (trajectory file, progress bar, in-memory history).
//!
//! Invariant: the loop sees only the arm's own commanded pose and the
//! sensor's frames. It never reads the true pose of the sensor relative to
//! the object; loop closure is detected from the commanded trajectory alone.
use crate::error::{LabError, Result};
use crate::metrics::ClosureDetector;
use crate::rig::TapConfig;
use serde::{Deserialize, Serialize};
use tactrace_arm::{Arm, ArmError, Pose};
use tactrace_control::{PbtsController, SensedPose};
use tactrace_geometry::Vec2;
use tactrace_learn::PoseModel;
use tactrace_sensor::{Frame, TactileSensor};
use tactrace_vision::PinExtractor;

/// Frame -> (r, theta): pin extraction then the pose model.
pub struct Perception {
    pub extractor: PinExtractor,
    pub model: PoseModel,
    /// Below this mean pin displacement (px) a tap counts as no contact.
    pub contact_threshold_px: f64,
}

/// What one tap told the controller.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Percept {
    pub r_mm: f64,
    pub theta_deg: f64,
    /// Mean pin displacement, px.
    pub mean_displacement_px: f64,
    pub contact: bool,
    pub missing_pins: usize,
}

impl Perception {
    /// Extract pins and predict the edge pose from one frame.
    pub fn perceive(&self, frame: &Frame) -> Result<Percept> {
        let tracked = self.extractor.extract(frame)?;
        let disp = tracked.displacement(self.extractor.tracker.reference());
        let p = disp.len() / 2;
        let mean = (0..p)
            .map(|i| f64::hypot(disp[i] as f64, disp[p + i] as f64))
            .sum::<f64>()
            / p.max(1) as f64;
        let [r, theta] = self.model.predict(&disp)?;
        Ok(Percept {
            r_mm: r,
            theta_deg: theta,
            mean_displacement_px: mean,
            contact: mean >= self.contact_threshold_px,
            missing_pins: tracked.missing,
        })
    }
}

/// When to stop following.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FollowConfig {
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
    /// Seed of the tap-depth variation.
    pub seed: u64,
}

impl Default for FollowConfig {
    fn default() -> Self {
        Self {
            steps: None,
            max_steps: 1500,
            close_radius_mm: 3.0,
            min_excursion_mm: 20.0,
            max_no_contact: 3,
            seed: 1,
        }
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
    fn on_step(&mut self, rec: &StepRecord) -> Result<()>;
}

impl StepSink for Vec<StepRecord> {
    fn on_step(&mut self, rec: &StepRecord) -> Result<()> {
        self.push(*rec);
        Ok(())
    }
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
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
}

/// Summary of a run.
#[derive(Debug, Clone, Serialize)]
pub struct FollowSummary {
    pub steps: usize,
    pub ending: Ending,
    pub closed: bool,
    /// Why the run ended, for people.
    pub message: String,
}

impl FollowSummary {
    fn new(steps: usize, ending: Ending, message: String) -> Self {
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
pub fn follow(
    arm: &mut dyn Arm,
    sensor: &mut dyn TactileSensor,
    perception: &Perception,
    controller: &mut PbtsController,
    cfg: &FollowConfig,
    tap: &TapConfig,
    sinks: &mut [&mut dyn StepSink],
) -> Result<FollowSummary> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(cfg.seed);
    let limit = cfg.steps.unwrap_or(cfg.max_steps);
    let mut closure = ClosureDetector::new(cfg.close_radius_mm, cfg.min_excursion_mm);
    let mut no_contact = 0usize;
    for step in 0..limit {
        let pose = arm.pose();
        let depth = tap.depth_mm + rng.random_range(-1.0..=1.0) * tap.depth_jitter_mm;
        let frame = crate::rig::tap(arm, sensor, depth)?;
        let percept = perception.perceive(&frame)?;
        no_contact = if percept.contact { 0 } else { no_contact + 1 };
        let delta = if percept.contact {
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
            sink.on_step(&rec)?;
        }
        if no_contact >= cfg.max_no_contact {
            let message = format!(
                "lost the object: {no_contact} taps in a row without contact; stopped at step {step}"
            );
            return Ok(FollowSummary::new(step + 1, Ending::LostContact, message));
        }
        if closure.observe(Vec2::new(pose.x, pose.y)) && cfg.steps.is_none() {
            let message = format!("the loop closed after {} steps", step + 1);
            return Ok(FollowSummary::new(step + 1, Ending::Closed, message));
        }
        if step + 1 < limit {
            match arm.move_to(tactrace_control::next_pose(pose, delta)) {
                Ok(()) => {}
                Err(
                    e @ (ArmError::OutsideWorkspace { .. }
                    | ArmError::StepTooLarge { .. }
                    | ArmError::RotationTooLarge { .. }
                    | ArmError::NonFinitePose { .. }),
                ) => {
                    let message = format!("stopped safely at step {step}: {e}");
                    return Ok(FollowSummary::new(step + 1, Ending::Refused, message));
                }
                Err(e) => return Err(e.into()),
            }
        }
    }
    Ok(if cfg.steps.is_some() {
        FollowSummary::new(
            limit,
            Ending::StepsDone,
            format!("ran the {limit} requested steps"),
        )
    } else {
        let message = format!("reached the step cap of {limit} without closing the loop");
        FollowSummary::new(limit, Ending::StepCap, message)
    })
}

/// Reject a follow configuration that cannot run.
pub fn check_follow_config(cfg: &FollowConfig) -> Result<()> {
    if cfg.steps == Some(0) || cfg.max_steps == 0 {
        return Err(LabError::Config(
            "the number of steps must be at least 1".into(),
        ));
    }
    if !(cfg.close_radius_mm > 0.0 && cfg.min_excursion_mm > cfg.close_radius_mm) {
        return Err(LabError::Config(
            "need 0 < close_radius_mm < min_excursion_mm".into(),
        ));
    }
    Ok(())
}
