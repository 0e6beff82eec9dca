//! One number for a model's errors on N targets, so configurations can be
//! ranked: each target's mean absolute error divided by a scale of its own
//! (its spread over the training rows, or a goal the user gives), summed.
//! Dividing puts millimetres and degrees on one footing and lets no target
//! be left out; a circular target's errors and spread are wrapped, so an
//! angle over the full circle is scored like any other.
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::targets::{wrap_deg, ModelTarget};

/// Spreads below this count as none: such a target is scaled by 1.
const MIN_SPREAD: f64 = 1e-9;

/// The scale each target's error is divided by in [`TargetScale::score`].
#[derive(Debug, Clone, PartialEq)]
pub struct TargetScale {
    scales: Vec<f64>,
}

impl TargetScale {
    /// Each target's spread over `train` (rows of the targets' values, in
    /// their units; [`target_spread`]).
    pub fn spreads(targets: &[ModelTarget], train: &Dataset) -> Result<Self, LearnError> {
        check_count(targets.len(), train.dim_y, "targets per sample")?;
        let scales = targets
            .iter()
            .enumerate()
            .map(|(j, t)| {
                let column = train.column(j).unwrap_or_default();
                let s = target_spread(t, &column);
                if s.is_finite() && s > MIN_SPREAD {
                    s
                } else {
                    1.0
                }
            })
            .collect();
        Ok(Self { scales })
    }

    /// Each target's goal (its error figure to reach, in its unit), one a
    /// target in order; each must be positive and finite.
    pub fn goals(targets: &[ModelTarget], goals: &[f64]) -> Result<Self, LearnError> {
        check_count(targets.len(), goals.len(), "goals")?;
        if let Some((t, g)) = targets
            .iter()
            .zip(goals)
            .find(|(_, g)| !(g.is_finite() && **g > 0.0))
        {
            return Err(LearnError::Targets {
                reason: format!(
                    "the goal of `{}` is {g}; it must be a positive number",
                    t.name
                ),
            });
        }
        Ok(Self {
            scales: goals.to_vec(),
        })
    }

    /// The scales, one a target, in the targets' units.
    pub fn scales(&self) -> &[f64] {
        &self.scales
    }

    /// `sum_j mae[j] / scale[j]` over every target (lower is better); +inf
    /// when an error is missing or not a number, so such a configuration
    /// ranks last.
    pub fn score(&self, mae: &[f64]) -> f64 {
        if mae.len() != self.scales.len() || mae.iter().any(|m| !m.is_finite()) {
            return f64::INFINITY;
        }
        let s: f64 = mae.iter().zip(&self.scales).map(|(m, s)| m / s).sum();
        if s.is_finite() {
            s
        } else {
            f64::INFINITY
        }
    }
}

/// The spread of one target's `values` (in its unit): the population
/// standard deviation; for a circular target the root mean square of the
/// wrapped deviations from the circular mean direction (the standard
/// deviation for angles bunched away from +-180, about 104 deg for angles
/// spread over the whole circle). NaN for no values.
pub fn target_spread(target: &ModelTarget, values: &[f32]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let n = values.len() as f64;
    let centre = if target.circular {
        let (s, c) = values.iter().fold((0.0, 0.0), |(s, c), &v| {
            let a = f64::from(v).to_radians();
            (s + a.sin(), c + a.cos())
        });
        f64::atan2(s, c).to_degrees()
    } else {
        values.iter().map(|&v| f64::from(v)).sum::<f64>() / n
    };
    let sq: f64 = values
        .iter()
        .map(|&v| {
            let d = f64::from(v) - centre;
            if target.circular {
                wrap_deg(d).powi(2)
            } else {
                d * d
            }
        })
        .sum();
    (sq / n).sqrt()
}

fn check_count(expected: usize, got: usize, what: &'static str) -> Result<(), LearnError> {
    if expected == got {
        Ok(())
    } else {
        Err(LearnError::Shape {
            what,
            expected,
            got,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::targets::Unit;

    #[test]
    fn circular_spread_wraps_and_plain_spread_is_the_std() {
        let a = ModelTarget::circular("a");
        // Bunched round +-180: the wrapped spread is small, the linear std huge.
        let near = [179.0f32, -179.0, 178.0, -178.0];
        let s = target_spread(&a, &near);
        assert!((s - (2.5f64).sqrt()).abs() < 1e-3, "{s}");
        let plain = ModelTarget::new("t", Unit::Deg);
        assert!(target_spread(&plain, &near) > 170.0);
        // Uniform over the circle: about 360 / sqrt(12).
        let uniform: Vec<f32> = (0..3600).map(|k| -180.0 + 0.1 * k as f32).collect();
        let u = target_spread(&a, &uniform);
        assert!((u - 360.0 / 12f64.sqrt()).abs() < 0.5, "{u}");
        let mm = ModelTarget::new("r", Unit::Mm);
        assert!((target_spread(&mm, &[1.0, 3.0]) - 1.0).abs() < 1e-12);
        assert!(target_spread(&mm, &[]).is_nan());
    }

    #[test]
    fn score_sums_every_target_over_its_scale() {
        let targets = [
            ModelTarget::new("r", Unit::Mm),
            ModelTarget::circular("a"),
            ModelTarget::new("d", Unit::Mm),
        ];
        let goals = TargetScale::goals(&targets, &[0.25, 3.0, 0.04]).unwrap();
        let s = goals.score(&[0.5, 3.0, 0.02]);
        assert!((s - (2.0 + 1.0 + 0.5)).abs() < 1e-12, "{s}");
        assert_eq!(goals.score(&[0.5, 3.0]), f64::INFINITY);
        assert_eq!(goals.score(&[0.5, f64::NAN, 0.0]), f64::INFINITY);
        assert!(TargetScale::goals(&targets, &[0.25, 0.0, 0.04]).is_err());
        assert!(TargetScale::goals(&targets, &[0.25]).is_err());
        // A constant target is scaled by 1, not divided by zero.
        let data = Dataset::new(
            vec![0.0; 2],
            vec![1.0, 170.0, 5.0, 3.0, -170.0, 5.0],
            2,
            1,
            3,
        )
        .unwrap();
        let spread = TargetScale::spreads(&targets, &data).unwrap();
        let sc = spread.scales();
        assert!((sc[0] - 1.0).abs() < 1e-12 && (sc[1] - 10.0).abs() < 1e-3 && sc[2] == 1.0);
    }
}
