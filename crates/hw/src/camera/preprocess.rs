//! The Bristol TacTip frame preprocessing: camera image -> binary frame.
//!
//! Order (as the Bristol `CvPreprocVideoCamera` applies the settings of a
//! collection's `collection_meta.json`): grayscale (OpenCV BGR2GRAY weights
//! 0.299 R + 0.587 G + 0.114 B), crop `[x0, y0, x1, y1]` (pixels, end
//! exclusive), 5x5 median blur, adaptive threshold `[block, C]`, then resize
//! to `size` (width, height) by pixel-area averaging (OpenCV INTER_AREA).
//! For the 127-pin TacTip edge set: crop (190, 132, 446, 388), size 256 x
//! 256, threshold [61, -5], so the resize is the identity and the output is
//! white pins on black, like the dataset frames.
use image::{DynamicImage, GrayImage};
use serde::{Deserialize, Serialize};

use super::threshold::{adaptive_threshold, median_blur, ThresholdMethod};
use crate::HwError;

/// Preprocessing settings (pixels). `Default` is the 127-pin TacTip edge
/// collection's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PreprocessConfig {
    /// Crop box `[x0, y0, x1, y1]` in camera pixels, end exclusive.
    pub crop: Option<[u32; 4]>,
    /// Output size `[width, height]`, pixels.
    pub size: Option<[u32; 2]>,
    /// Median blur kernel (odd, >= 3) applied before thresholding.
    pub median_blur: Option<u32>,
    /// Adaptive threshold `[block size (odd, >= 3), C]`.
    pub threshold: Option<(u32, f64)>,
    /// Weighting of the adaptive threshold's neighbourhood mean.
    pub threshold_method: ThresholdMethod,
}

impl Default for PreprocessConfig {
    fn default() -> Self {
        Self {
            crop: Some([190, 132, 446, 388]),
            size: Some([256, 256]),
            median_blur: Some(5),
            threshold: Some((61, -5.0)),
            threshold_method: ThresholdMethod::Gaussian,
        }
    }
}

impl PreprocessConfig {
    /// No processing beyond grayscale.
    pub fn grayscale_only() -> Self {
        Self {
            crop: None,
            size: None,
            median_blur: None,
            threshold: None,
            threshold_method: ThresholdMethod::Gaussian,
        }
    }

    /// Reads `crop`, `size` and `threshold` from the text of a Bristol
    /// `collection_meta.json`; a missing key switches that step off. The
    /// median blur (5) and Gaussian method are the Bristol pipeline's.
    pub fn from_collection_meta(json: &str) -> Result<Self, HwError> {
        let meta: serde_json::Value = serde_json::from_str(json).map_err(|e| HwError::Meta {
            reason: e.to_string(),
        })?;
        let field = |key: &str| meta.get(key).filter(|v| !v.is_null()).cloned();
        let parse = |key: &'static str| -> Result<Option<Vec<f64>>, HwError> {
            field(key)
                .map(|v| {
                    serde_json::from_value::<Vec<f64>>(v).map_err(|e| HwError::Meta {
                        reason: format!("`{key}`: {e}"),
                    })
                })
                .transpose()
        };
        let crop = parse("crop")?
            .map(|v| to_u32s::<4>("crop", &v))
            .transpose()?;
        let size = parse("size")?
            .map(|v| to_u32s::<2>("size", &v))
            .transpose()?;
        let threshold = parse("threshold")?
            .map(|v| match v.as_slice() {
                [block, c] => Ok((to_u32s::<1>("threshold", &[*block])?[0], *c)),
                _ => Err(HwError::Meta {
                    reason: "`threshold` must be [block, C]".into(),
                }),
            })
            .transpose()?;
        Ok(Self {
            crop,
            size,
            threshold,
            ..Self::default()
        })
    }

    /// Checks the settings and returns the usable preprocessing.
    pub fn validate(&self) -> Result<Preprocess, HwError> {
        if let Some([x0, y0, x1, y1]) = self.crop {
            if x1 <= x0 || y1 <= y0 {
                return Err(config("crop", format!("[{x0}, {y0}, {x1}, {y1}] is empty")));
            }
        }
        if let Some([w, h]) = self.size {
            if w == 0 || h == 0 || w > 8192 || h > 8192 {
                return Err(config("size", format!("{w}x{h} not in 1..=8192")));
            }
        }
        if let Some(k) = self.median_blur {
            check_odd_kernel("median_blur", k)?;
        }
        if let Some((block, c)) = self.threshold {
            check_odd_kernel("threshold", block)?;
            if !c.is_finite() {
                return Err(config("threshold", "C is not finite".into()));
            }
        }
        Ok(Preprocess {
            config: self.clone(),
        })
    }
}

fn config(field: &'static str, reason: String) -> HwError {
    HwError::Config { field, reason }
}

fn check_odd_kernel(field: &'static str, k: u32) -> Result<(), HwError> {
    if k >= 3 && k % 2 == 1 && k <= 1001 {
        Ok(())
    } else {
        Err(config(field, format!("kernel {k} must be odd, 3..=1001")))
    }
}

fn to_u32s<const N: usize>(key: &str, values: &[f64]) -> Result<[u32; N], HwError> {
    let bad = || HwError::Meta {
        reason: format!("`{key}` must hold {N} non-negative integers"),
    };
    if values.len() != N {
        return Err(bad());
    }
    let mut out = [0u32; N];
    for (o, v) in out.iter_mut().zip(values) {
        if v.fract() != 0.0 || *v < 0.0 || *v > u32::MAX as f64 {
            return Err(bad());
        }
        *o = *v as u32;
    }
    Ok(out)
}

/// Checked preprocessing, made by [`PreprocessConfig::validate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Preprocess {
    config: PreprocessConfig,
}

impl Preprocess {
    /// The settings.
    pub fn config(&self) -> &PreprocessConfig {
        &self.config
    }

    /// Camera image -> preprocessed grayscale (binary when thresholded).
    /// Fails only when the crop box does not fit the image.
    pub fn apply(&self, image: &DynamicImage) -> Result<GrayImage, HwError> {
        let mut gray = opencv_gray(image);
        if let Some(crop) = self.config.crop {
            gray = crop_checked(&gray, crop)?;
        }
        if let Some(k) = self.config.median_blur {
            gray = median_blur(&gray, k);
        }
        if let Some((block, c)) = self.config.threshold {
            gray = adaptive_threshold(&gray, self.config.threshold_method, block, c);
        }
        if let Some([w, h]) = self.config.size {
            gray = resize_area(&gray, w, h);
        }
        Ok(gray)
    }
}

/// Grayscale with OpenCV's BGR2GRAY weights (fixed point, 14 bits).
pub fn opencv_gray(image: &DynamicImage) -> GrayImage {
    match image {
        DynamicImage::ImageLuma8(gray) => gray.clone(),
        DynamicImage::ImageLuma16(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageLumaA16(_) => image.to_luma8(),
        _ => {
            let rgb = image.to_rgb8();
            GrayImage::from_fn(rgb.width(), rgb.height(), |x, y| {
                let [r, g, b] = rgb.get_pixel(x, y).0;
                let y = (r as u32 * 4899 + g as u32 * 9617 + b as u32 * 1868 + (1 << 13)) >> 14;
                image::Luma([y.min(255) as u8])
            })
        }
    }
}

/// Crops `[x0, y0, x1, y1]` (end exclusive), failing if it leaves the image.
pub fn crop_checked(image: &GrayImage, crop: [u32; 4]) -> Result<GrayImage, HwError> {
    let [x0, y0, x1, y1] = crop;
    let (w, h) = image.dimensions();
    if x1 > w || y1 > h || x1 <= x0 || y1 <= y0 {
        return Err(HwError::Crop {
            crop,
            width: w,
            height: h,
        });
    }
    Ok(image::imageops::crop_imm(image, x0, y0, x1 - x0, y1 - y0).to_image())
}

/// Resize to `w` x `h`: exact pixel-area averaging when shrinking (OpenCV
/// INTER_AREA), bilinear when enlarging, identity when the size matches.
pub fn resize_area(image: &GrayImage, w: u32, h: u32) -> GrayImage {
    let (sw, sh) = image.dimensions();
    if (sw, sh) == (w, h) || sw == 0 || sh == 0 {
        return image.clone();
    }
    if w > sw || h > sh {
        return image::imageops::resize(image, w, h, image::imageops::FilterType::Triangle);
    }
    let wx = area_weights(sw, w);
    let wy = area_weights(sh, h);
    // Horizontal pass into floats, then vertical pass.
    let mut rows = vec![0.0f64; (w * sh) as usize];
    for y in 0..sh {
        for (x, taps) in wx.iter().enumerate() {
            rows[(y * w) as usize + x] = taps
                .iter()
                .map(|&(i, f)| f * image.get_pixel(i, y)[0] as f64)
                .sum();
        }
    }
    GrayImage::from_fn(w, h, |x, y| {
        let v: f64 = wy[y as usize]
            .iter()
            .map(|&(j, f)| f * rows[(j * w + x) as usize])
            .sum();
        image::Luma([v.round().clamp(0.0, 255.0) as u8])
    })
}

/// For each output index, the source indices and their overlap fractions.
fn area_weights(src: u32, dst: u32) -> Vec<Vec<(u32, f64)>> {
    let scale = src as f64 / dst as f64;
    (0..dst)
        .map(|o| {
            let (start, end) = (o as f64 * scale, (o as f64 + 1.0) * scale);
            let mut taps = Vec::new();
            let mut i = start.floor() as u32;
            while (i as f64) < end && i < src {
                let overlap = (end.min(i as f64 + 1.0) - start.max(i as f64)).max(0.0);
                if overlap > 1e-12 {
                    taps.push((i, overlap / scale));
                }
                i += 1;
            }
            taps
        })
        .collect()
}
