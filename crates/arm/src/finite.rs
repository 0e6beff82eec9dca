//! [`FinitePose`]: a pose checked once to hold only finite numbers.
//!
//! A NaN or an infinity in a pose turns every comparison made with it
//! false (`NaN > max_step` is false too), so a limit written as "refuse
//! when larger" lets it through. The limiter, the real arm's driver and
//! `tactrace rig check` therefore work on `FinitePose`s: the check is made
//! where a pose enters (a command, a controller's state) and the type
//! carries it from there.
use std::ops::Deref;

use crate::ArmError;
use tactrace_geometry::Pose;

/// A pose (mm, degrees) whose six components are finite, by construction.
///
/// Read it through `Deref` (`p.x`) or [`FinitePose::pose`]; there is no
/// way to change a component without checking again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FinitePose(Pose);

impl FinitePose {
    /// `pose` when all six components are finite, else
    /// [`ArmError::NonFinitePose`].
    pub fn new(pose: Pose) -> Result<Self, ArmError> {
        if pose.is_finite() {
            Ok(Self(pose))
        } else {
            Err(ArmError::NonFinitePose { pose })
        }
    }

    /// The pose itself.
    pub fn pose(self) -> Pose {
        self.0
    }
}

impl Deref for FinitePose {
    type Target = Pose;

    fn deref(&self) -> &Pose {
        &self.0
    }
}

impl TryFrom<Pose> for FinitePose {
    type Error = ArmError;

    fn try_from(pose: Pose) -> Result<Self, ArmError> {
        Self::new(pose)
    }
}

impl From<FinitePose> for Pose {
    fn from(p: FinitePose) -> Pose {
        p.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_finite_poses_are_made() {
        assert!(FinitePose::new(Pose::planar(1.0, 2.0, 3.0, 4.0)).is_ok());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for k in 0..6 {
                let mut a = [0.0; 6];
                a[k] = bad;
                let err = FinitePose::new(Pose::from_array(a)).unwrap_err();
                assert!(matches!(err, ArmError::NonFinitePose { .. }), "{err}");
            }
        }
        let huge = FinitePose::new(Pose::planar(1e306, 0.0, 0.0, 1e200)).unwrap();
        assert_eq!(huge.x, 1e306);
    }
}
