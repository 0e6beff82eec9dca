//! How close two sets of displacement fields are, tap by tap: the
//! per-coordinate RMS misfit (px) and the cosine between paired fields
//! (the figures a sensor file records for its held-out taps).
use crate::error::Result;
use crate::fields::{check_paired, Fields};
use serde::{Deserialize, Serialize};

/// Misfit of paired fields `a` (e.g. corrected twin) and `b` (real).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldStats {
    /// Taps compared.
    pub taps: usize,
    /// sqrt(mean over taps and coordinates of (a - b)^2), px.
    pub rms_px: f64,
    /// Mean over taps of cos(a_i, b_i).
    pub mean_cosine: f64,
    /// Median over taps of cos(a_i, b_i).
    pub median_cosine: f64,
}

/// Compare paired fields; errors on mismatched shapes. A tap where either
/// field is all zero has cosine 0.
pub fn field_stats(a: &Fields, b: &Fields) -> Result<FieldStats> {
    check_paired(a, b)?;
    let (am, bm) = (a.matrix(), b.matrix());
    let diff = am - bm;
    let n = a.len();
    let mut cos: Vec<f64> = (0..n)
        .map(|i| {
            let (x, y) = (am.row(i), bm.row(i));
            let den = x.norm() * y.norm();
            if den > 0.0 {
                x.dot(&y) / den
            } else {
                0.0
            }
        })
        .collect();
    cos.sort_by(f64::total_cmp);
    let median = match n {
        0 => f64::NAN,
        _ if !n.is_multiple_of(2) => cos[n / 2],
        _ => (cos[n / 2 - 1] + cos[n / 2]) / 2.0,
    };
    Ok(FieldStats {
        taps: n,
        rms_px: (diff.norm_squared() / diff.len().max(1) as f64).sqrt(),
        mean_cosine: cos.iter().sum::<f64>() / n.max(1) as f64,
        median_cosine: median,
    })
}
