//! Which pin is which: a displacement vector lists its pins in the order of
//! the reference frame they were matched against (detection order), so a
//! model only understands data ordered against the same reference pins as
//! its training data. Another reference frame of the same layout can still
//! list the pins in another order (the simulated and the real reference
//! differ in 56 of 127 places), and the numbers then mean something else to
//! the model. These checks refuse such data instead of predicting garbage.
use crate::error::{LabError, Result};
use std::path::Path;

/// Pins further than this fraction of the reference's pin spacing from
/// their counterpart count as another pin.
const SAME_PIN_FRACTION: f64 = 0.3;

/// Why the pins `data` are not ordered like `model`'s (both px, reference
/// order), or `None` when every pin lies within [`SAME_PIN_FRACTION`] of a
/// spacing of its counterpart.
pub fn pin_order_mismatch(model: &[[f64; 2]], data: &[[f64; 2]]) -> Option<String> {
    if model.len() != data.len() {
        return Some(format!(
            "{} reference pins, the model's training data had {}",
            data.len(),
            model.len()
        ));
    }
    let tolerance = SAME_PIN_FRACTION * spacing(model);
    let dist = |a: &[f64; 2], b: &[f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let far: Vec<f64> = model
        .iter()
        .zip(data)
        .map(|(a, b)| dist(a, b))
        .filter(|d| d.is_nan() || *d > tolerance)
        .collect();
    if far.is_empty() {
        return None;
    }
    let worst = far.iter().copied().fold(0.0, f64::max);
    Some(format!(
        "{} of {} reference pins are more than {tolerance:.1} px from the model's \
         (up to {worst:.0} px): the pins are listed in another order",
        far.len(),
        model.len()
    ))
}

/// Median distance from each pin to its nearest neighbour, px (1 for fewer
/// than two pins).
fn spacing(pins: &[[f64; 2]]) -> f64 {
    if pins.len() < 2 {
        return 1.0;
    }
    let mut nearest: Vec<f64> = pins
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let others = pins.iter().enumerate().filter(|(j, _)| *j != i);
            others
                .map(|(_, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    nearest.sort_by(f64::total_cmp);
    nearest[nearest.len() / 2]
}

/// Refuse `data` (named by `what`) whose pins follow another reference than
/// the model's `model_pins` (`None`: a model saved without them, not checked).
pub fn check_pin_order(
    model_pins: Option<&[[f64; 2]]>,
    data_pins: &[[f64; 2]],
    what: &Path,
) -> Result<()> {
    let Some(model_pins) = model_pins else {
        return Ok(());
    };
    match pin_order_mismatch(model_pins, data_pins) {
        None => Ok(()),
        Some(why) => Err(LabError::Format {
            path: what.to_path_buf(),
            reason: format!(
                "not ordered like the model's training data: {why}. Import or \
                 collect it against the same reference frame as the training data \
                 (for real frames and a simulator, see `tactrace twin`)"
            ),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<[f64; 2]> {
        (0..25)
            .map(|k| [(k % 5) as f64 * 10.0, (k / 5) as f64 * 10.0])
            .collect()
    }

    #[test]
    fn the_same_pins_slightly_moved_are_the_same_order() {
        let a = grid();
        let b: Vec<[f64; 2]> = a.iter().map(|p| [p[0] + 1.5, p[1] - 1.5]).collect();
        assert_eq!(pin_order_mismatch(&a, &b), None);
    }

    #[test]
    fn two_swapped_pins_or_another_count_are_refused() {
        let a = grid();
        let mut b = a.clone();
        b.swap(3, 4);
        let why = pin_order_mismatch(&a, &b).expect("a swap");
        assert!(why.starts_with("2 of 25"), "{why}");
        assert!(pin_order_mismatch(&a, &a[..24]).is_some());
        let err = check_pin_order(Some(&a), &b, Path::new("data/x")).unwrap_err();
        assert!(
            err.is_bad_input() && err.to_string().contains("data/x"),
            "{err}"
        );
        assert!(check_pin_order(None, &b, Path::new("data/x")).is_ok());
    }
}
