//! Safety by wrapping: a workspace box and step limits around any [`Arm`].
//!
//! [`LimitedArm`] checks every move before the wrapped arm sees it. In
//! [`LimitMode::Refuse`] an offending move is an error and the arm stays
//! put; in [`LimitMode::Clamp`] the target is projected into the box and
//! the step shortened (translation and rotation separately) along the same
//! direction, so a runaway controller slows down instead of stopping.
//!
//! Every comparison is written so that a NaN refuses: a move passes only
//! when `step <= max` holds (false for NaN), never because `step > max`
//! failed (also false for NaN). Both the target and the arm's current pose
//! must be finite ([`FinitePose`]) before anything is compared: a NaN in
//! either is an error, never a move.
use crate::{Arm, ArmError, FinitePose};
use nalgebra::UnitQuaternion;
use serde::{Deserialize, Serialize};
use tactrace_geometry::Pose;

/// Slack on the limits so targets exactly on a bound are accepted.
const SLACK: f64 = 1e-9;
const AXES: [char; 3] = ['x', 'y', 'z'];

/// The box the sensor tip may visit and the largest single move (work frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Workspace {
    /// Lower corner (x, y, z), mm.
    pub min: [f64; 3],
    /// Upper corner (x, y, z), mm.
    pub max: [f64; 3],
    /// Largest straight-line move of the tip per command, mm.
    pub max_step_mm: f64,
    /// Largest rotation of the tool per command, degrees.
    pub max_step_deg: f64,
}

impl Default for Workspace {
    /// A box around the report's objects (all within x in [-70, 65],
    /// y in [-115, 10] mm) with room for the approach and for taps below
    /// the top face; steps up to 25 mm and 90 deg.
    fn default() -> Self {
        Self {
            min: [-250.0, -300.0, -30.0],
            max: [250.0, 200.0, 150.0],
            max_step_mm: 25.0,
            max_step_deg: 90.0,
        }
    }
}

impl Workspace {
    /// Check that the limits are finite, ordered and the steps positive.
    pub fn validate(&self) -> Result<(), ArmError> {
        for k in 0..3 {
            if !(self.min[k].is_finite() && self.max[k].is_finite() && self.min[k] <= self.max[k]) {
                return Err(ArmError::InvalidConfig {
                    field: ["min/max x", "min/max y", "min/max z"][k],
                    value: self.min[k],
                    reason: "bounds must be finite with min <= max",
                });
            }
        }
        for (field, value) in [
            ("max_step_mm", self.max_step_mm),
            ("max_step_deg", self.max_step_deg),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ArmError::InvalidConfig {
                    field,
                    value,
                    reason: "must be finite and > 0",
                });
            }
        }
        Ok(())
    }

    /// The first axis on which `pose` is outside the box (a NaN
    /// coordinate is outside).
    pub fn check_inside(&self, pose: Pose) -> Result<(), ArmError> {
        let p = [pose.x, pose.y, pose.z];
        for k in 0..3 {
            let inside = p[k] >= self.min[k] - SLACK && p[k] <= self.max[k] + SLACK;
            if !inside {
                return Err(ArmError::OutsideWorkspace {
                    pose,
                    axis: AXES[k],
                    value_mm: p[k],
                    min_mm: self.min[k],
                    max_mm: self.max[k],
                });
            }
        }
        Ok(())
    }

    /// The rule of [`LimitMode::Refuse`] for one move from `current` to
    /// `target`: the target inside the box, the straight-line step and the
    /// rotation within the step limits. `tactrace rig check` applies it to
    /// the move to the start, as `follow` will.
    pub fn check_move(&self, current: FinitePose, target: FinitePose) -> Result<(), ArmError> {
        self.check_inside(*target)?;
        let step_mm = current.distance(*target);
        let short = step_mm <= self.max_step_mm + SLACK;
        if !short {
            return Err(ArmError::StepTooLarge {
                step_mm,
                max_mm: self.max_step_mm,
            });
        }
        let step_deg = current.angle_to(*target);
        let small = step_deg <= self.max_step_deg + SLACK;
        if !small {
            return Err(ArmError::RotationTooLarge {
                step_deg,
                max_deg: self.max_step_deg,
            });
        }
        Ok(())
    }

    /// `pose` with its position projected into the box.
    pub fn clamp(&self, pose: Pose) -> Pose {
        Pose {
            x: pose.x.clamp(self.min[0], self.max[0]),
            y: pose.y.clamp(self.min[1], self.max[1]),
            z: pose.z.clamp(self.min[2], self.max[2]),
            ..pose
        }
    }
}

/// What to do with a move that breaks a limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LimitMode {
    /// Return an error; the arm does not move.
    #[default]
    Refuse,
    /// Move as far as the limits allow towards the target.
    Clamp,
}

/// Any arm behind a workspace and step limiter.
#[derive(Debug)]
pub struct LimitedArm<A: Arm> {
    inner: A,
    workspace: Workspace,
    mode: LimitMode,
}

impl<A: Arm> LimitedArm<A> {
    /// Wrap `inner`. The workspace is validated on every move (an invalid
    /// one makes every move an [`ArmError::InvalidConfig`]).
    pub fn new(inner: A, workspace: Workspace, mode: LimitMode) -> Self {
        Self {
            inner,
            workspace,
            mode,
        }
    }
    /// The wrapped arm.
    pub fn inner(&self) -> &A {
        &self.inner
    }
    /// The wrapped arm, mutably (moves made through it bypass the limits).
    pub fn inner_mut(&mut self) -> &mut A {
        &mut self.inner
    }
    /// Unwrap.
    pub fn into_inner(self) -> A {
        self.inner
    }
    /// The limits in force.
    pub fn workspace(&self) -> &Workspace {
        &self.workspace
    }
    /// Refuse or clamp.
    pub fn mode(&self) -> LimitMode {
        self.mode
    }

    /// The move the limits allow towards `target` (Refuse: `target` or an
    /// error). A non-finite target, or a non-finite current pose of the
    /// wrapped arm, is an error in both modes.
    pub fn limit(&self, target: Pose) -> Result<FinitePose, ArmError> {
        self.workspace.validate()?;
        let target = FinitePose::new(target)?;
        let now = self.inner.pose();
        let current =
            FinitePose::new(now).map_err(|_| ArmError::CurrentPoseNotFinite { pose: now })?;
        match self.mode {
            LimitMode::Refuse => {
                self.workspace.check_move(current, target)?;
                Ok(target)
            }
            LimitMode::Clamp => self.clamp(current, target),
        }
    }

    /// Project into the box, then shorten the translation and the rotation.
    /// With `current` inside the box the result stays inside (the box is
    /// convex and the shortened step lies on the segment to the clamped
    /// target); a result outside the box (the arm was outside it), or a
    /// step too long to measure (overflow to infinity), is refused.
    fn clamp(&self, current: FinitePose, target: FinitePose) -> Result<FinitePose, ArmError> {
        let boxed = self.workspace.clamp(*target);
        let step_mm = current.distance(boxed);
        if !step_mm.is_finite() {
            return Err(ArmError::StepTooLarge {
                step_mm,
                max_mm: self.workspace.max_step_mm,
            });
        }
        let f = if step_mm > self.workspace.max_step_mm {
            self.workspace.max_step_mm / step_mm
        } else {
            1.0
        };
        let position = [
            current.x + f * (boxed.x - current.x),
            current.y + f * (boxed.y - current.y),
            current.z + f * (boxed.z - current.z),
        ];
        let step_deg = current.angle_to(boxed);
        let orientation = if step_deg > self.workspace.max_step_deg {
            let (from, to) = (rotation(*current), rotation(boxed));
            let t = self.workspace.max_step_deg / step_deg;
            let q = from.try_slerp(&to, t, 1e-12).unwrap_or(to);
            let (rx, ry, rz) = q.euler_angles();
            [rx.to_degrees(), ry.to_degrees(), rz.to_degrees()]
        } else {
            [boxed.rx, boxed.ry, boxed.rz]
        };
        let moved = FinitePose::new(Pose::new(
            position[0],
            position[1],
            position[2],
            orientation[0],
            orientation[1],
            orientation[2],
        ))?;
        self.workspace.check_inside(*moved)?;
        Ok(moved)
    }
}

fn rotation(p: Pose) -> UnitQuaternion<f64> {
    p.to_isometry().rotation
}

impl<A: Arm> Arm for LimitedArm<A> {
    fn move_to(&mut self, pose: Pose) -> Result<(), ArmError> {
        let allowed = self.limit(pose)?;
        self.inner.move_to(allowed.pose())
    }

    fn pose(&self) -> Pose {
        self.inner.pose()
    }
}
