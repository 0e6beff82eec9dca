//! The TacTip's USB camera behind the `TactileSensor` trait.
//!
//! A [`CameraSensor`] grabs a raw image from a [`FrameSource`] and turns it
//! into the frame the pin detector expects (white pins on black, pixels of
//! the preprocessed image) through the one preprocessing stage every
//! command uses ([`tactrace_vision::Preprocess`], from a sensor file or
//! the rig file's `[preprocess]` table, [`PreprocessConfig`]).

mod preprocess;
mod sources;
pub mod v4l2;

#[cfg(test)]
mod tests;

use std::path::PathBuf;

use image::GrayImage;
use tactrace_sensor::{Frame, SensorError, TactileSensor};

pub use preprocess::{PreprocessConfig, ThresholdMethod};
pub use sources::{
    natural_cmp, open_image, CommandSource, CommandSourceConfig, FolderSource, FrameSource,
    OUTPUT_PLACEHOLDER,
};
pub use tactrace_vision::Preprocess;

use tactrace_vision::PreprocessStage;

use crate::HwError;

/// A tactile sensor made of a frame source and the TacTip preprocessing.
#[derive(Debug, Clone)]
pub struct CameraSensor<S: FrameSource> {
    source: S,
    preprocess: Preprocess,
    /// The camera image size the settings were made for (a sensor
    /// file's), when known: other sizes are refused.
    expected_size: Option<[u32; 2]>,
    /// The stage laid out for the last image size seen.
    stage: Option<PreprocessStage>,
    captured: usize,
}

impl<S: FrameSource> CameraSensor<S> {
    /// A sensor over `source` with checked preprocessing, for images of
    /// any size (the stage is laid out for the first image's).
    pub fn new(source: S, preprocess: Preprocess) -> Self {
        Self {
            source,
            preprocess,
            expected_size: None,
            stage: None,
            captured: 0,
        }
    }

    /// The same sensor taking only camera images of `[width, height]` px
    /// (what a sensor file's settings were made for); checks now that the
    /// settings fit such images.
    pub fn for_size(mut self, size: [u32; 2]) -> Result<Self, HwError> {
        let stage = self
            .preprocess
            .stage(size[0], size[1])
            .map_err(|source| HwError::Preprocess { source })?;
        self.expected_size = Some(size);
        self.stage = Some(stage);
        Ok(self)
    }

    /// One preprocessed frame; blocks as long as the source's `grab`.
    /// Fails on an image of another size than [`CameraSensor::for_size`]
    /// set, or one the crop box does not fit.
    pub fn capture_frame(&mut self) -> Result<GrayImage, HwError> {
        let raw = self.source.grab()?;
        let size = [raw.width(), raw.height()];
        let stage = match self.stage.take() {
            Some(stage) if stage.input_size() == size || self.expected_size.is_some() => stage,
            _ => self
                .preprocess
                .stage(size[0], size[1])
                .map_err(|source| HwError::Preprocess { source })?,
        };
        let frame = stage.apply(&raw);
        self.stage = Some(stage);
        let frame = frame.map_err(|source| HwError::Preprocess { source })?;
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
