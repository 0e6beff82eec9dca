//! Simulated taps kept as images for the image models (`collect
//! --frames-size`, `twin --frames-size`): each rendered frame, the frame
//! the pin detector reads, area-averaged by the same [`ImageInput`] that
//! `import --frames-size` and the follow perception use, stacked as a
//! dataset's `frames.npy` (`crate::import::images_of`).
use crate::error::{LabError, Result};
use crate::import_reader::SmallFrame;
use tactrace_sensor::Frame;
use tactrace_servo::ImageInput;
use tactrace_vision::PreprocessParams;

/// Smallest and largest side accepted, px (as `import --frames-size`).
const SIZES: std::ops::RangeInclusive<usize> = 4..=1024;

/// The image input of a collection's simulated taps: no preprocessing
/// (a simulated world's frames reach the follow perception as rendered),
/// `size x size` px; `None` without a size. A size out of range is bad input.
pub(crate) fn sim_input(size: Option<usize>) -> Result<Option<ImageInput>> {
    size.map(|s| input_of(None, s)).transpose()
}

/// The image input of `size x size` px frames recorded as preprocessed by
/// `preprocess`: the settings real frames go through before the
/// averaging, so a model trained on simulated taps is fed real frames as
/// `import` made them.
pub(crate) fn input_of(preprocess: Option<&PreprocessParams>, size: usize) -> Result<ImageInput> {
    if !SIZES.contains(&size) {
        return Err(LabError::Config(format!(
            "--frames-size {size} is not in {}..={} px",
            SIZES.start(),
            SIZES.end()
        )));
    }
    Ok(ImageInput::new(preprocess, (size, size))?)
}

/// `frame` (what the pin detector read) made into `input`'s image, with
/// its size.
pub(crate) fn small_of(input: &ImageInput, frame: &Frame) -> SmallFrame {
    let size = [frame.height() as usize, frame.width() as usize];
    (input.small(frame), size)
}
