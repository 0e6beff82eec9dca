//! The nearest-neighbour start kept with pins missing (issue 21, item 6):
//! when its first matching is settled by the tracker's margin, the
//! ordering equals the full coarse-to-fine path's. Synthetic 331-pin ring
//! frames with dropped and merged pins here; the shared real sets are
//! checked by `speed.rs` (the default tracker against the full path) and,
//! frame by frame on both parts of the 331-pin set, by
//! `examples/order_timing.rs --full --compare`.

use crate::common;

use common::{merged_dropped_shuffled, rings};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_vision::{KeyPoint, PinTracker};

/// A tap's keypoints: the layout sheared and bumped, with pins dropped and
/// a few neighbouring pairs merged into one point at their midpoint (as
/// touching pins are detected), in a shuffled order.
fn tap(reference: &[[f64; 2]], rng: &mut ChaCha8Rng) -> Vec<KeyPoint> {
    let shear = rng.random_range(-0.15..0.15);
    let bump = rng.random_range(0.0..2.5);
    let points: Vec<[f64; 2]> = reference
        .iter()
        .map(|r| {
            let (x, y) = (r[0] - 64.0, r[1] - 64.0);
            let g = bump * (-(x * x + y * y) / 300.0).exp();
            [
                r[0] + shear * y + g + rng.random_range(-0.3..0.3),
                r[1] + g * 0.5 + rng.random_range(-0.3..0.3),
            ]
        })
        .collect();
    merged_dropped_shuffled(points, 4, 0.97, rng)
}

/// On 60 synthetic taps with pins missing, the default tracker (the
/// nearest-neighbour start kept when settled) orders every point as the
/// full path does, bit for bit, and as the tracker that never keeps such
/// a start.
#[test]
fn settled_nearest_start_orders_synthetic_331_pin_taps_as_the_full_path() {
    let reference = rings();
    let fast = PinTracker::new(reference.clone()).expect("tracker");
    let before = PinTracker::new(reference.clone())
        .expect("tracker")
        .with_nearest_margin(None);
    let full = PinTracker::new(reference.clone())
        .expect("tracker")
        .with_nearest_start(false);
    let mut rng = ChaCha8Rng::seed_from_u64(2104);
    let mut with_missing = 0;
    for trial in 0..60 {
        let keypoints = tap(&reference, &mut rng);
        let (a, b, c) = (
            fast.order(&keypoints),
            before.order(&keypoints),
            full.order(&keypoints),
        );
        with_missing += usize::from(c.missing > 0);
        assert_eq!(a.matched, c.matched, "trial {trial}");
        assert_eq!(a.pins, c.pins, "trial {trial}");
        assert_eq!(b.pins, c.pins, "trial {trial}");
    }
    assert!(
        with_missing >= 50,
        "{with_missing} of 60 taps with pins missing"
    );
}
