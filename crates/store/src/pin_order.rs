//! Which pin is which: a displacement vector lists its pins in the order of
//! the reference frame they were matched against (detection order), so a
//! model only understands data ordered against the same reference pins as
//! its training data. Another reference frame of the same layout can still
//! list the pins in another order (the simulated and the real reference
//! differ in 56 of 127 places), and the numbers then mean something else to
//! the model. [`crate::StoredModel`] runs this check whenever a model meets
//! data or a rig's reference frame.
use tactrace_vision::median_spacing;

/// Pins further than this fraction of the reference's pin spacing from
/// their counterpart count as another pin.
const SAME_PIN_FRACTION: f64 = 0.3;

/// Why two lists of reference pins are not the same pins in the same order.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PinOrderError {
    /// Another number of pins.
    #[error("{data} reference pins, the model's training data had {model}")]
    Count { model: usize, data: usize },
    /// The same number, listed in another order (or another layout).
    #[error(
        "{far} of {total} reference pins are more than {tolerance_px:.1} px from the model's \
         (up to {worst_px:.0} px): the pins are listed in another order. Import or collect \
         the data against the same reference frame as the training data (for real frames \
         and a simulator, see `tactrace twin`)"
    )]
    Order {
        far: usize,
        total: usize,
        tolerance_px: f64,
        worst_px: f64,
    },
}

/// Why the pins `data` are not ordered like `model`'s (both px, reference
/// order), or `None` when every pin lies within 0.3 of a
/// spacing of its counterpart.
pub fn pin_order_mismatch(model: &[[f64; 2]], data: &[[f64; 2]]) -> Option<PinOrderError> {
    if model.len() != data.len() {
        return Some(PinOrderError::Count {
            model: model.len(),
            data: data.len(),
        });
    }
    let tolerance_px = SAME_PIN_FRACTION * median_spacing(model);
    let dist = |a: &[f64; 2], b: &[f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let far: Vec<f64> = model
        .iter()
        .zip(data)
        .map(|(a, b)| dist(a, b))
        .filter(|d| d.is_nan() || *d > tolerance_px)
        .collect();
    if far.is_empty() {
        return None;
    }
    Some(PinOrderError::Order {
        far: far.len(),
        total: model.len(),
        tolerance_px,
        worst_px: far.iter().copied().fold(0.0, f64::max),
    })
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
        assert!(why.to_string().starts_with("2 of 25"), "{why}");
        assert!(matches!(
            pin_order_mismatch(&a, &a[..24]),
            Some(PinOrderError::Count {
                model: 25,
                data: 24
            })
        ));
    }
}
