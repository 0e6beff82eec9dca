//! The few-shot linear correction of simulated fields towards real ones:
//! `real ~ sim + W sim + b`, W (2P x 2P) a ridge fit shrunk towards zero
//! (so towards "the twin is right"), b unpenalised, the penalty chosen by
//! exact leave-one-out on the calibration pairs only.
//!
//! With the inputs centred (and optionally standardised) to Z = U S V^T
//! (thin SVD, r = min(N, 2P) modes), the ridge fit for penalty lambda has the
//! hat matrix H = 11^T/N + U diag(s^2/(s^2+lambda)) U^T, and the
//! leave-one-out residual of tap i is e_i / (1 - H_ii) (the PRESS identity,
//! Hastie, Tibshirani & Friedman, Elements of Statistical Learning, eq. 7.52
//! and ex. 7.3). One SVD serves every penalty of the grid, and each penalty
//! costs O(N r 2P): with N = 100 taps of 254 coordinates this is the dual
//! (kernel) form's cost and takes milliseconds.
use crate::error::{CalibError, Result};
use crate::fields::{check_paired, Fields};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Fewest paired taps a fit accepts.
pub const MIN_TAPS: usize = 10;
/// Paired taps recommended (issue 11: 100 taps give 0.33 mm / 2.7 deg).
pub const RECOMMENDED_TAPS: usize = 100;

/// Settings of the fit; [`Default`] is the documented baseline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CorrectionParams {
    /// Scale each simulated coordinate to unit variance before the penalty
    /// (folded back into W: [`LinearCorrection::apply`] is always raw).
    pub standardise: bool,
    /// Penalty grid: lambda = s_max^2 10^e, e from `log10_min` to
    /// `log10_max` in `steps` equal steps (s_max the largest singular value).
    pub log10_min: f64,
    pub log10_max: f64,
    pub steps: usize,
    /// Keep only the leading `rank` output modes of the fitted change
    /// (reduced-rank ridge); `None`: full rank.
    pub rank: Option<usize>,
}

impl Default for CorrectionParams {
    fn default() -> Self {
        CorrectionParams {
            standardise: false,
            log10_min: -7.0,
            log10_max: 1.0,
            steps: 33,
            rank: None,
        }
    }
}

/// The affine correction `x -> x + W x + b` of a simulated field.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearCorrection {
    /// D x D, acting on a column field.
    pub w: DMatrix<f64>,
    /// D.
    pub b: DVector<f64>,
}

/// A fitted correction and how its penalty was chosen.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedCorrection {
    pub correction: LinearCorrection,
    /// The chosen penalty lambda (on the centred, possibly standardised inputs).
    pub penalty: f64,
    /// Leave-one-out per-coordinate RMS of the corrected field against the
    /// real one at the chosen penalty, px.
    pub loo_rms: f64,
    /// Per-coordinate RMS of the uncorrected misfit on the calibration taps, px.
    pub rms_before: f64,
    /// (lambda, leave-one-out RMS px) over the grid.
    pub loo_curve: Vec<(f64, f64)>,
    /// Number of calibration pairs.
    pub taps: usize,
}

impl LinearCorrection {
    /// The correction that changes nothing, for `dim` coordinates.
    pub fn identity(dim: usize) -> Self {
        LinearCorrection {
            w: DMatrix::zeros(dim, dim),
            b: DVector::zeros(dim),
        }
    }

    /// Coordinates a field (2P).
    pub fn dim(&self) -> usize {
        self.b.len()
    }

    /// Fit on paired taps: row i of `sim` is the twin replay of the real
    /// tap in row i of `real`. Errors on fewer than [`MIN_TAPS`] pairs,
    /// mismatched shapes or a bad grid.
    pub fn fit(sim: &Fields, real: &Fields, params: &CorrectionParams) -> Result<FittedCorrection> {
        check_paired(sim, real)?;
        check_params(params)?;
        if sim.len() < MIN_TAPS {
            return Err(CalibError::TooFewTaps {
                got: sim.len(),
                needed: MIN_TAPS,
                recommended: RECOMMENDED_TAPS,
            });
        }
        let prep = Prepared::new(sim, real, params.standardise);
        let svd = prep.z.clone().svd(true, true);
        let (u, s) = (svd.u.expect("u asked"), svd.singular_values);
        let v_t = svd.v_t.expect("v_t asked");
        let a = u.transpose() * &prep.rc; // r x D
        let s_max2 = s.max().powi(2).max(f64::MIN_POSITIVE);
        let curve: Vec<(f64, f64)> = penalty_grid(params)
            .map(|e| s_max2 * 10f64.powf(e))
            .map(|lam| (lam, loo_rms(&u, &s, &a, &prep.rc, lam)))
            .collect();
        let &(penalty, loo) = curve
            .iter()
            .filter(|(_, l)| l.is_finite())
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .ok_or_else(|| CalibError::Param("no penalty gave a finite leave-one-out".into()))?;
        let mut coef = coefficients(&v_t, &s, &a, penalty); // D x D, Z -> change
        if let Some(k) = params.rank {
            coef = reduce_rank(&prep.z, coef, k);
        }
        Ok(FittedCorrection {
            correction: prep.unfold(coef),
            penalty,
            loo_rms: loo,
            rms_before: rms(&(real.matrix() - sim.matrix())),
            loo_curve: curve,
            taps: sim.len(),
        })
    }

    /// The corrected fields `x + W x + b`, tap by tap.
    pub fn apply(&self, sim: &Fields) -> Result<Fields> {
        if sim.dim() != self.dim() {
            return Err(CalibError::Dimension {
                what: "coordinates a tap (2 x pins), fields vs correction".into(),
                expected: self.dim(),
                found: sim.dim(),
            });
        }
        let x = sim.matrix();
        let mut out = x + x * self.w.transpose();
        for mut row in out.row_iter_mut() {
            row += self.b.transpose();
        }
        Fields::from_matrix(out, "corrected fields")
    }
}

/// The grid's exponents e (lambda = s_max^2 10^e).
fn penalty_grid(p: &CorrectionParams) -> impl Iterator<Item = f64> + '_ {
    let step = (p.log10_max - p.log10_min) / (p.steps.max(2) - 1) as f64;
    (0..p.steps).map(move |k| p.log10_min + step * k as f64)
}

fn check_params(p: &CorrectionParams) -> Result<()> {
    let ok = p.steps >= 1 && p.log10_min.is_finite() && p.log10_max >= p.log10_min;
    if !ok {
        return Err(CalibError::Param(format!(
            "penalty grid 10^{}..10^{} in {} steps",
            p.log10_min, p.log10_max, p.steps
        )));
    }
    if p.rank == Some(0) {
        return Err(CalibError::Param(
            "rank 0 (use no correction instead)".into(),
        ));
    }
    Ok(())
}

/// Centred (and scaled) inputs and centred targets, with what undoes them.
struct Prepared {
    z: DMatrix<f64>,
    rc: DMatrix<f64>,
    mean_x: DVector<f64>,
    scale: DVector<f64>,
    mean_r: DVector<f64>,
}

impl Prepared {
    fn new(sim: &Fields, real: &Fields, standardise: bool) -> Self {
        let x = sim.matrix();
        let r = real.matrix() - x;
        let mean_x = col_means(x);
        let mean_r = col_means(&r);
        let mut z = x.clone();
        centre(&mut z, &mean_x);
        let mut rc = r;
        centre(&mut rc, &mean_r);
        let scale = if standardise {
            column_scales(&z)
        } else {
            DVector::from_element(x.ncols(), 1.0)
        };
        for (j, mut col) in z.column_iter_mut().enumerate() {
            col /= scale[j];
        }
        Prepared {
            z,
            rc,
            mean_x,
            scale,
            mean_r,
        }
    }

    /// Raw W and b from coefficients acting on Z: change = ((x - mu)/sigma) C + mean_r.
    fn unfold(&self, coef: DMatrix<f64>) -> LinearCorrection {
        let mut wt = coef; // rows: input coordinates
        for (j, mut row) in wt.row_iter_mut().enumerate() {
            row /= self.scale[j];
        }
        let b = &self.mean_r - wt.transpose() * &self.mean_x;
        // Rounded to f32 here, so that the stored tensors give identical taps.
        let f32_exact = |v: f64| v as f32 as f64;
        LinearCorrection {
            w: wt.transpose().map(f32_exact),
            b: b.map(f32_exact),
        }
    }
}

fn col_means(m: &DMatrix<f64>) -> DVector<f64> {
    DVector::from_iterator(m.ncols(), m.column_iter().map(|c| c.mean()))
}

fn centre(m: &mut DMatrix<f64>, mean: &DVector<f64>) {
    for (j, mut col) in m.column_iter_mut().enumerate() {
        col.add_scalar_mut(-mean[j]);
    }
}

/// Column standard deviations, floored at 1e-3 of their mean (a pin that
/// never moves keeps a finite scale).
fn column_scales(zc: &DMatrix<f64>) -> DVector<f64> {
    let n = zc.nrows().max(1) as f64;
    let sd = DVector::from_iterator(
        zc.ncols(),
        zc.column_iter().map(|c| (c.norm_squared() / n).sqrt()),
    );
    let floor = 1e-3 * sd.mean().max(f64::MIN_POSITIVE);
    sd.map(|v| v.max(floor))
}

/// Per-coordinate RMS of a matrix of residuals.
fn rms(m: &DMatrix<f64>) -> f64 {
    (m.norm_squared() / m.len().max(1) as f64).sqrt()
}

/// Exact leave-one-out per-coordinate RMS for penalty `lam` (PRESS).
fn loo_rms(
    u: &DMatrix<f64>,
    s: &DVector<f64>,
    a: &DMatrix<f64>,
    rc: &DMatrix<f64>,
    lam: f64,
) -> f64 {
    let n = u.nrows();
    let f = s.map(|v| v * v / (v * v + lam));
    let uf = u * DMatrix::from_diagonal(&f);
    let resid = rc - &uf * a;
    let mut total = 0.0;
    for i in 0..n {
        let h = 1.0 / n as f64 + uf.row(i).dot(&u.row(i));
        total += resid.row(i).norm_squared() / (1.0 - h).powi(2);
    }
    (total / (n * rc.ncols()) as f64).sqrt()
}

/// Ridge coefficients C (D x D) with Z C = U diag(s^2/(s^2+lam)) A.
fn coefficients(v_t: &DMatrix<f64>, s: &DVector<f64>, a: &DMatrix<f64>, lam: f64) -> DMatrix<f64> {
    let g = s.map(|v| v / (v * v + lam));
    v_t.transpose() * DMatrix::from_diagonal(&g) * a
}

/// Reduced-rank ridge: keep the `k` leading right singular directions of
/// the fitted changes Z C (Mukherjee & Zhu 2011).
fn reduce_rank(z: &DMatrix<f64>, coef: DMatrix<f64>, k: usize) -> DMatrix<f64> {
    let fitted = z * &coef;
    let svd = fitted.svd(false, true);
    let v_t = svd.v_t.expect("v_t asked");
    let k = k.min(v_t.nrows());
    let vk = v_t.rows(0, k).transpose();
    coef * &vk * vk.transpose()
}
