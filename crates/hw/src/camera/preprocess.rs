//! The rig file's `[preprocess]` table of older rig files: the Bristol
//! TacTip settings (crop, median blur, adaptive threshold, resize) in the
//! keys they always had, read into the one preprocessing type every
//! command uses ([`tactrace_vision::PreprocessParams`]; steps and their
//! order in `tactrace_vision::preprocess`). A sensor file
//! (`tactrace sensor inspect`) holds the same type directly.
//!
//! For the 127-pin TacTip edge set: crop (190, 132, 446, 388), 5 x 5
//! median blur, Gaussian adaptive threshold [61, -5], size 256 x 256 (so
//! the resize is the identity): white pins on black, like the dataset
//! frames.
use serde::{Deserialize, Serialize};
use tactrace_vision::{Preprocess, PreprocessParams, Resize, ResizeMethod, Threshold};

use crate::HwError;

/// Preprocessing settings in the rig file's keys (pixels). `Default` is
/// the 127-pin TacTip edge collection's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PreprocessConfig {
    /// Crop box `[x0, y0, x1, y1]` in camera pixels, end exclusive.
    pub crop: Option<[u32; 4]>,
    /// Output size `[width, height]`, pixels (pixel-area resize).
    pub size: Option<[u32; 2]>,
    /// Median blur kernel (odd, >= 3) applied before thresholding.
    pub median_blur: Option<u32>,
    /// Adaptive threshold `[block size (odd, >= 3), C]`.
    pub threshold: Option<(u32, f64)>,
    /// Weighting of the adaptive threshold's neighbourhood mean.
    pub threshold_method: ThresholdMethod,
}

/// How the neighbourhood mean of the adaptive threshold is weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ThresholdMethod {
    /// Plain block mean (OpenCV `ADAPTIVE_THRESH_MEAN_C`).
    Mean,
    /// Gaussian-weighted block mean (OpenCV `ADAPTIVE_THRESH_GAUSSIAN_C`).
    #[default]
    Gaussian,
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

    /// The same settings as the preprocessing type every command uses.
    pub fn to_params(&self) -> PreprocessParams {
        let threshold = self
            .threshold
            .map(|(block, c)| match self.threshold_method {
                ThresholdMethod::Mean => Threshold::AdaptiveMean { block, c },
                ThresholdMethod::Gaussian => Threshold::AdaptiveGaussian { block, c },
            });
        PreprocessParams {
            crop: self.crop,
            mask: None,
            median_blur: self.median_blur,
            threshold,
            resize: self.size.map(|size| Resize {
                size,
                method: ResizeMethod::Area,
            }),
        }
    }

    /// Checks the settings and returns the usable preprocessing.
    pub fn validate(&self) -> Result<Preprocess, HwError> {
        self.to_params()
            .check()
            .map_err(|source| HwError::Preprocess { source })
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
