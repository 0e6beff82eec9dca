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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::targets::{encode_into, Unit};

    /// The edge's distance, its angle over the full circle and the tap's
    /// depth: the depth's encoded column comes after the angle's two.
    fn edge_and_depth() -> Vec<ModelTarget> {
        vec![
            ModelTarget::new("pose_2", Unit::Mm),
            ModelTarget::circular("pose_6"),
            ModelTarget::new("pose_3", Unit::Mm),
        ]
    }

    #[test]
    fn a_band_under_a_value_picks_the_shallow_rows_after_a_circular_target() {
        // Depths 3.0 .. 4.8 mm; distances and angles chosen so that a band
        // read from the wrong column (the distance, or the angle's sine or
        // cosine) would pick other rows.
        let outputs = edge_and_depth();
        let depths = [3.0, 4.8, 3.5, 4.2, 3.69, 3.71];
        let mut y = Vec::new();
        for (i, d) in depths.iter().enumerate() {
            let r = 6.0 - i as f32;
            encode_into(&outputs, &[r, 170.0 - 60.0 * i as f32, *d], &mut y);
        }
        let n = depths.len();
        let data = Dataset::new(vec![0.0; n], y, n, 1, 4).expect("data");
        let shallow = BandWeight {
            target: "pose_3".into(),
            min: None,
            max: Some(3.7),
            weight: 3,
        };
        shallow.validate().expect("a band with only `max` is valid");
        let rows = shallow.epoch_rows(&outputs, &data).expect("rows");
        assert_eq!(rows, [0, 1, 2, 3, 4, 5, 0, 2, 4, 0, 2, 4]);
        let angle = BandWeight {
            target: "pose_6".into(),
            ..shallow
        };
        let err = angle.epoch_rows(&outputs, &data).expect_err("circular");
        assert!(err.to_string().contains("circular"), "{err}");
    }
}
