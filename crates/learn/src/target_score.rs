//! One number for a model's errors on N named targets, so that a search
//! can rank models of any targets: each target's mean absolute error
//! (circular angles wrapped, [`crate::target_mae`]) divided by that
//! target's spread in the training data, summed. A millimetre and a
//! degree then weigh by how much each target varies.
use crate::targets::{target_mae, ModelTarget};

/// The mean absolute error of every target (in its unit, circular ones
/// wrapped) and their sum weighted by `1 / spread` (the training targets'
/// standard deviations, one a target); lower is better. A score that is
/// not a finite number (no rows, a prediction that is not a number, a
/// zero spread) is +inf, so it never ranks as best.
pub fn target_score(
    targets: &[ModelTarget],
    predicted: &[Vec<f64>],
    truth: &[Vec<f64>],
    spread: &[f64],
) -> (Vec<f64>, f64) {
    let mae = target_mae(targets, predicted, truth);
    let score = mae.iter().zip(spread).fold(0.0, |sum, (m, s)| sum + m / s);
    let score = if score.is_finite() && mae.len() == spread.len() {
        score
    } else {
        f64::INFINITY
    };
    (mae, score)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::targets::Unit;

    #[test]
    fn issue24_every_target_counts_and_circular_errors_are_wrapped() {
        let targets = vec![
            ModelTarget::new("d", Unit::Mm),
            ModelTarget::circular("a"),
            ModelTarget::new("t", Unit::Deg),
        ];
        let truth = vec![vec![1.0, 179.0, 10.0], vec![2.0, -90.0, 20.0]];
        let pred = vec![vec![1.5, -179.0, 12.0], vec![2.5, -92.0, 18.0]];
        let (mae, score) = target_score(&targets, &pred, &truth, &[0.5, 2.0, 4.0]);
        assert_eq!(mae, vec![0.5, 2.0, 2.0]);
        assert_eq!(score, 0.5 / 0.5 + 2.0 / 2.0 + 2.0 / 4.0);
    }

    #[test]
    fn issue24_a_score_that_is_not_a_number_is_infinite() {
        let targets = vec![ModelTarget::new("d", Unit::Mm)];
        let (_, score) = target_score(&targets, &[vec![f64::NAN]], &[vec![1.0]], &[1.0]);
        assert_eq!(score, f64::INFINITY);
        let (_, score) = target_score(&targets, &[], &[], &[1.0]);
        assert_eq!(score, f64::INFINITY);
    }
}
