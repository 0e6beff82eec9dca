//! Per-feature standardisation (report ch. 4.2, "PCADenNN"): subtract the
//! training mean and divide by the training standard deviation. The report
//! writes "divide by the variance" but its formula divides by sigma; we
//! divide by sigma. Fitted on training data only, then frozen.
use crate::error::LearnError;
use serde::{Deserialize, Serialize};

/// Features whose standard deviation is below this are treated as constant
/// (their std is set to 1, so they map to 0 instead of blowing up).
const MIN_STD: f64 = 1e-9;

/// Mean and population standard deviation (1/n, as in the report) per feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Standardiser {
    mean: Vec<f64>,
    std: Vec<f64>,
}

impl Standardiser {
    /// Fit on a row-major `n x dim` matrix.
    pub fn fit(x: &[f32], n: usize, dim: usize) -> Result<Self, LearnError> {
        if n == 0 || dim == 0 {
            return Err(LearnError::Empty {
                n,
                dim_x: dim,
                dim_y: 0,
            });
        }
        if x.len() != n * dim {
            return Err(LearnError::Shape {
                what: "standardiser input",
                expected: n * dim,
                got: x.len(),
            });
        }
        let mut mean = vec![0.0f64; dim];
        for row in x.chunks_exact(dim) {
            mean.iter_mut().zip(row).for_each(|(m, &v)| *m += v as f64);
        }
        mean.iter_mut().for_each(|m| *m /= n as f64);
        let mut var = vec![0.0f64; dim];
        for row in x.chunks_exact(dim) {
            for ((s, &v), m) in var.iter_mut().zip(row).zip(&mean) {
                *s += (v as f64 - m).powi(2);
            }
        }
        let std = var
            .iter()
            .map(|s| (s / n as f64).sqrt())
            .map(|s| if s > MIN_STD { s } else { 1.0 })
            .collect();
        Ok(Standardiser { mean, std })
    }

    /// Rebuild from stored statistics (lengths must agree, std positive).
    pub fn from_parts(mean: Vec<f64>, std: Vec<f64>) -> Result<Self, LearnError> {
        if mean.len() != std.len() || mean.is_empty() {
            return Err(LearnError::Corrupt {
                reason: format!("standardiser: {} means vs {} stds", mean.len(), std.len()),
            });
        }
        if std.iter().any(|s| !(s.is_finite() && *s > 0.0)) || mean.iter().any(|m| !m.is_finite()) {
            return Err(LearnError::Corrupt {
                reason: "standardiser: non-finite mean or non-positive std".into(),
            });
        }
        Ok(Standardiser { mean, std })
    }

    /// Number of features.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Per-feature means.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Per-feature standard deviations (1 for constant features).
    pub fn std(&self) -> &[f64] {
        &self.std
    }

    /// Standardise one sample into `out` (both of length [`Self::dim`]).
    pub fn transform_into(&self, x: &[f32], out: &mut [f64]) {
        for (((o, &v), m), s) in out.iter_mut().zip(x).zip(&self.mean).zip(&self.std) {
            *o = (v as f64 - m) / s;
        }
    }

    /// Standardise a row-major matrix, returning f64 rows.
    pub fn transform(&self, x: &[f32]) -> Vec<f64> {
        let mut out = vec![0.0; x.len()];
        for (row, o) in x
            .chunks_exact(self.dim())
            .zip(out.chunks_exact_mut(self.dim()))
        {
            self.transform_into(row, o);
        }
        out
    }

    /// Map standardised values back to original units.
    pub fn inverse_into(&self, z: &[f64], out: &mut [f64]) {
        for (((o, &v), m), s) in out.iter_mut().zip(z).zip(&self.mean).zip(&self.std) {
            *o = v * s + m;
        }
    }
}
