//! The one error type of the vision crate: every fallible call (parsing blob
//! parameters, building a tracker, extracting pins from a frame) reports one
//! of these variants, with the offending values as fields.

use thiserror::Error;

/// Errors from blob-parameter handling, pin tracking and pin extraction.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum VisionError {
    /// The blob configuration text is not valid TOML or has a value of the wrong type.
    #[error("blob parameters are not valid TOML: {message}")]
    Toml { message: String },
    /// The blob configuration names a key that `BlobParams` does not have.
    #[error("unknown blob parameter key `{key}`")]
    UnknownKey { key: String },
    /// `BlobParams::preset` was asked for a name it does not know.
    #[error("unknown blob preset `{name}` (known presets: {known})")]
    UnknownPreset { name: String, known: String },
    /// A blob parameter is out of range (see `BlobParams::validate`).
    #[error("invalid blob parameter `{name}`: {reason}")]
    InvalidParam { name: &'static str, reason: String },
    /// The reference pin set is too small to define a displacement field.
    #[error("the reference needs at least {required} pins, found {found}")]
    TooFewReferencePins { found: usize, required: usize },
    /// A reference pin centre is NaN or infinite.
    #[error("reference pin {index} has a non-finite coordinate")]
    NonFiniteReference { index: usize },
    /// Reference pins coincide, so no pin spacing can be measured.
    #[error("reference pins have zero nearest-neighbour spacing")]
    DegenerateReference,
    /// `min_matched_fraction` is outside [0, 1].
    #[error("min_matched_fraction {value} must lie in [0, 1]")]
    InvalidFraction { value: f64 },
    /// Fewer pins were matched in a frame than the extractor requires.
    #[error("only {matched} of {total} pins matched, {required} required")]
    TooFewPins {
        matched: usize,
        total: usize,
        required: usize,
    },
    /// No frame shows the expected number of pins, so no provisional
    /// rest layout can be taken from one.
    #[error("no frame shows exactly {pins} pins, so none can start the rest layout")]
    NoFrameWithPinCount { pins: usize },
    /// No frame could be ordered against the layout.
    #[error("none of the {frames} frames could be ordered against the layout")]
    NoFrameTracked { frames: usize },
    /// The crop box does not fit in the frame.
    #[error("crop [{x0}, {y0}, {x1}, {y1}] does not fit in a {width} x {height} frame", x0 = crop[0], y0 = crop[1], x1 = crop[2], y1 = crop[3])]
    Crop {
        crop: [u32; 4],
        width: u32,
        height: u32,
    },
    /// A frame's size is not the one the preprocessing was laid out for.
    #[error("the frame is {} x {} px, the preprocessing expects {} x {}", found[0], found[1], expected[0], expected[1])]
    FrameSize { expected: [u32; 2], found: [u32; 2] },
    /// Inspection was given no frames.
    #[error("no frames to inspect")]
    NoFrames,
    /// Inspection found nothing pin-like in the frames.
    #[error("no pins found in the {frames} frames inspected")]
    NoPins { frames: usize },
}

impl VisionError {
    /// Whether the detector's set-up is at fault (its parameters or the
    /// reference pins), not a frame in which too few pins were found.
    pub fn is_config(&self) -> bool {
        !matches!(self, VisionError::TooFewPins { .. })
    }
}
