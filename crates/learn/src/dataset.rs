//! Row-major sample matrices with their shape checked once, so every later
//! stage (standardiser, PCA, networks) can index without re-validating.
use crate::error::LearnError;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Row-major samples: `x` is `n x dim_x` (pin displacements, px), `y` is
/// `n x dim_y` (for pose models `dim_y = 2`: r in mm, theta in degrees).
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    pub x: Vec<f32>,
    pub y: Vec<f32>,
    pub n: usize,
    pub dim_x: usize,
    pub dim_y: usize,
}

impl Dataset {
    /// Check lengths, non-emptiness and finiteness (the error names the row
    /// and column of the first NaN or infinity).
    pub fn new(
        x: Vec<f32>,
        y: Vec<f32>,
        n: usize,
        dim_x: usize,
        dim_y: usize,
    ) -> Result<Self, LearnError> {
        if n == 0 || dim_x == 0 || dim_y == 0 {
            return Err(LearnError::Empty { n, dim_x, dim_y });
        }
        check_len("inputs", &x, n * dim_x)?;
        check_len("targets", &y, n * dim_y)?;
        check_finite("input", &x, dim_x)?;
        check_finite("target", &y, dim_y)?;
        Ok(Dataset {
            x,
            y,
            n,
            dim_x,
            dim_y,
        })
    }

    /// Inputs of sample `i`.
    pub fn x_row(&self, i: usize) -> &[f32] {
        &self.x[i * self.dim_x..(i + 1) * self.dim_x]
    }

    /// Targets of sample `i`.
    pub fn y_row(&self, i: usize) -> &[f32] {
        &self.y[i * self.dim_y..(i + 1) * self.dim_y]
    }

    /// Target column `j` over all samples (`None` when out of range).
    pub fn column(&self, j: usize) -> Option<Vec<f32>> {
        (j < self.dim_y).then(|| (0..self.n).map(|i| self.y[i * self.dim_y + j]).collect())
    }

    /// Input column `j` over all samples (`None` when out of range).
    pub fn x_column(&self, j: usize) -> Option<Vec<f32>> {
        (j < self.dim_x).then(|| (0..self.n).map(|i| self.x[i * self.dim_x + j]).collect())
    }

    /// The samples at `rows`, in that order (rows must be in range).
    pub fn select(&self, rows: &[usize]) -> Dataset {
        let mut x = Vec::with_capacity(rows.len() * self.dim_x);
        let mut y = Vec::with_capacity(rows.len() * self.dim_y);
        for &r in rows {
            x.extend_from_slice(self.x_row(r));
            y.extend_from_slice(self.y_row(r));
        }
        Dataset {
            x,
            y,
            n: rows.len(),
            dim_x: self.dim_x,
            dim_y: self.dim_y,
        }
    }

    /// Shuffle with `seed` and cut into a first part holding `frac_first` of
    /// the samples (rounded, clamped so both parts keep at least one sample
    /// when `n >= 2`) and the rest.
    pub fn split(&self, frac_first: f64, seed: u64) -> (Dataset, Dataset) {
        let mut order: Vec<usize> = (0..self.n).collect();
        order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
        let frac = if frac_first.is_finite() {
            frac_first.clamp(0.0, 1.0)
        } else {
            0.5
        };
        let mut k = (frac * self.n as f64).round() as usize;
        if self.n >= 2 {
            k = k.clamp(1, self.n - 1);
        }
        (self.select(&order[..k]), self.select(&order[k..]))
    }
}

fn check_len(what: &'static str, v: &[f32], expected: usize) -> Result<(), LearnError> {
    if v.len() == expected {
        Ok(())
    } else {
        Err(LearnError::Shape {
            what,
            expected,
            got: v.len(),
        })
    }
}

fn check_finite(what: &'static str, v: &[f32], dim: usize) -> Result<(), LearnError> {
    match v.iter().position(|a| !a.is_finite()) {
        None => Ok(()),
        Some(k) => Err(LearnError::NonFinite {
            what,
            row: k / dim,
            column: k % dim,
            value: v[k],
        }),
    }
}

/// Mean absolute error per target column (`[r mm, theta deg]` for pose
/// models). Rows beyond the shorter of the two inputs are ignored; an empty
/// comparison gives NaN.
pub fn mean_absolute_error(pred: &[[f64; 2]], truth: &Dataset) -> [f64; 2] {
    let n = pred.len().min(truth.n);
    let mut sum = [0.0; 2];
    for (i, p) in pred.iter().take(n).enumerate() {
        let t = truth.y_row(i);
        for j in 0..2.min(truth.dim_y) {
            sum[j] += (p[j] - t[j] as f64).abs();
        }
    }
    sum.map(|s| s / n as f64)
}
