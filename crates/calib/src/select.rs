//! Which real taps to label for calibration: a seeded rule that spans edge
//! position r and angle theta (issue 11: taps fitted on one half of either
//! range carry badly to the other half; shear need not be spanned).
//!
//! The rule, for `n` taps out of a pool:
//! 1. r and theta are scaled to [0, 1] by the pool's own min and max;
//! 2. the unit square is cut into k x k cells, k = floor(sqrt(n)); from each
//!    non-empty cell one tap is drawn uniformly at random (ChaCha8 seeded
//!    with `seed`), cells in row-major order (theta bins outer, r inner);
//! 3. the remaining taps are added one at a time by farthest-point
//!    (maximin) sampling in the scaled square among the unchosen taps, ties
//!    to the lowest index, so they fill the largest gaps.
//!
//! The result is sorted by pool index. [`check_span`] is the guard a user's
//! calibration taps must pass.
use crate::error::{CalibError, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// A tap's labels: edge position r (mm) and angle theta (deg).
pub type Label = (f64, f64);

/// Pick `n` taps of `labels` (indices into it) by the module's rule.
/// Errors on a bad label, `n` = 0 or `n` larger than the pool.
pub fn select_taps(labels: &[Label], n: usize, seed: u64) -> Result<Vec<usize>> {
    check_labels(labels)?;
    if n == 0 || n > labels.len() {
        return Err(CalibError::TooFewTaps {
            got: labels.len(),
            needed: n.max(1),
            recommended: n.max(1),
        });
    }
    let unit = scaled(labels);
    let k = (n as f64).sqrt().floor().max(1.0) as usize;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut chosen: Vec<usize> = Vec::with_capacity(n);
    for cell in cells(&unit, k) {
        if !cell.is_empty() {
            chosen.push(cell[rng.random_range(0..cell.len())]);
        }
    }
    fill_maximin(&unit, &mut chosen, n);
    chosen.sort_unstable();
    Ok(chosen)
}

/// Errors on a NaN or infinite label.
pub fn check_labels(labels: &[Label]) -> Result<()> {
    match labels
        .iter()
        .position(|(r, t)| !r.is_finite() || !t.is_finite())
    {
        Some(i) => Err(CalibError::BadLabel {
            index: i,
            r: labels[i].0,
            theta: labels[i].1,
        }),
        None => Ok(()),
    }
}

/// The labels scaled to [0, 1] by their min and max (0.5 when constant).
fn scaled(labels: &[Label]) -> Vec<(f64, f64)> {
    let (r0, r1) = range(labels.iter().map(|l| l.0));
    let (t0, t1) = range(labels.iter().map(|l| l.1));
    let unit = |v: f64, lo: f64, hi: f64| if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
    labels
        .iter()
        .map(|&(r, t)| (unit(r, r0, r1), unit(t, t0, t1)))
        .collect()
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
        (lo.min(x), hi.max(x))
    })
}

/// The taps of each of the k x k cells, theta bins outer, r bins inner.
fn cells(unit: &[(f64, f64)], k: usize) -> Vec<Vec<usize>> {
    let bin = |v: f64| ((v * k as f64).floor() as usize).min(k - 1);
    let mut out = vec![Vec::new(); k * k];
    for (i, &(r, t)) in unit.iter().enumerate() {
        out[bin(t) * k + bin(r)].push(i);
    }
    out
}

/// Add taps by farthest-point sampling until `chosen` holds `n`.
fn fill_maximin(unit: &[(f64, f64)], chosen: &mut Vec<usize>, n: usize) {
    let d2 = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).powi(2) + (a.1 - b.1).powi(2);
    let mut taken = vec![false; unit.len()];
    let mut gap = vec![f64::INFINITY; unit.len()];
    for &c in chosen.iter() {
        taken[c] = true;
    }
    for &c in chosen.iter() {
        for (i, g) in gap.iter_mut().enumerate() {
            *g = g.min(d2(unit[i], unit[c]));
        }
    }
    while chosen.len() < n {
        let next = (0..unit.len())
            .filter(|&i| !taken[i])
            .fold(None, |best: Option<usize>, i| match best {
                Some(b) if gap[b] >= gap[i] => Some(b),
                _ => Some(i),
            })
            .expect("n <= pool size");
        taken[next] = true;
        chosen.push(next);
        for (i, g) in gap.iter_mut().enumerate() {
            *g = g.min(d2(unit[i], unit[next]));
        }
    }
}

/// What calibration taps must cover.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpanRule {
    /// Least range of r over the taps, mm.
    pub min_r_range_mm: f64,
    /// Least range of theta over the taps, deg.
    pub min_theta_range_deg: f64,
}

impl Default for SpanRule {
    /// 4 mm and 30 deg: a bit under half the Bristol edge set's -5..5 mm and
    /// -45..45 deg.
    fn default() -> Self {
        SpanRule {
            min_r_range_mm: 4.0,
            min_theta_range_deg: 30.0,
        }
    }
}

/// Errors unless the taps' labels are finite, cover the rule's ranges, and
/// every quadrant of their (r, theta) box (cut at its middle) holds a tap.
pub fn check_span(labels: &[Label], rule: &SpanRule) -> Result<()> {
    check_labels(labels)?;
    let (r0, r1) = range(labels.iter().map(|l| l.0));
    let (t0, t1) = range(labels.iter().map(|l| l.1));
    let no_span = |reason: String| Err(CalibError::NoSpan { reason });
    if labels.is_empty() {
        return no_span("no taps".into());
    }
    if r1 - r0 < rule.min_r_range_mm {
        return no_span(format!(
            "r covers {r0:.2}..{r1:.2} mm, at least {} mm of range needed",
            rule.min_r_range_mm
        ));
    }
    if t1 - t0 < rule.min_theta_range_deg {
        return no_span(format!(
            "theta covers {t0:.1}..{t1:.1} deg, at least {} deg of range needed",
            rule.min_theta_range_deg
        ));
    }
    let (rm, tm) = ((r0 + r1) / 2.0, (t0 + t1) / 2.0);
    let mut seen = [false; 4];
    for &(r, t) in labels {
        seen[usize::from(r >= rm) + 2 * usize::from(t >= tm)] = true;
    }
    if let Some(q) = seen.iter().position(|s| !s) {
        let side = |hi: bool| if hi { "high" } else { "low" };
        return no_span(format!(
            "no tap with {} r and {} theta (split at r {rm:.2} mm, theta {tm:.1} deg)",
            side(q % 2 == 1),
            side(q >= 2)
        ));
    }
    Ok(())
}
