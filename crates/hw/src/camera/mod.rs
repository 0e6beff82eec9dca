//! The TacTip's USB camera behind the `TactileSensor` trait.
//!
//! A [`CameraSensor`] grabs a raw image from a [`FrameSource`] and turns it
//! into the binary frame the vision stage expects (white pins on black,
//! pixels of the preprocessed image) with the Bristol pipeline in
//! [`Preprocess`].

mod preprocess;
mod sources;
mod threshold;
pub mod v4l2;

#[cfg(test)]
mod tests;

use std::path::PathBuf;

use image::GrayImage;
use tactrace_sensor::{Frame, SensorError, TactileSensor};

pub use preprocess::{crop_checked, opencv_gray, resize_area, Preprocess, PreprocessConfig};
pub use sources::{
    natural_cmp, open_image, CommandSource, CommandSourceConfig, FolderSource, FrameSource,
    OUTPUT_PLACEHOLDER,
};
pub use threshold::{
    adaptive_threshold, box_mean, gaussian_mean, median_blur, opencv_sigma, ThresholdMethod,
};

use crate::HwError;

/// A tactile sensor made of a frame source and the TacTip preprocessing.
#[derive(Debug, Clone)]
pub struct CameraSensor<S: FrameSource> {
    source: S,
    preprocess: Preprocess,
    captured: usize,
}

impl<S: FrameSource> CameraSensor<S> {
    /// A sensor over `source` with checked preprocessing.
    pub fn new(source: S, preprocess: Preprocess) -> Self {
        Self {
            source,
            preprocess,
            captured: 0,
        }
    }

    /// One preprocessed frame; blocks as long as the source's `grab`.
    pub fn capture_frame(&mut self) -> Result<GrayImage, HwError> {
        let raw = self.source.grab()?;
        let frame = self.preprocess.apply(&raw)?;
        self.captured += 1;
        Ok(frame)
    }

    /// Frames captured so far.
    pub fn captured(&self) -> usize {
        self.captured
    }

    /// The preprocessing in use.
    pub fn preprocess(&self) -> &Preprocess {
        &self.preprocess
    }

    /// The frame source.
    pub fn source_mut(&mut self) -> &mut S {
        &mut self.source
    }
}

impl<S: FrameSource> TactileSensor for CameraSensor<S> {
    /// Grabs and preprocesses one frame, blocking like the source.
    fn capture(&mut self) -> Result<Frame, SensorError> {
        self.capture_frame().map_err(to_sensor_error)
    }
}

/// Maps hardware errors onto the sensor crate's variants. The sensor crate
/// has no camera/hardware variant, so failures that are not about a file
/// are reported as an unreadable frame of the pseudo-path "camera".
fn to_sensor_error(err: HwError) -> SensorError {
    match err {
        HwError::Exhausted { count } => SensorError::ReplayExhausted { count },
        HwError::Image { path, source } => SensorError::CorruptFrame {
            path,
            reason: source.to_string(),
        },
        other => SensorError::FrameUnreadable {
            path: PathBuf::from("camera"),
            reason: other.to_string(),
        },
    }
}
