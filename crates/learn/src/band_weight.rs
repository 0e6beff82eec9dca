//! A heavier weight for the training rows whose target lies in a band
//! ([`BandWeight`]): on the 331-pin edge the angle error sits where the
//! edge is far from the centre on one side (docs/results.md, "The 331-pin
//! edge over the full circle"), so those rows may count more in the loss.
//!
//! Training is per-sample SGD (eq. 3.21 one row at a time), so a row of
//! integer weight `w` is visited `w` times in every epoch's shuffled
//! order: its squared error counts `w` times in the epoch's sum, the loss
//! `sum_i w_i 0.5 ||y_i - t_i||^2` of a weighted least-squares fit. The
//! standardiser, PCA and target scaling are fitted on the rows as read,
//! once each; only the training order repeats rows. Nothing changes at
//! prediction.
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::targets::{linear_column, ModelTarget};
use serde::{Deserialize, Serialize};

/// The largest weight accepted: each epoch grows by `weight - 1` times
/// the band's rows.
pub const MAX_BAND_WEIGHT: usize = 16;

/// Rows whose target `target` lies in `[min, max]` (either end open when
/// absent, in the target's unit) count `weight` times in each epoch
/// ([`crate::ModelConfig::band_weight`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BandWeight {
    /// The target whose value picks the rows (a dataset's target name,
    /// e.g. `pose_2`; the edge task's `r`); not a circular one.
    pub target: String,
    /// The band's lower end (mm or deg, the target's unit); none: open.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    /// The band's upper end; none: open.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// How many times a row in the band is visited per epoch
    /// (2..=[`MAX_BAND_WEIGHT`]); the other rows once.
    pub weight: usize,
}

impl BandWeight {
    /// Check the weight and that the band has an end and is not empty.
    pub fn validate(&self) -> Result<(), LearnError> {
        if !(2..=MAX_BAND_WEIGHT).contains(&self.weight) {
            return Err(band_err(format!(
                "weight {} must lie in [2, {MAX_BAND_WEIGHT}]",
                self.weight
            )));
        }
        let ends = [self.min, self.max];
        if ends.iter().flatten().any(|v| !v.is_finite()) {
            return Err(band_err("the band's ends must be finite".into()));
        }
        match (self.min, self.max) {
            (None, None) => Err(band_err("give `min`, `max` or both".into())),
            (Some(lo), Some(hi)) if lo > hi => {
                Err(band_err(format!("min {lo} lies above max {hi}")))
            }
            _ => Ok(()),
        }
    }

    /// Whether `value` lies in the band.
    pub fn contains(&self, value: f64) -> bool {
        self.min.is_none_or(|lo| value >= lo) && self.max.is_none_or(|hi| value <= hi)
    }

    /// The epoch's rows of `train` (targets encoded as `outputs` name
    /// them): every row once, then every row in the band `weight - 1`
    /// more times, in row order (each epoch shuffles it). Error when
    /// `target` is not one of `outputs` or is circular.
    pub(crate) fn epoch_rows(
        &self,
        outputs: &[ModelTarget],
        train: &Dataset,
    ) -> Result<Vec<usize>, LearnError> {
        let column = self.column(outputs)?;
        let band: Vec<usize> = (0..train.n)
            .filter(|&i| self.contains(f64::from(train.y_row(i)[column])))
            .collect();
        let mut rows: Vec<usize> = (0..train.n).collect();
        for _ in 1..self.weight {
            rows.extend_from_slice(&band);
        }
        Ok(rows)
    }

    /// The encoded column of the band's target.
    fn column(&self, outputs: &[ModelTarget]) -> Result<usize, LearnError> {
        let why = "a band of an angle that wraps is not supported";
        linear_column(outputs, &self.target, why).map_err(band_err)
    }
}

/// The rows of one epoch of `train`: each once without a band weight.
pub(crate) fn epoch_rows(
    band: Option<&BandWeight>,
    outputs: &[ModelTarget],
    train: &Dataset,
) -> Result<Vec<usize>, LearnError> {
    match band {
        Some(b) => b.epoch_rows(outputs, train),
        None => Ok((0..train.n).collect()),
    }
}

fn band_err(reason: String) -> LearnError {
    LearnError::Config {
        field: "band_weight",
        reason,
    }
}
