//! The `Arm` trait.
use crate::ArmError;
use tactrace_geometry::Pose;

/// A robot arm carrying the tactile sensor at its tool centre point.
///
/// Poses are of the sensor tip (centre-bottom of the dome) in the work
/// frame: mm and degrees (see [`Pose`]); z is the height of the tip above
/// the object's top face. All moves block until the arm has stopped.
pub trait Arm {
    /// Move linearly to `pose` (work frame, mm/deg); blocks until reached.
    fn move_to(&mut self, pose: Pose) -> Result<(), ArmError>;
    /// The commanded pose most recently reached, as the controller knows it
    /// (the arm's own reading; in simulation the commanded pose, not the
    /// physically perturbed one).
    fn pose(&self) -> Pose;
    /// Tap: move straight down by `depth_mm` along the work z axis, blocking.
    fn tap_down(&mut self, depth_mm: f64) -> Result<(), ArmError> {
        let p = self.pose();
        self.move_to(Pose {
            z: p.z - depth_mm,
            ..p
        })
    }
    /// Undo a tap: move straight up by `depth_mm`, blocking.
    fn tap_up(&mut self, depth_mm: f64) -> Result<(), ArmError> {
        let p = self.pose();
        self.move_to(Pose {
            z: p.z + depth_mm,
            ..p
        })
    }
}
