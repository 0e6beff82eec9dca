//! How close two sets of displacement fields are, tap by tap: the
//! per-coordinate RMS misfit (px) and the cosine between paired fields
//! (the figures a sensor file records for its held-out taps); and the
//! median these and the lab's timings use.
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
    // Summed in ascending order, as the figures have always been.
    cos.sort_by(f64::total_cmp);
    Ok(FieldStats {
        taps: n,
        rms_px: (diff.norm_squared() / diff.len().max(1) as f64).sqrt(),
        mean_cosine: cos.iter().sum::<f64>() / n.max(1) as f64,
        median_cosine: median(&cos).unwrap_or(f64::NAN),
    })
}

/// The median of `values` in any order (the mean of the two middle ones
/// for an even count); `None` without values.
pub fn median(values: &[f64]) -> Option<f64> {
    let mut sorted = values.to_vec();
    sorted.sort_unstable_by(f64::total_cmp);
    let n = sorted.len();
    (n > 0).then(|| (sorted[(n - 1) / 2] + sorted[n / 2]) / 2.0)
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn the_median_is_the_middle_value_or_the_mean_of_the_two() {
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[7.0]), Some(7.0));
        assert_eq!(median(&[5.0, 1.0, 4.0, 2.0, 3.0]), Some(3.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), Some(2.5));
        // Against the definition: half the values at or below, half at or
        // above, on an odd count of distinct values.
        let values: Vec<f64> = (0..101).map(|k| f64::from((k * 37) % 101)).collect();
        let m = median(&values).unwrap();
        let below = values.iter().filter(|v| **v < m).count();
        let above = values.iter().filter(|v| **v > m).count();
        assert_eq!((below, above), (50, 50));
    }
}
