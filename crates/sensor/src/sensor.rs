//! The tactile sensor interface the servo loop talks to, independent of
//! whether frames come from the simulated TacTip, saved files or hardware.
use crate::SensorError;

/// One tactile frame: 8-bit grey, white pins on black, pixel (x, y) has its
/// centre at image coordinates (x, y).
pub type Frame = image::GrayImage;

/// A source of tactile frames (simulated TacTip, replayed files, camera).
pub trait TactileSensor {
    /// Capture one frame now, blocking until it is available: the sensor's
    /// current deformation, in pixels of the sensor's camera.
    fn capture(&mut self) -> Result<Frame, SensorError>;
}
