//! What the network sees: pixels standardised by the training frames'
//! mean (one for all pixels, or the mean frame) and standard deviation,
//! targets
//! standardised per column, so millimetres and degrees reach the output
//! at the same scale and one learning rate suits both.
use crate::config::InputCentring;
use crate::data::{Frames, Targets};
use serde::{Deserialize, Serialize};

/// `x = (pixel - mean) / std`, where `mean` is one number for every pixel
/// or, with [`InputCentring::MeanFrame`], the training frames' mean at
/// that pixel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputScaling {
    /// The mean over all pixels (the centre when `mean_frame` is empty).
    pub mean: f64,
    /// The standard deviation of the centred pixels.
    pub std: f64,
    /// Per-pixel means (`height x width`), or empty.
    #[serde(default)]
    pub mean_frame: Vec<f32>,
    /// The pin displacement vector's per-column standardisation (a
    /// pins-and-pixels model), `None` for a model of pixels only.
    #[serde(default)]
    pub pins: Option<TargetScaling>,
    /// The side values are a base prediction of the targets (`pins` is
    /// then the target scaling), added to the network's output in
    /// standardised units (`input = "pin_model_and_pixels"`).
    #[serde(default)]
    pub base_skip: bool,
}

impl InputScaling {
    /// From every pixel of `frames` (std 1 when the centred pixels are
    /// constant).
    pub fn fit(frames: &Frames, centring: InputCentring) -> Self {
        let (h, w) = frames.size();
        let (n, hw) = (frames.count().max(1) as f64, h * w);
        let mut sums = vec![0.0f64; hw];
        for i in 0..frames.count() {
            sums.iter_mut()
                .zip(frames.frame(i))
                .for_each(|(s, &p)| *s += p as f64);
        }
        let mean = sums.iter().sum::<f64>() / (n * hw as f64);
        let centre: Vec<f64> = match centring {
            InputCentring::Global => vec![mean; hw],
            InputCentring::MeanFrame => sums.iter().map(|s| s / n).collect(),
        };
        let mut var = 0.0;
        for i in 0..frames.count() {
            var += frames
                .frame(i)
                .iter()
                .zip(&centre)
                .map(|(&p, c)| (p as f64 - c).powi(2))
                .sum::<f64>();
        }
        var /= n * hw as f64;
        InputScaling {
            mean,
            std: if var > 1e-12 { var.sqrt() } else { 1.0 },
            mean_frame: match centring {
                InputCentring::Global => Vec::new(),
                InputCentring::MeanFrame => centre.iter().map(|&c| c as f32).collect(),
            },
            pins: None,
            base_skip: false,
        }
    }

    /// Standardise `pixels` into `out`.
    #[inline]
    pub(crate) fn apply(&self, pixels: &[u8], out: &mut [f32]) {
        let k = (1.0 / self.std) as f32;
        if self.mean_frame.is_empty() {
            let m = self.mean as f32;
            out.iter_mut()
                .zip(pixels)
                .for_each(|(o, &p)| *o = (p as f32 - m) * k);
        } else {
            out.iter_mut()
                .zip(pixels.iter().zip(&self.mean_frame))
                .for_each(|(o, (&p, m))| *o = (p as f32 - m) * k);
        }
    }

    /// Standardise `pixels` (`size = (height, width)`) moved by `(dx, dy)`
    /// px into `out`: `out[y][x]` takes the pixel at `(y - dy, x - dx)`,
    /// the nearest edge pixel where that falls outside the frame.
    pub(crate) fn apply_shifted(
        &self,
        pixels: &[u8],
        (h, w): (usize, usize),
        (dx, dy): (isize, isize),
        out: &mut [f32],
    ) {
        let k = (1.0 / self.std) as f32;
        let clamp = |v: isize, n: usize| v.clamp(0, n as isize - 1) as usize;
        for y in 0..h {
            let sy = clamp(y as isize - dy, h);
            for x in 0..w {
                let p = pixels[sy * w + clamp(x as isize - dx, w)] as f32;
                let m = match self.mean_frame.get(y * w + x) {
                    Some(&m) => m,
                    None => self.mean as f32,
                };
                out[y * w + x] = (p - m) * k;
            }
        }
    }

    /// Whether the numbers are usable for `pixels`-pixel frames.
    pub(crate) fn is_valid(&self, pixels: usize) -> bool {
        self.mean.is_finite()
            && self.std.is_finite()
            && self.std > 0.0
            && (self.mean_frame.is_empty() || self.mean_frame.len() == pixels)
            && self.mean_frame.iter().all(|m| m.is_finite())
            && self.pins.as_ref().is_none_or(TargetScaling::is_valid)
    }

    /// Pin values a frame the model reads, 0 for pixels only.
    pub fn pin_count(&self) -> usize {
        self.pins.as_ref().map_or(0, TargetScaling::dim)
    }
}

/// `z_j = (t_j - mean_j) / std_j` per target column.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetScaling {
    pub mean: Vec<f64>,
    pub std: Vec<f64>,
}

impl TargetScaling {
    /// From the training targets (population std; 1 for a constant column).
    pub fn fit(targets: &Targets) -> Self {
        let (n, d) = (targets.count().max(1) as f64, targets.dim());
        let mut mean = vec![0.0; d];
        let mut var = vec![0.0; d];
        for i in 0..targets.count() {
            mean.iter_mut()
                .zip(targets.row(i))
                .for_each(|(m, v)| *m += v);
        }
        mean.iter_mut().for_each(|m| *m /= n);
        for i in 0..targets.count() {
            for ((s, m), v) in var.iter_mut().zip(&mean).zip(targets.row(i)) {
                *s += (v - m).powi(2);
            }
        }
        var.iter_mut().for_each(|v| *v /= n);
        let std = var
            .into_iter()
            .map(|v: f64| if v > 1e-24 { v.sqrt() } else { 1.0 })
            .collect();
        TargetScaling { mean, std }
    }

    /// Targets a row.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// The scaled value of column `j`.
    #[inline]
    pub(crate) fn scale(&self, j: usize, v: f64) -> f32 {
        ((v - self.mean[j]) / self.std[j]) as f32
    }

    /// Back to the caller's units.
    #[inline]
    pub(crate) fn unscale(&self, j: usize, z: f32) -> f64 {
        z as f64 * self.std[j] + self.mean[j]
    }

    /// Whether every number is usable.
    pub(crate) fn is_valid(&self) -> bool {
        self.mean.len() == self.std.len()
            && self.mean.iter().all(|m| m.is_finite())
            && self.std.iter().all(|s| s.is_finite() && *s > 0.0)
    }
}
