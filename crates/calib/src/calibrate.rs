//! The whole few-shot calibration of `tactrace calibrate` in one pure call:
//! check the user's paired taps, pick the calibration taps by the seeded
//! spanning rule, fit the correction, score it on the taps left out, and
//! describe it for the sensor file.
use crate::error::{CalibError, Result};
use crate::fields::{check_paired, Fields};
use crate::record::{CalibrationRecord, Selection, FORMAT_VERSION};
use crate::ridge::{
    CorrectionParams, FittedCorrection, LinearCorrection, MIN_TAPS, RECOMMENDED_TAPS,
};
use crate::select::{check_labels, check_span, select_taps, Label, SpanRule};
use crate::stats::field_stats;

/// What to calibrate with.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationPlan {
    /// Calibration taps to pick (`None`: every given tap, nothing held out).
    pub samples: Option<usize>,
    /// Seed of the selection.
    pub seed: u64,
    pub params: CorrectionParams,
    pub span: SpanRule,
}

impl Default for CalibrationPlan {
    /// 100 taps, seed 1, the baseline ridge, the default span rule.
    fn default() -> Self {
        CalibrationPlan {
            samples: Some(RECOMMENDED_TAPS),
            seed: 1,
            params: CorrectionParams::default(),
            span: SpanRule::default(),
        }
    }
}

/// A fitted calibration: the correction, its description, and the chosen
/// real taps (for training recipes that add them, [`real_tap_repeats`]).
#[derive(Debug, Clone)]
pub struct Calibration {
    pub correction: LinearCorrection,
    pub record: CalibrationRecord,
    pub fit: FittedCorrection,
    /// The chosen real taps' fields and labels, in selection order.
    pub real_taps: Fields,
    pub labels: Vec<Label>,
}

/// Calibrate on paired taps: row i of `sim` is the twin replay of the real
/// tap in row i of `real`, labelled `labels[i]`. Errors on mismatched
/// shapes or counts, bad labels or fields, fewer taps than needed, or
/// chosen taps that do not span r and theta.
pub fn calibrate(
    sim: &Fields,
    real: &Fields,
    labels: &[Label],
    plan: &CalibrationPlan,
) -> Result<Calibration> {
    check_inputs(sim, real, labels)?;
    let chosen = choose(labels, plan)?;
    let picked: Vec<Label> = chosen.iter().map(|&i| labels[i]).collect();
    check_span(&picked, &plan.span)?;
    let (sim_c, real_c) = (sim.subset(&chosen), real.subset(&chosen));
    let fit = LinearCorrection::fit(&sim_c, &real_c, &plan.params)?;
    let rest: Vec<usize> = (0..labels.len())
        .filter(|i| chosen.binary_search(i).is_err())
        .collect();
    let (before, after) = if rest.is_empty() {
        (None, None)
    } else {
        let (s, r) = (sim.subset(&rest), real.subset(&rest));
        let corrected = fit.correction.apply(&s)?;
        (
            Some(field_stats(&s, &r)?),
            Some(field_stats(&corrected, &r)?),
        )
    };
    let record = CalibrationRecord {
        format_version: FORMAT_VERSION,
        pins: sim.dim() / 2,
        params: plan.params.clone(),
        penalty: fit.penalty,
        loo_rms_px: fit.loo_rms,
        selection: Selection {
            seed: plan.seed,
            samples: chosen.len(),
            indices: chosen.clone(),
        },
        held_out_before: before,
        held_out_after: after,
        pin_jitter: None,
    };
    Ok(Calibration {
        correction: fit.correction.clone(),
        record,
        fit,
        real_taps: real_c,
        labels: picked,
    })
}

/// How many times to repeat N calibration taps so that they make up about
/// a third of a training set with `twin_taps` corrected twin taps (half as
/// many rows as the twin; at least once).
pub fn real_tap_repeats(twin_taps: usize, n: usize) -> usize {
    ((twin_taps as f64 / (2 * n.max(1)) as f64).round() as usize).max(1)
}

fn check_inputs(sim: &Fields, real: &Fields, labels: &[Label]) -> Result<()> {
    check_paired(sim, real)?;
    if !sim.dim().is_multiple_of(2) {
        return Err(CalibError::Dimension {
            what: "coordinates a tap (must be 2 x pins)".into(),
            expected: sim.dim() + 1,
            found: sim.dim(),
        });
    }
    if labels.len() != sim.len() {
        return Err(CalibError::Dimension {
            what: "labels vs taps".into(),
            expected: sim.len(),
            found: labels.len(),
        });
    }
    check_labels(labels)
}

/// The chosen tap indices, sorted.
fn choose(labels: &[Label], plan: &CalibrationPlan) -> Result<Vec<usize>> {
    let n = plan.samples.unwrap_or(labels.len());
    if n < MIN_TAPS || labels.len() < n {
        return Err(CalibError::TooFewTaps {
            got: n.min(labels.len()),
            needed: n.max(MIN_TAPS),
            recommended: RECOMMENDED_TAPS,
        });
    }
    match plan.samples {
        Some(n) => select_taps(labels, n, plan.seed),
        None => Ok((0..labels.len()).collect()),
    }
}
