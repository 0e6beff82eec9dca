//! A dataset's frames as images, for the image models: `frames.npy`
//! (uint8, `N x H x W`, row i the frame of row i of `inputs.npy` and
//! `targets.npy`), the sensor's preprocessed frame area-averaged to
//! `H x W` px, described in `meta.json` under `image_frames`
//! ([`FramesInfo`], which also records the sensor preprocessing the frames
//! went through, copied into an image model's `frames.json` so the model
//! is fed frames made the same way). A dataset without them has no
//! `image_frames` key.
use crate::error::{Result, StoreError};
use ndarray::Array3;
use serde::{Deserialize, Serialize};
use std::path::Path;
use tactrace_vision::PreprocessParams;

/// The frames file of a dataset folder.
pub const FRAMES_NPY: &str = "frames.npy";

/// `meta.json`'s `image_frames`: what `frames.npy` holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FramesInfo {
    /// The file, [`FRAMES_NPY`].
    pub file: String,
    /// Frame height, px.
    pub height: usize,
    /// Frame width, px.
    pub width: usize,
    /// The size of the frames they were averaged from (after the sensor's
    /// preprocessing), `[height, width]` px.
    pub source_size: [usize; 2],
    /// How they were made, for readers.
    pub layout: String,
    /// The sensor preprocessing settings each frame went through before
    /// the averaging; absent: none (the grey frame as it is; also what
    /// folders written before this was recorded mean).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preprocess: Option<PreprocessParams>,
}

impl FramesInfo {
    /// Frames of `height x width` px averaged from `source_size` ones.
    pub fn new(height: usize, width: usize, source_size: [usize; 2]) -> Self {
        Self {
            file: FRAMES_NPY.into(),
            height,
            width,
            source_size,
            layout: "N x H x W uint8 grey: each row's frame as the pin detector sees it \
                     (after the sensor's preprocessing), area-averaged to H x W"
                .into(),
            preprocess: None,
        }
    }

    /// The same frames, recorded as preprocessed by `preprocess` (settings
    /// that do nothing are recorded as none).
    pub fn with_preprocess(mut self, preprocess: Option<&PreprocessParams>) -> Self {
        self.preprocess = preprocess
            .filter(|p| **p != PreprocessParams::default())
            .cloned();
        self
    }
}

/// A dataset's frames in memory: `count x height x width` grey pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageFrames {
    pub info: FramesInfo,
    /// Row-major, frame after frame.
    pub pixels: Vec<u8>,
}

impl ImageFrames {
    /// Pixels of one frame.
    pub fn frame_len(&self) -> usize {
        self.info.height * self.info.width
    }

    /// Number of frames.
    pub fn count(&self) -> usize {
        self.pixels.len().checked_div(self.frame_len()).unwrap_or(0)
    }

    /// Frame `i`.
    pub fn frame(&self, i: usize) -> &[u8] {
        let n = self.frame_len();
        &self.pixels[i * n..(i + 1) * n]
    }

    /// The frames at `rows`, in that order.
    pub fn subset(&self, rows: &[usize]) -> ImageFrames {
        let mut pixels = Vec::with_capacity(rows.len() * self.frame_len());
        for &r in rows {
            pixels.extend_from_slice(self.frame(r));
        }
        ImageFrames {
            info: self.info.clone(),
            pixels,
        }
    }
}

/// The `image_frames` entry of the dataset `meta.json` text, if any.
pub fn frames_info(meta_json: &str, meta_path: &Path) -> Result<Option<FramesInfo>> {
    #[derive(Deserialize)]
    struct Entry {
        #[serde(default)]
        image_frames: Option<FramesInfo>,
    }
    let entry: Entry = serde_json::from_str(meta_json).map_err(|e| StoreError::Format {
        path: meta_path.to_path_buf(),
        reason: format!("image_frames: {e}"),
    })?;
    Ok(entry.image_frames)
}

/// Write `frames` as `dir/frames.npy`.
pub(crate) fn write_frames(dir: &Path, frames: &ImageFrames) -> Result<()> {
    let (h, w) = (frames.info.height, frames.info.width);
    let p = dir.join(FRAMES_NPY);
    let array =
        Array3::from_shape_vec((frames.count(), h, w), frames.pixels.clone()).map_err(|e| {
            StoreError::Format {
                path: p.clone(),
                reason: format!("frames shape: {e}"),
            }
        })?;
    ndarray_npy::write_npy(&p, &array).map_err(|e| StoreError::Write {
        path: p.clone(),
        source: std::io::Error::other(e),
    })
}

/// The frames of the dataset folder `dir` of `samples` rows, whose
/// `meta.json` text is `meta_json`: `None` when it records none, an error
/// when `frames.npy` does not hold what `meta.json` says.
pub fn read_image_frames(
    dir: &Path,
    meta_json: &str,
    samples: usize,
) -> Result<Option<ImageFrames>> {
    let Some(info) = frames_info(meta_json, &dir.join("meta.json"))? else {
        return Ok(None);
    };
    let p = dir.join(&info.file);
    if info.file != FRAMES_NPY {
        return Err(StoreError::Format {
            path: dir.join("meta.json"),
            reason: format!("image_frames.file is \"{}\", not {FRAMES_NPY}", info.file),
        });
    }
    let array = crate::npy_file::read_u8_stack(&p)?;
    let want = (samples, info.height, info.width);
    if array.dim() != want {
        let (n, h, w) = array.dim();
        return Err(StoreError::Format {
            path: p,
            reason: format!(
                "holds {n} x {h} x {w} frames, meta.json says {} x {} x {} (rows x height x width)",
                want.0, want.1, want.2
            ),
        });
    }
    let pixels = array.iter().copied().collect();
    Ok(Some(ImageFrames { info, pixels }))
}
