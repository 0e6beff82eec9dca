//! The edge position a model trained on the simulator alone reads off the
//! real calibration taps, mapped back to their labels: a per-sensor
//! correction of the twin's position labels (docs/calibration.md, "The
//! position map").
//!
//! A model trained on the calibrated simulator's twin (without the real
//! taps) reads a real tap labelled `r` as `p`, and on the 331-pin edge
//! set it reads it too far towards the object (by about 0.4 mm at
//! `r` 0-4 mm, less near the ends). The map is the least-squares quadratic
//!
//! `m(p) = p + c0 + c1 p + c2 p^2`,   minimising `sum_i (r_i - m(p_i))^2`
//!
//! over the N calibration taps (the normal equations of the three
//! coefficients, solved exactly). Relabelling each simulated tap rendered
//! at `s` as `m(s)` makes the twin say what the real sensor would have
//! been labelled when it looked like that tap, since the twin-trained
//! model reads its own taps at their rendered position (`p = s`). The
//! map must rise over the positions read (`1 + c1 + 2 c2 p > 0`), or
//! two simulated positions would share a label; a map that folds is
//! refused.
use crate::error::{CalibError, Result};
use crate::ridge::MIN_TAPS;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// `m(p) = p + c0 + c1 p + c2 p^2` (mm), fitted on read and labelled
/// positions of real taps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PositionMap {
    /// `[c0 (mm), c1, c2 (1/mm)]`.
    pub coefficients: [f64; 3],
    /// The range of positions read that the map was fitted on, mm.
    pub range_mm: [f64; 2],
    /// RMS of `r - p` over the taps, mm (before the map).
    pub rms_before_mm: f64,
    /// RMS of `r - m(p)` over the taps, mm (after it).
    pub rms_after_mm: f64,
    /// Taps fitted on.
    pub taps: usize,
}

impl PositionMap {
    /// Fit the map on the positions a twin-trained model `read` off real
    /// taps and their `labelled` positions (mm, one each). Errors on
    /// mismatched or too few taps ([`MIN_TAPS`]), non-finite values, read
    /// positions without spread, or a map that does not rise over them.
    pub fn fit(read: &[f64], labelled: &[f64]) -> Result<Self> {
        check(read, labelled)?;
        let residual: Vec<f64> = labelled.iter().zip(read).map(|(r, p)| r - p).collect();
        let coefficients = least_squares(read, &residual)?;
        let lo = read.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = read.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut map = PositionMap {
            coefficients,
            range_mm: [lo, hi],
            rms_before_mm: rms(residual.iter().copied()),
            rms_after_mm: 0.0,
            taps: read.len(),
        };
        if !map.rises() {
            return Err(CalibError::Param(format!(
                "the position map {} folds over the positions read ({lo:.2} to {hi:.2} mm): \
                 the model's readings of the calibration taps do not rise with their labels",
                map.describe()
            )));
        }
        map.rms_after_mm = rms(labelled.iter().zip(read).map(|(r, &p)| r - map.apply(p)));
        Ok(map)
    }

    /// The labelled position of a tap read (or rendered) at `p` mm.
    pub fn apply(&self, p: f64) -> f64 {
        let [c0, c1, c2] = self.coefficients;
        p + c0 + c1 * p + c2 * p * p
    }

    /// Whether `m` rises over [`Self::range_mm`]: its slope
    /// `1 + c1 + 2 c2 p`, linear in `p`, is positive at both ends.
    pub fn rises(&self) -> bool {
        let [_, c1, c2] = self.coefficients;
        self.range_mm.iter().all(|&p| 1.0 + c1 + 2.0 * c2 * p > 0.0)
    }

    /// One line: the map and its fit.
    pub fn describe(&self) -> String {
        let [c0, c1, c2] = self.coefficients;
        format!(
            "r = p {c0:+.3} mm {c1:+.4} p {c2:+.5}/mm p^2 (RMS over {} taps {:.3} -> {:.3} mm)",
            self.taps, self.rms_before_mm, self.rms_after_mm
        )
    }
}

fn check(read: &[f64], labelled: &[f64]) -> Result<()> {
    if read.len() != labelled.len() {
        return Err(CalibError::Dimension {
            what: "positions read vs labelled".into(),
            expected: labelled.len(),
            found: read.len(),
        });
    }
    if read.len() < MIN_TAPS {
        return Err(CalibError::TooFewTaps {
            got: read.len(),
            needed: MIN_TAPS,
            recommended: crate::ridge::RECOMMENDED_TAPS,
        });
    }
    for (index, (&p, &r)) in read.iter().zip(labelled).enumerate() {
        if !(p.is_finite() && r.is_finite()) {
            return Err(CalibError::BadLabel { index, r, theta: p });
        }
    }
    Ok(())
}

/// `[c0, c1, c2]` minimising `sum (y - c0 - c1 x - c2 x^2)^2`: the normal
/// equations on the centred and scaled `x` (for conditioning), solved by
/// LU, and mapped back.
fn least_squares(x: &[f64], y: &[f64]) -> Result<[f64; 3]> {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let spread = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
    if spread < 1e-9 {
        return Err(CalibError::Param(
            "the positions read do not vary: no position map can be fitted".into(),
        ));
    }
    let u: Vec<f64> = x.iter().map(|v| (v - mean) / spread).collect();
    let mut a = Matrix3::zeros();
    let mut b = Vector3::zeros();
    for (&ui, &yi) in u.iter().zip(y) {
        let f = Vector3::new(1.0, ui, ui * ui);
        a += f * f.transpose();
        b += f * yi;
    }
    let d = a
        .lu()
        .solve(&b)
        .filter(|d| d.iter().all(|v| v.is_finite()))
        .ok_or_else(|| {
            CalibError::Param("the positions read take fewer than three values".into())
        })?;
    let (d0, d1, d2) = (d[0], d[1], d[2]);
    // y = d0 + d1 u + d2 u^2 with u = (x - mean) / spread.
    let (s, m) = (spread, mean);
    Ok([
        d0 - d1 * m / s + d2 * m * m / (s * s),
        d1 / s - 2.0 * d2 * m / (s * s),
        d2 / (s * s),
    ])
}

fn rms(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), e| (s + e * e, n + 1));
    (s / n.max(1) as f64).sqrt()
}
