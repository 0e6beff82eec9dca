//! The servo loop of the 3D tasks (surface_3d): tap, perceive, control in
//! SE(3), move; repeat for a path of a given number of steps.
//!
//! [`Perception3d`] maps a frame to a six-component label (x, y, z mm; rx,
//! ry, rz deg; z the depth): the pins' displacements, then a pose model of
//! N named targets, each target put in the component it names (`z`, `rx`,
//! `ry`, ... or the Bristol columns `pose_1`..`pose_6`). The
//! [`tactrace_control::Se3Controller`] turns it into the move in the sensor
//! frame; its reference's constant step along y (1 mm in the presets) is
//! the tangential motion: the sensor slides along its own y axis, which
//! the tilt corrections keep in the surface's tangent plane, so the path
//! runs straight across the surface in the start's heading (rz is not
//! sensed, so the heading is not turned), or with the controller's
//! `heading_deg` turned onto that direction of travel (the rz error then
//! read from the commanded pose: `Se3Controller::step_at`).
//!
//! The edge tasks (edge_3d, edge_5d) run the same loop: rz is sensed, so
//! the controller turns the heading onto the edge, and the constant step
//! along y carries the sensor along it; round a closed edge the loop stops
//! when the commanded path closes ([`Loop3dConfig::closure`]).
//!
//! A tap is made along the sensor's own axis: from a contact pose the arm
//! lifts `lift_mm` along the axis, moves to the next pose lifted the same,
//! and presses down to it. The loop sees only the arm's commanded pose and
//! the frames, never the sensor's true pose on the object.
use crate::error::{Result, ServoError};
use crate::metrics::ClosureDetector;
use crate::servo_loop::{Ending, LoopSummary};
use serde::Serialize;
use tactrace_arm::{Arm, ArmError, Pose};
use tactrace_control::{Se3Controller, COMPONENTS};
use tactrace_learn::PoseModel;
use tactrace_sensor::{Frame, TactileSensor};
use tactrace_vision::PinExtractor;

/// Pin extraction and a pose model whose named targets are components of
/// the six-component label.
pub struct Perception3d {
    /// `None` when the taps come as displacement vectors (a bank of real
    /// frames read by import).
    extractor: Option<PinExtractor>,
    reference_pins: Vec<[f64; 2]>,
    model: PoseModel,
    /// For each model output, its component (0..6).
    components: Vec<usize>,
    contact_threshold_px: f64,
}

/// The component (0..6) a target named `name` is: `x`, `y`, `z`, `rx`,
/// `ry`, `rz` (case-insensitive, a unit suffix `_mm` / `_deg` allowed) or
/// the Bristol columns `pose_1`..`pose_6`.
pub fn component_of(name: &str) -> Option<usize> {
    let n = name.trim().to_ascii_lowercase();
    let n = n
        .strip_suffix("_mm")
        .or_else(|| n.strip_suffix("_deg"))
        .unwrap_or(&n);
    if let Some(k) = n.strip_prefix("pose_") {
        return k
            .parse::<usize>()
            .ok()
            .filter(|k| (1..=6).contains(k))
            .map(|k| k - 1);
    }
    COMPONENTS.iter().position(|c| *c == n)
}

impl Perception3d {
    /// Pair `extractor` with `model`, whose every target must name a
    /// component, once, among those `sensed` (bad input otherwise).
    pub fn new(
        extractor: PinExtractor,
        model: PoseModel,
        sensed: [bool; 6],
        contact_threshold_px: f64,
    ) -> Result<Self> {
        let pins = extractor.tracker.reference().to_vec();
        let mut p = Self::of_fields(pins, model, sensed, contact_threshold_px)?;
        p.extractor = Some(extractor);
        Ok(p)
    }

    /// As [`Self::new`] for taps given as displacement vectors against
    /// `reference_pins` ([`Self::perceive_field`]); frames are refused.
    pub fn of_fields(
        reference_pins: Vec<[f64; 2]>,
        model: PoseModel,
        sensed: [bool; 6],
        contact_threshold_px: f64,
    ) -> Result<Self> {
        let got = 2 * reference_pins.len();
        if model.input_dim() != got {
            return Err(ServoError::InputSize {
                expected: model.input_dim(),
                got,
            });
        }
        let mut components = Vec::new();
        for t in model.outputs() {
            let k = component_of(&t.name).ok_or_else(|| {
                ServoError::Config(format!(
                    "the model's target `{}` names no pose component (x, y, z, rx, ry, rz)",
                    t.name
                ))
            })?;
            if components.contains(&k) || !sensed[k] {
                return Err(ServoError::Config(format!(
                    "the model's target `{}` is {} twice or not sensed by the task",
                    t.name, COMPONENTS[k]
                )));
            }
            components.push(k);
        }
        let missing: Vec<&str> = (0..6)
            .filter(|k| sensed[*k] && !components.contains(k))
            .map(|k| COMPONENTS[k])
            .collect();
        if !missing.is_empty() {
            return Err(ServoError::Config(format!(
                "the model predicts no {} (the task senses them)",
                missing.join(", ")
            )));
        }
        Ok(Self {
            extractor: None,
            reference_pins,
            model,
            components,
            contact_threshold_px,
        })
    }

    /// The reference pins (px) the displacement vectors are ordered by.
    pub fn reference_pins(&self) -> &[[f64; 2]] {
        &self.reference_pins
    }

    /// The displacement vector of a frame, its mean pin displacement (px)
    /// and the label it predicts (unsensed components 0).
    pub fn perceive(&self, frame: &Frame) -> Result<Sensed> {
        let Some(extractor) = &self.extractor else {
            return Err(ServoError::Config(
                "this perception takes displacement vectors, not frames".into(),
            ));
        };
        let tracked = extractor.extract(frame)?;
        self.perceive_field(tracked.displacement(&self.reference_pins))
    }

    /// What a displacement vector (x of every reference pin, then y; px)
    /// tells: as [`Self::perceive`] after the pins are read.
    pub fn perceive_field(&self, field: Vec<f32>) -> Result<Sensed> {
        if field.len() != 2 * self.reference_pins.len() {
            return Err(ServoError::InputSize {
                expected: 2 * self.reference_pins.len(),
                got: field.len(),
            });
        }
        let p = field.len() / 2;
        let mean = (0..p)
            .map(|i| f64::hypot(field[i] as f64, field[p + i] as f64))
            .sum::<f64>()
            / p.max(1) as f64;
        let out = self.model.predict_targets(&field)?;
        let mut label = [0.0; 6];
        for (k, v) in self.components.iter().zip(out) {
            label[*k] = v;
        }
        Ok(Sensed {
            label,
            mean_displacement_px: mean,
            contact: mean >= self.contact_threshold_px,
            field,
        })
    }
}

/// What one tap told the controller.
#[derive(Debug, Clone)]
pub struct Sensed {
    /// The predicted label (x, y, z mm; rx, ry, rz deg), z the depth.
    pub label: [f64; 6],
    pub mean_displacement_px: f64,
    pub contact: bool,
    /// The pins' displacements (x of every pin, then y), px.
    pub field: Vec<f32>,
}

/// One step of the 3D loop.
#[derive(Debug, Clone, Serialize)]
pub struct Step3d {
    pub step: usize,
    /// The commanded contact pose of the tap (work frame).
    pub pose: Pose,
    /// The predicted label.
    pub label: [f64; 6],
    pub mean_displacement_px: f64,
    pub contact: bool,
    /// The move in the sensor frame (mm; rotation vector, deg).
    pub u: [f64; 6],
}

/// How long to run and when a tap counts as contact.
#[derive(Debug, Clone, Serialize)]
pub struct Loop3dConfig {
    /// Steps of the path.
    pub steps: usize,
    /// Taps in a row without contact before stopping safely.
    pub max_no_contact: usize,
    /// Lift between taps, along the sensor's axis, mm.
    pub lift_mm: f64,
    /// Stop when the commanded path closes (edge tasks round a closed
    /// edge): the [`ClosureDetector`] of the 2D loop on the poses' (x, y),
    /// with this radius and minimum excursion, mm; `None`: run every step.
    pub closure: Option<[f64; 2]>,
}

/// `pose` moved `height_mm` back along its own z axis (away from the
/// surface): where a tap along the sensor's axis starts.
pub fn lifted(pose: Pose, height_mm: f64) -> Pose {
    let up = Pose::new(0.0, 0.0, height_mm, 0.0, 0.0, 0.0).to_isometry();
    Pose::from_isometry(&(pose.to_isometry() * up))
}

/// Whether an arm error is the limiter refusing a move.
fn refused(e: &ArmError) -> bool {
    matches!(
        e,
        ArmError::OutsideWorkspace { .. }
            | ArmError::StepTooLarge { .. }
            | ArmError::RotationTooLarge { .. }
            | ArmError::TiltTooLarge { .. }
            | ArmError::NonFinitePose { .. }
    )
}

/// Run the surface loop from the arm's current (contact) pose; `sink`
/// hears every step with the tap's pin field.
pub fn servo_loop_3d(
    arm: &mut dyn Arm,
    sensor: &mut dyn TactileSensor,
    perception: &Perception3d,
    controller: &mut Se3Controller,
    cfg: &Loop3dConfig,
    sink: &mut dyn FnMut(&Step3d, &[f32]) -> Result<()>,
) -> Result<LoopSummary> {
    let mut tap = || {
        let frame = sensor.capture().map_err(ServoError::from)?;
        perception.perceive(&frame)
    };
    servo_loop_3d_taps(arm, &mut tap, controller, cfg, sink)
}

/// [`servo_loop_3d`] with each tap's percept from `tap` (called at the
/// arm's pose after each move): the real-frame world answers it from a
/// bank of read frames.
pub fn servo_loop_3d_taps(
    arm: &mut dyn Arm,
    tap: &mut dyn FnMut() -> Result<Sensed>,
    controller: &mut Se3Controller,
    cfg: &Loop3dConfig,
    sink: &mut dyn FnMut(&Step3d, &[f32]) -> Result<()>,
) -> Result<LoopSummary> {
    if cfg.steps == 0 || cfg.max_no_contact == 0 || !cfg.lift_mm.is_finite() || cfg.lift_mm < 0.0 {
        return Err(ServoError::Config(
            "steps and max_no_contact must be at least 1, lift_mm >= 0".into(),
        ));
    }
    let stop = |step: usize, ending, message: String| Ok(LoopSummary::new(step, ending, message));
    let mut no_contact = 0;
    let mut closure = cfg.closure.map(|[r, m]| ClosureDetector::new(r, m));
    for step in 0..cfg.steps {
        let pose = arm.pose();
        let sensed = match tap() {
            Ok(s) => s,
            Err(e) => return stop(step, Ending::Fault, format!("stopped at step {step}: {e}")),
        };
        no_contact = if sensed.contact { 0 } else { no_contact + 1 };
        let u = if sensed.contact {
            controller.observe_contact(sensed.mean_displacement_px);
            match controller.step_at(pose, sensed.label) {
                Ok(u) => u,
                Err(e) => return stop(step, Ending::Fault, format!("stopped at step {step}: {e}")),
            }
        } else {
            // No contact: press 1 mm further along the axis, keep the heading.
            [0.0, 0.0, -1.0, 0.0, 0.0, 0.0]
        };
        let rec = Step3d {
            step,
            pose,
            label: sensed.label,
            mean_displacement_px: sensed.mean_displacement_px,
            contact: sensed.contact,
            u,
        };
        sink(&rec, &sensed.field)?;
        if no_contact >= cfg.max_no_contact {
            let m = format!("lost the surface: {no_contact} taps without contact at step {step}");
            return stop(step + 1, Ending::LostContact, m);
        }
        let closed = closure
            .as_mut()
            .is_some_and(|c| c.observe(tactrace_geometry::Vec2::new(pose.x, pose.y)));
        if closed {
            let m = format!("closed the loop after {} steps", step + 1);
            return stop(step + 1, Ending::Closed, m);
        }
        if step + 1 == cfg.steps {
            break;
        }
        let next = tactrace_control::apply_servo(pose, u);
        let moved = arm
            .move_to(lifted(pose, cfg.lift_mm))
            .and_then(|()| arm.move_to(lifted(next, cfg.lift_mm)))
            .and_then(|()| arm.move_to(next));
        match moved {
            Ok(()) => {}
            Err(e) if refused(&e) => {
                let m = format!("stopped safely at step {step}: {e}");
                return stop(step + 1, Ending::Refused, m);
            }
            Err(e) => {
                let m = format!("stopped at step {step}: the arm failed: {e}");
                return stop(step + 1, Ending::Fault, m);
            }
        }
    }
    let n = cfg.steps;
    if cfg.closure.is_some() {
        let m = format!("the path did not close in {n} steps (the step cap)");
        return stop(n, Ending::StepCap, m);
    }
    stop(
        n,
        Ending::StepsDone,
        format!("ran the {n} steps of the path"),
    )
}
