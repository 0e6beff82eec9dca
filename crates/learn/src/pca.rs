//! Principal component analysis (report ch. 4.2): the eigenvectors of the
//! covariance of the standardised training inputs, largest eigenvalue first.
//! It shrinks 254 pin displacements to the 30-35 inputs of the PCA networks.
use crate::error::LearnError;
use faer::{Mat, Side};
use serde::{Deserialize, Serialize};

/// How many components to keep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Components {
    /// Exactly this many (clamped to the data dimension).
    Count(usize),
    /// The fewest components whose explained variance reaches this fraction
    /// (e.g. 0.9947 for the report's 35 components).
    Variance(f64),
}

/// How the projections onto the kept components are scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PcScaling {
    /// Plain projections (the report): component `c` has variance
    /// `lambda_c`.
    Raw,
    /// Each projection divided by `sqrt(lambda_c)`: unit variance per
    /// component. Amplifies the small, noisy components as much as the
    /// leading ones.
    Whiten,
    /// All projections divided by one factor, `sqrt(mean kept lambda)`: the
    /// inputs have unit variance on average (like standardised features, so
    /// the `1/sqrt(fan-in)` initialisation suits them) while the leading
    /// components keep their larger share.
    UnitMean,
}

/// A fitted PCA projection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pca {
    /// Mean of the fitted data (near zero on standardised data).
    mean: Vec<f64>,
    /// `k x dim` row-major, rows orthonormal, ordered by eigenvalue.
    components: Vec<f64>,
    /// The kept eigenvalues of the covariance (population, 1/n).
    eigenvalues: Vec<f64>,
    /// Kept eigenvalues over the sum of all eigenvalues.
    explained_variance_ratio: Vec<f64>,
    /// How projections are scaled.
    scaling: PcScaling,
    /// The factor applied to each projection (from `scaling`).
    scales: Vec<f64>,
}

impl Pca {
    /// Fit on a row-major `n x dim` matrix of (standardised) samples.
    pub fn fit(
        x: &[f64],
        n: usize,
        dim: usize,
        keep: Components,
        scaling: PcScaling,
    ) -> Result<Self, LearnError> {
        if n == 0 || dim == 0 || x.len() != n * dim {
            return Err(LearnError::Shape {
                what: "PCA input",
                expected: n * dim,
                got: x.len(),
            });
        }
        let mean = column_means(x, n, dim);
        let cov = covariance(x, n, dim, &mean);
        let eig = cov
            .self_adjoint_eigen(Side::Lower)
            .map_err(|e| LearnError::Config {
                field: "pca",
                reason: match e {
                    faer::linalg::evd::EvdError::NoConvergence => {
                        "the eigendecomposition did not converge".into()
                    }
                },
            })?;
        let values: Vec<f64> = (0..dim)
            .rev()
            .map(|i| eig.S().column_vector()[i].max(0.0))
            .collect();
        let total: f64 = values.iter().sum();
        let ratio: Vec<f64> = values
            .iter()
            .map(|v| if total > 0.0 { v / total } else { 0.0 })
            .collect();
        let k = count_for(keep, &ratio)?;
        let mut components = Vec::with_capacity(k * dim);
        for c in 0..k {
            let col = dim - 1 - c;
            components.extend((0..dim).map(|r| eig.U()[(r, col)]));
        }
        let eigenvalues = values[..k].to_vec();
        let scales = scales_for(scaling, &eigenvalues);
        Ok(Pca {
            mean,
            components,
            eigenvalues,
            explained_variance_ratio: ratio[..k].to_vec(),
            scaling,
            scales,
        })
    }

    /// Number of kept components.
    pub fn n_components(&self) -> usize {
        self.eigenvalues.len()
    }

    /// Input dimension.
    pub fn dim(&self) -> usize {
        self.mean.len()
    }

    /// Fraction of the total variance carried by each kept component.
    pub fn explained_variance_ratio(&self) -> &[f64] {
        &self.explained_variance_ratio
    }

    /// Kept covariance eigenvalues, descending.
    pub fn eigenvalues(&self) -> &[f64] {
        &self.eigenvalues
    }

    /// The projection matrix, `k x dim` row-major (row `c` is component `c`).
    pub fn components(&self) -> &[f64] {
        &self.components
    }

    /// How projections are scaled.
    pub fn scaling(&self) -> PcScaling {
        self.scaling
    }

    /// Mean of the fitted data, subtracted before projecting.
    pub(crate) fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// The factor applied to each projection.
    pub(crate) fn scales(&self) -> &[f64] {
        &self.scales
    }

    /// Project one sample (length [`Self::dim`]) into `out` (length k).
    pub fn transform_into(&self, x: &[f64], out: &mut [f64]) {
        let dim = self.dim();
        for ((o, w), scale) in out
            .iter_mut()
            .zip(self.components.chunks_exact(dim))
            .zip(&self.scales)
        {
            let proj: f64 = w
                .iter()
                .zip(x)
                .zip(&self.mean)
                .map(|((w, x), m)| w * (x - m))
                .sum();
            *o = proj * scale;
        }
    }

    /// Project a row-major matrix; returns `n x k` row-major.
    pub fn transform(&self, x: &[f64]) -> Vec<f64> {
        let k = self.n_components();
        let rows = x.len() / self.dim().max(1);
        let mut out = vec![0.0; rows * k];
        for (row, o) in x.chunks_exact(self.dim()).zip(out.chunks_exact_mut(k)) {
            self.transform_into(row, o);
        }
        out
    }

    /// Check the internal consistency of a deserialised PCA.
    pub(crate) fn validate(&self) -> Result<(), LearnError> {
        let k = self.eigenvalues.len();
        let ok = k > 0
            && self.components.len() == k * self.mean.len()
            && self.explained_variance_ratio.len() == k
            && self.scales.len() == k
            && self.scales.iter().all(|v| v.is_finite() && *v > 0.0)
            && self
                .components
                .iter()
                .chain(&self.mean)
                .all(|v| v.is_finite())
            && self.eigenvalues.iter().all(|v| v.is_finite() && *v >= 0.0);
        if ok {
            Ok(())
        } else {
            Err(LearnError::Corrupt {
                reason: "PCA shapes or values are inconsistent".into(),
            })
        }
    }
}

/// The factor applied to each projection.
fn scales_for(scaling: PcScaling, eigenvalues: &[f64]) -> Vec<f64> {
    let inv_sqrt = |v: f64| 1.0 / v.max(f64::MIN_POSITIVE).sqrt();
    match scaling {
        PcScaling::Raw => vec![1.0; eigenvalues.len()],
        PcScaling::Whiten => eigenvalues.iter().map(|&l| inv_sqrt(l)).collect(),
        PcScaling::UnitMean => {
            let mean = eigenvalues.iter().sum::<f64>() / eigenvalues.len().max(1) as f64;
            vec![inv_sqrt(mean); eigenvalues.len()]
        }
    }
}

fn column_means(x: &[f64], n: usize, dim: usize) -> Vec<f64> {
    let mut mean = vec![0.0; dim];
    for row in x.chunks_exact(dim) {
        mean.iter_mut().zip(row).for_each(|(m, v)| *m += v);
    }
    mean.iter_mut().for_each(|m| *m /= n as f64);
    mean
}

/// Population covariance (1/n) of centred data, as a faer matrix.
fn covariance(x: &[f64], n: usize, dim: usize, mean: &[f64]) -> Mat<f64> {
    let centred = Mat::from_fn(n, dim, |i, j| x[i * dim + j] - mean[j]);
    let mut cov = centred.transpose() * &centred;
    for j in 0..dim {
        for i in 0..dim {
            cov[(i, j)] /= n as f64;
        }
    }
    cov
}

fn count_for(keep: Components, ratio: &[f64]) -> Result<usize, LearnError> {
    match keep {
        Components::Count(0) => Err(LearnError::Config {
            field: "n_components",
            reason: "must be at least 1".into(),
        }),
        Components::Count(k) => Ok(k.min(ratio.len())),
        Components::Variance(f) if !(f > 0.0 && f <= 1.0) => Err(LearnError::Config {
            field: "variance",
            reason: format!("{f} is not in (0, 1]"),
        }),
        Components::Variance(f) => {
            let mut acc = 0.0;
            for (i, r) in ratio.iter().enumerate() {
                acc += r;
                if acc >= f - 1e-12 {
                    return Ok(i + 1);
                }
            }
            Ok(ratio.len())
        }
    }
}
