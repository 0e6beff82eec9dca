//! The arm's state as the driver uses it, checked once where it enters.
//!
//! The parsers (`realtime::parse_packet`, `rtde::state_from_values`)
//! decode what the controller sent into a [`RobotState`] and refuse NaN
//! and infinity. A finite state can still be impossible: a tool 1e306 m
//! from the base overflows to infinity on the way to millimetres, and a
//! rotation vector of 1e200 rad has an infinite angle; either becomes NaN
//! in the work frame. [`ArmState::check`] refuses those as well, and it is
//! the only way the driver ([`super::Ur5Arm`], [`super::probe_state`])
//! gets a state: the state reader makes one per packet, so every pose the
//! driver derives from a state is finite by construction
//! ([`FinitePose`]). The same [`ToolPose`] check guards every `movel`
//! target before it is written.
use std::ops::Deref;

use nalgebra::Isometry3;
use tactrace_arm::FinitePose;
use tactrace_geometry::Pose;

use super::realtime::RobotState;
use super::script::{base_to_work, tool_vector_to_isometry};
use crate::HwError;

/// Farthest a TCP can plausibly be from a UR robot's base, m: the largest
/// UR arm reaches 1.75 m, and a tool adds a few tenths.
pub const MAX_REACH_M: f64 = 3.0;
/// Longest plausible rotation vector, rad: a full turn (UR controllers
/// report angles in [0, pi]; some clients in [0, 2 pi]).
pub const MAX_ROTATION_RAD: f64 = std::f64::consts::TAU + 1e-6;

/// A UR tool vector (TCP pose in the robot's base frame: x, y, z in m,
/// rotation vector in rad) that is finite and within a UR arm's reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolPose([f64; 6]);

impl ToolPose {
    /// `v` when it is a pose a UR arm can be in; `field` names it in the
    /// error ([`HwError::ImplausibleState`]).
    pub fn new(v: [f64; 6], field: &'static str) -> Result<Self, HwError> {
        let bad = |reason: String| HwError::ImplausibleState { field, reason };
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            const NAMES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];
            return Err(bad(format!("{} is {}", NAMES[k], v[k])));
        }
        let reach = length([v[0], v[1], v[2]]);
        let near = reach <= MAX_REACH_M;
        if !near {
            return Err(bad(format!(
                "its position is {} m from the robot's base, beyond the {MAX_REACH_M} m \
                 any UR arm reaches",
                amount(reach)
            )));
        }
        let angle = length([v[3], v[4], v[5]]);
        let turn = angle <= MAX_ROTATION_RAD;
        if !turn {
            return Err(bad(format!(
                "its rotation vector is {} rad long, more than a full turn",
                amount(angle)
            )));
        }
        Ok(Self(v))
    }

    /// The tool vector of a rigid transform (mm), checked.
    pub fn from_isometry(iso: &Isometry3<f64>, field: &'static str) -> Result<Self, HwError> {
        Self::new(super::script::isometry_to_tool_vector(iso), field)
    }

    /// The six numbers (m, rad).
    pub fn values(&self) -> [f64; 6] {
        self.0
    }

    /// As a rigid transform in mm.
    pub fn isometry(&self) -> Isometry3<f64> {
        tool_vector_to_isometry(self.0)
    }

    /// The pose in the work frame given as the base -> work transform
    /// `work_frame` (mm, deg; a validated `Ur5Config::work_frame`).
    pub fn in_work_frame(&self, work_frame: Pose) -> Result<FinitePose, HwError> {
        FinitePose::new(base_to_work(work_frame, &self.isometry())).map_err(|e| {
            HwError::ImplausibleState {
                field: "tool pose in the work frame",
                reason: format!("{e} (check work_frame)"),
            }
        })
    }
}

/// Euclidean length without overflow for any finite components.
fn length(v: [f64; 3]) -> f64 {
    let scale = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if scale == 0.0 {
        return 0.0;
    }
    scale * v.iter().map(|x| (x / scale).powi(2)).sum::<f64>().sqrt()
}

/// A number for a message: plain when moderate, scientific when huge.
fn amount(v: f64) -> String {
    if v.abs() < 1e6 {
        format!("{v:.3}")
    } else {
        format!("{v:.3e}")
    }
}

/// A controller state the driver may use: every number finite, the
/// actual and target TCP poses within a UR arm's reach ([`ToolPose`]).
/// Reads as a [`RobotState`] through `Deref`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmState {
    raw: RobotState,
    tool_actual: ToolPose,
    tool_target: ToolPose,
}

impl ArmState {
    /// `raw` when a UR arm can be in it, else
    /// [`HwError::ImplausibleState`] naming the field and why.
    pub fn check(raw: RobotState) -> Result<Self, HwError> {
        let finite = std::iter::once(raw.time_s)
            .chain(raw.joints_rad)
            .chain(raw.tcp_speed)
            .all(f64::is_finite);
        if !finite {
            return Err(HwError::ImplausibleState {
                field: "state",
                reason: "a time, joint angle or speed is not finite".into(),
            });
        }
        Ok(Self {
            raw,
            tool_actual: ToolPose::new(raw.tool_actual, "actual TCP pose")?,
            tool_target: ToolPose::new(raw.tool_target, "target TCP pose")?,
        })
    }

    /// The measured TCP pose in the base frame.
    pub fn tool_actual(&self) -> ToolPose {
        self.tool_actual
    }

    /// The TCP pose the controller is moving to, in the base frame.
    pub fn tool_target(&self) -> ToolPose {
        self.tool_target
    }
}

impl Deref for ArmState {
    type Target = RobotState;

    fn deref(&self) -> &RobotState {
        &self.raw
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ur5::rtde::resting_state;

    #[test]
    fn huge_or_non_finite_tool_poses_are_refused_with_the_reason() {
        let ok = resting_state();
        assert!(ArmState::check(ok).is_ok());
        let cases: [([f64; 6], &str); 4] = [
            (
                [1e306, 0.0, 0.3, 3.1, 0.0, 0.0],
                "1.000e306 m from the robot's base",
            ),
            ([0.4, 0.0, 0.3, 1e200, 0.0, 0.0], "1.000e200 rad long"),
            ([0.4, f64::NAN, 0.3, 3.1, 0.0, 0.0], "y is NaN"),
            (
                [0.0, 0.0, 3.5, 0.0, 0.0, 0.0],
                "3.500 m from the robot's base",
            ),
        ];
        for (tool, reason) in cases {
            let mut raw = ok;
            raw.tool_actual = tool;
            let err = ArmState::check(raw).unwrap_err();
            assert!(
                matches!(
                    err,
                    HwError::ImplausibleState {
                        field: "actual TCP pose",
                        ..
                    }
                ),
                "{err}"
            );
            assert!(err.to_string().contains(reason), "{err}");
        }
        // What a UR arm can report passes: 1.8 m out, a rotation of 2 pi.
        let far = ToolPose::new([1.8, 0.0, 0.0, std::f64::consts::TAU, 0.0, 0.0], "t");
        let pose = far.unwrap().in_work_frame(Pose::default()).unwrap();
        assert!((pose.x - 1800.0).abs() < 1e-9);
    }
}
