//! Frames in: one typed preprocessing stage from a camera image (or a
//! saved frame) to the grey or binary frame the detector sees. Steps, each
//! optional, always in this order:
//!
//! 1. grey: grey input as it is; colour (RGB, RGBA: alpha ignored) with
//!    OpenCV's `BGR2GRAY` weights 0.299 R + 0.587 G + 0.114 B;
//! 2. crop `[x0, y0, x1, y1]` (input pixels, end exclusive);
//! 3. circular mask of the dome: pixels farther than `radius` from
//!    `centre` (pixels of the cropped frame) turn black, so the rim and the
//!    specks on it never count as pins;
//! 4. median blur (`k` x `k`, replicated borders; OpenCV `medianBlur`);
//! 5. threshold: global (`v > level`) or adaptive as the Bristol pipeline
//!    uses it (OpenCV `adaptiveThreshold`, `THRESH_BINARY`, block size and
//!    `C`, mean or Gaussian neighbourhood); the masked-out pixels stay
//!    black whatever the threshold;
//! 6. resize to `[width, height]` by pixel-area averaging (OpenCV
//!    `INTER_AREA`) or bilinear interpolation (OpenCV `INTER_LINEAR`).
//!
//! Settings ([`PreprocessParams`], serde, unknown keys refused) are checked
//! into a [`Preprocess`], which is made into a [`PreprocessStage`] for one
//! input size (where the crop is checked against the frame and the mask
//! and resize weights are laid out once).

mod filters;
mod resize;

use image::DynamicImage;
use serde::{Deserialize, Serialize};

use crate::blob::Frame;
use crate::error::VisionError;
pub use filters::{adaptive_threshold, grey_of, median_blur};
pub use resize::resize;

/// The preprocessing settings, as a configuration file holds them; every
/// step is off when its key is absent.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PreprocessParams {
    /// Crop box `[x0, y0, x1, y1]`, input pixels, end exclusive.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crop: Option<[u32; 4]>,
    /// The circle of the dome kept, in pixels of the cropped frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mask: Option<MaskCircle>,
    /// Median blur kernel size (odd, 3..=255) applied before the threshold.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub median_blur: Option<u32>,
    /// How the frame is binarised.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub threshold: Option<Threshold>,
    /// Output size and interpolation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resize: Option<Resize>,
}

/// A circle in frame pixels (x right, y down; pixel (i, j) is centred at
/// (i, j)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaskCircle {
    /// Centre `[x, y]`, px.
    pub centre: [f64; 2],
    /// Radius, px: pixels whose centre lies within it are kept.
    pub radius: f64,
}

/// Binarisation: white (255) where the test holds, else black (0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Threshold {
    /// `v > level` (OpenCV `THRESH_BINARY` at a fixed level).
    Global {
        /// Grey level, 0..=255.
        level: u8,
    },
    /// `v - mean > -ceil(c)`, `mean` the `block` x `block` box mean
    /// (OpenCV `ADAPTIVE_THRESH_MEAN_C`).
    AdaptiveMean {
        /// Neighbourhood size, odd, >= 3.
        block: u32,
        /// Offset `C` (negative: a pin must be brighter than its surroundings).
        c: f64,
    },
    /// As `AdaptiveMean` with a Gaussian-weighted mean (OpenCV
    /// `ADAPTIVE_THRESH_GAUSSIAN_C`, sigma `0.3 ((block - 1) / 2 - 1) + 0.8`);
    /// the Bristol TacTip pipeline's.
    AdaptiveGaussian {
        /// Neighbourhood size, odd, >= 3.
        block: u32,
        /// Offset `C`.
        c: f64,
    },
}

/// Output size and how it is reached.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Resize {
    /// `[width, height]`, px, each 1..=8192.
    pub size: [u32; 2],
    /// Interpolation.
    #[serde(default)]
    pub method: ResizeMethod,
}

/// Interpolation of [`Resize`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResizeMethod {
    /// Each output pixel the mean of the input area it covers (OpenCV
    /// `INTER_AREA`; when enlarging, OpenCV's enlarging form of it).
    #[default]
    Area,
    /// Bilinear, pixel centres aligned (OpenCV `INTER_LINEAR`).
    Bilinear,
}

/// Checked [`PreprocessParams`], made by [`PreprocessParams::check`].
#[derive(Clone, Debug, PartialEq)]
pub struct Preprocess {
    params: PreprocessParams,
}

/// A [`Preprocess`] for one input size, made by [`Preprocess::stage`].
#[derive(Clone, Debug, PartialEq)]
pub struct PreprocessStage {
    params: PreprocessParams,
    input: [u32; 2],
    /// Per row of the cropped frame, the kept columns `start..end`.
    mask_rows: Option<Vec<std::ops::Range<u32>>>,
}

const MAX_SIZE: u32 = 8192;

fn invalid(name: &'static str, reason: String) -> VisionError {
    VisionError::InvalidParam { name, reason }
}

fn odd_kernel(name: &'static str, k: u32, max: u32) -> Result<(), VisionError> {
    if k >= 3 && k % 2 == 1 && k <= max {
        Ok(())
    } else {
        Err(invalid(name, format!("{k} must be odd, 3..={max}")))
    }
}

impl PreprocessParams {
    /// Checks every step's settings (an empty crop, a mask radius that is
    /// not positive and finite, an even or too small kernel, a non-finite
    /// `C`, an output size outside 1..=8192 are refused).
    pub fn check(self) -> Result<Preprocess, VisionError> {
        if let Some([x0, y0, x1, y1]) = self.crop {
            if x1 <= x0 || y1 <= y0 {
                return Err(invalid(
                    "crop",
                    format!("[{x0}, {y0}, {x1}, {y1}] is empty"),
                ));
            }
        }
        if let Some(m) = self.mask {
            let finite = m.centre.iter().all(|v| v.is_finite());
            if !(finite && m.radius.is_finite() && m.radius > 0.0) {
                return Err(invalid(
                    "mask",
                    format!(
                        "centre [{}, {}] radius {} must be finite with radius > 0",
                        m.centre[0], m.centre[1], m.radius
                    ),
                ));
            }
        }
        if let Some(k) = self.median_blur {
            odd_kernel("median_blur", k, 255)?;
        }
        match self.threshold {
            Some(
                Threshold::AdaptiveMean { block, c } | Threshold::AdaptiveGaussian { block, c },
            ) => {
                odd_kernel("threshold.block", block, 1001)?;
                if !c.is_finite() {
                    return Err(invalid("threshold.c", format!("{c} is not finite")));
                }
            }
            Some(Threshold::Global { .. }) | None => {}
        }
        if let Some(r) = self.resize {
            let [w, h] = r.size;
            if !(1..=MAX_SIZE).contains(&w) || !(1..=MAX_SIZE).contains(&h) {
                return Err(invalid(
                    "resize.size",
                    format!("{w} x {h} is not within 1..={MAX_SIZE}"),
                ));
            }
        }
        Ok(Preprocess { params: self })
    }
}

impl Preprocess {
    /// The settings.
    pub fn params(&self) -> &PreprocessParams {
        &self.params
    }

    /// The stage for inputs of `width` x `height` px; fails when the crop
    /// box does not fit in such a frame.
    pub fn stage(&self, width: u32, height: u32) -> Result<PreprocessStage, VisionError> {
        let (cw, ch) = match self.params.crop {
            Some(crop @ [x0, y0, x1, y1]) => {
                if x1 > width || y1 > height {
                    return Err(VisionError::Crop {
                        crop,
                        width,
                        height,
                    });
                }
                (x1 - x0, y1 - y0)
            }
            None => (width, height),
        };
        let mask_rows = self.params.mask.map(|m| mask_rows(m, cw, ch));
        Ok(PreprocessStage {
            params: self.params.clone(),
            input: [width, height],
            mask_rows,
        })
    }
}

/// Per row, the columns whose pixel centre lies within the circle: the
/// direct test `(x - cx)^2 + (y - cy)^2 <= r^2`, run once per pixel.
fn mask_rows(m: MaskCircle, width: u32, height: u32) -> Vec<std::ops::Range<u32>> {
    let r2 = m.radius * m.radius;
    (0..height)
        .map(|y| {
            let dy2 = (f64::from(y) - m.centre[1]).powi(2);
            let inside = |x: u32| (f64::from(x) - m.centre[0]).powi(2) + dy2 <= r2;
            match (0..width).find(|&x| inside(x)) {
                Some(start) => {
                    let end = (start..width).find(|&x| !inside(x)).unwrap_or(width);
                    start..end
                }
                None => 0..0,
            }
        })
        .collect()
}

impl PreprocessStage {
    /// The settings.
    pub fn params(&self) -> &PreprocessParams {
        &self.params
    }

    /// `[width, height]` of the inputs it takes.
    pub fn input_size(&self) -> [u32; 2] {
        self.input
    }

    /// `[width, height]` of the frames it gives.
    pub fn output_size(&self) -> [u32; 2] {
        if let Some(r) = self.params.resize {
            return r.size;
        }
        match self.params.crop {
            Some([x0, y0, x1, y1]) => [x1 - x0, y1 - y0],
            None => self.input,
        }
    }

    /// Whether the pixel (x, y) of the cropped frame is kept by the mask.
    pub fn keeps(&self, x: u32, y: u32) -> bool {
        match &self.mask_rows {
            Some(rows) => rows.get(y as usize).is_some_and(|r| r.contains(&x)),
            None => true,
        }
    }

    /// A camera image (grey or colour) through every step.
    pub fn apply(&self, image: &DynamicImage) -> Result<Frame, VisionError> {
        self.check_size(image.width(), image.height())?;
        Ok(self.run(grey_of(image)))
    }

    /// A grey frame through every step after the grey conversion.
    pub fn apply_grey(&self, frame: &Frame) -> Result<Frame, VisionError> {
        self.check_size(frame.width(), frame.height())?;
        Ok(self.run(frame.clone()))
    }

    fn check_size(&self, width: u32, height: u32) -> Result<(), VisionError> {
        if [width, height] == self.input {
            Ok(())
        } else {
            Err(VisionError::FrameSize {
                expected: self.input,
                found: [width, height],
            })
        }
    }

    fn run(&self, grey: Frame) -> Frame {
        let p = &self.params;
        let mut frame = match p.crop {
            Some([x0, y0, x1, y1]) => {
                image::imageops::crop_imm(&grey, x0, y0, x1 - x0, y1 - y0).to_image()
            }
            None => grey,
        };
        self.mask(&mut frame);
        if let Some(k) = p.median_blur {
            frame = median_blur(&frame, k);
        }
        if let Some(t) = p.threshold {
            frame = threshold(&frame, t);
            self.mask(&mut frame);
        }
        match p.resize {
            Some(r) => resize(&frame, r.size, r.method),
            None => frame,
        }
    }

    /// Blackens the pixels outside the mask.
    fn mask(&self, frame: &mut Frame) {
        let Some(rows) = &self.mask_rows else { return };
        let width = frame.width() as usize;
        for (row, kept) in frame.chunks_exact_mut(width).zip(rows) {
            let (start, end) = (kept.start as usize, kept.end as usize);
            if start >= end {
                row.fill(0);
                continue;
            }
            row[..start].fill(0);
            row[end..].fill(0);
        }
    }
}

/// `frame` binarised by `t` (0 or 255).
pub fn threshold(frame: &Frame, t: Threshold) -> Frame {
    match t {
        Threshold::Global { level } => {
            let mut out = frame.clone();
            for v in out.iter_mut() {
                *v = if *v > level { 255 } else { 0 };
            }
            out
        }
        Threshold::AdaptiveMean { block, c } => adaptive_threshold(frame, block, c, false),
        Threshold::AdaptiveGaussian { block, c } => adaptive_threshold(frame, block, c, true),
    }
}

#[cfg(test)]
mod tests;
