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
//!
//! Poses are 6-DoF: the rotation step is the angle of the relative
//! rotation (any tilt), and the clamp turns along the shortest rotation.
//! An optional largest tilt ([`LimitedArm::with_max_tilt_deg`]) bounds
//! the angle of the tool's z axis from the work frame's ([`tilt_deg`]):
//! refused, or levelled the least way ([`level_to`]) when clamping.
use crate::tilt::{level_to, tilt_deg};
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
    max_tilt_deg: Option<f64>,
}

impl<A: Arm> LimitedArm<A> {
    /// Wrap `inner`. The workspace is validated on every move (an invalid
    /// one makes every move an [`ArmError::InvalidConfig`]).
    pub fn new(inner: A, workspace: Workspace, mode: LimitMode) -> Self {
        Self {
            inner,
            workspace,
            mode,
            max_tilt_deg: None,
        }
    }
    /// Also bound the tool's tilt to `max_deg` (in (0, 180]; checked on
    /// every move as the workspace is). Without it any tilt is allowed.
    pub fn with_max_tilt_deg(mut self, max_deg: f64) -> Self {
        self.max_tilt_deg = Some(max_deg);
        self
    }
    /// The largest tilt allowed, if bounded.
    pub fn max_tilt_deg(&self) -> Option<f64> {
        self.max_tilt_deg
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
        let max_tilt = self.checked_max_tilt()?;
        match self.mode {
            LimitMode::Refuse => {
                self.workspace.check_move(current, target)?;
                check_tilt(*target, max_tilt)?;
                Ok(target)
            }
            LimitMode::Clamp => {
                let levelled = FinitePose::new(level_to(*target, max_tilt))?;
                let moved = self.clamp(current, levelled, max_tilt)?;
                check_tilt(*moved, max_tilt)?;
                Ok(moved)
            }
        }
    }

    /// The tilt bound in force (180 deg when unbounded), checked.
    fn checked_max_tilt(&self) -> Result<f64, ArmError> {
        match self.max_tilt_deg {
            None => Ok(180.0),
            Some(value) if value > 0.0 && value <= 180.0 => Ok(value),
            Some(value) => Err(ArmError::InvalidConfig {
                field: "max_tilt_deg",
                value,
                reason: "must be in (0, 180]",
            }),
        }
    }

    /// Project into the box, then shorten the translation and the rotation
    /// (the turn stopped earlier where it would tilt beyond `max_tilt`).
    /// With `current` inside the box the result stays inside (the box is
    /// convex and the shortened step lies on the segment to the clamped
    /// target); a result outside the box (the arm was outside it), or a
    /// step too long to measure (overflow to infinity), is refused.
    fn clamp(
        &self,
        current: FinitePose,
        target: FinitePose,
        max_tilt: f64,
    ) -> Result<FinitePose, ArmError> {
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
            let t = self.workspace.max_step_deg / step_deg;
            turn_within_tilt(*current, boxed, t, max_tilt)
        } else if tilt_deg(boxed) <= max_tilt + SLACK {
            [boxed.rx, boxed.ry, boxed.rz]
        } else {
            turn_within_tilt(*current, boxed, 1.0, max_tilt)
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

/// Refuses a pose tilted by more than `max_deg` (a NaN tilt refuses).
fn check_tilt(pose: Pose, max_deg: f64) -> Result<(), ArmError> {
    let tilt = tilt_deg(pose);
    if tilt <= max_deg + SLACK {
        Ok(())
    } else {
        Err(ArmError::TiltTooLarge {
            tilt_deg: tilt,
            max_deg,
        })
    }
}

/// The orientation (Euler degrees) a fraction `t` of the shortest turn
/// from `from` to `to`, or, when that tilts beyond `max_tilt`, the
/// furthest fraction of it found by bisection that does not (the start
/// itself when it is already beyond: the move is then refused).
fn turn_within_tilt(from: Pose, to: Pose, t: f64, max_tilt: f64) -> [f64; 3] {
    let (q0, q1) = (rotation(from), rotation(to));
    let at = |t: f64| {
        let (rx, ry, rz) = q0.try_slerp(&q1, t, 1e-12).unwrap_or(q1).euler_angles();
        [rx.to_degrees(), ry.to_degrees(), rz.to_degrees()]
    };
    let tilt = |o: [f64; 3]| tilt_deg(Pose::new(0.0, 0.0, 0.0, o[0], o[1], o[2]));
    let end = at(t);
    if tilt(end) <= max_tilt + SLACK {
        return end;
    }
    let (mut lo, mut hi) = (0.0, t);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if tilt(at(mid)) <= max_tilt {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    if lo == 0.0 {
        [from.rx, from.ry, from.rz]
    } else {
        at(lo)
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
