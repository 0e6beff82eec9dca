//! How a tap's frame becomes an image model's input, exactly as the
//! frames of its training dataset were made (`frames.npy`): the grey frame
//! through the dataset's sensor preprocessing stage (crop, dome mask,
//! blur, threshold, resize; none for a dataset imported without a sensor
//! file), then area-averaged to the model's input size.
//!
//! Every place that feeds an image model (the follow perception in every
//! world, `predict --image`, import writing `frames.npy`) goes through
//! [`ImageInput`], so a model sees at run time the pixels it was trained on.
use std::sync::{Mutex, PoisonError};
use tactrace_vision::{Frame, Preprocess, PreprocessParams, PreprocessStage, VisionError};

/// The recipe of an image model's input frames: the preprocessing (or
/// none) and the input size `(height, width)` px.
#[derive(Debug)]
pub struct ImageInput {
    preprocess: Option<Preprocess>,
    size: (usize, usize),
    /// The stage made for the last frame size seen.
    stage: Mutex<Option<PreprocessStage>>,
}

impl ImageInput {
    /// Frames preprocessed by `preprocess` (`None`, or settings that do
    /// nothing: the grey frame as it is), area-averaged to `size`
    /// `(height, width)` px; settings that do not check are refused.
    pub fn new(
        preprocess: Option<&PreprocessParams>,
        size: (usize, usize),
    ) -> Result<Self, VisionError> {
        let preprocess = match preprocess {
            Some(p) if *p != PreprocessParams::default() => Some(p.clone().check()?),
            _ => None,
        };
        Ok(Self {
            preprocess,
            size,
            stage: Mutex::new(None),
        })
    }

    /// The preprocessing settings, `None` when frames are taken as they are.
    pub fn preprocess(&self) -> Option<&PreprocessParams> {
        self.preprocess.as_ref().map(Preprocess::params)
    }

    /// The input size, `(height, width)` px.
    pub fn size(&self) -> (usize, usize) {
        self.size
    }

    /// The `[height, width]` px of the preprocessed frame of a grey frame
    /// of `width x height` px (refused when the stage cannot take it).
    pub fn preprocessed_size(&self, width: u32, height: u32) -> Result<[usize; 2], VisionError> {
        let [w, h] = match &self.preprocess {
            Some(p) => p.stage(width, height)?.output_size(),
            None => [width, height],
        };
        Ok([h as usize, w as usize])
    }

    /// The grey `frame` through the preprocessing stage (itself with none).
    pub fn preprocessed(&self, frame: &Frame) -> Result<Frame, VisionError> {
        let Some(p) = &self.preprocess else {
            return Ok(frame.clone());
        };
        let mut stage = self.stage.lock().unwrap_or_else(PoisonError::into_inner);
        let fits = |s: &PreprocessStage| s.input_size() == [frame.width(), frame.height()];
        if !stage.as_ref().is_some_and(fits) {
            *stage = Some(p.stage(frame.width(), frame.height())?);
        }
        stage.as_ref().expect("stage made above").apply_grey(frame)
    }

    /// An already preprocessed frame area-averaged to the input size.
    pub fn small(&self, preprocessed: &Frame) -> Vec<u8> {
        let from = (
            preprocessed.height() as usize,
            preprocessed.width() as usize,
        );
        tactrace_convnet::area_resample(preprocessed.as_raw(), from, self.size)
    }

    /// The model's input for the grey frame `frame`: preprocessed, then
    /// area-averaged (a colour image is made grey by
    /// `tactrace_vision::preprocess::grey_of` first, as import does).
    pub fn of_frame(&self, frame: &Frame) -> Result<Vec<u8>, VisionError> {
        Ok(self.small(&self.preprocessed(frame)?))
    }
}
