//! The speed cuts of the 331-pin ordering (issue 21, item 6) change no
//! pin: the default tracker against the same tracker with the cuts off
//! (`PinTracker::with_speed_cuts(false)`, the ordering computed as
//! before them), bit for bit, on synthetic ring and hexagonal taps and on
//! the shared 331-pin shear set and 127-pin edge set. The real-data tests
//! fail when the data is absent unless TACTRACE_SKIP_REAL_DATA=1 (see
//! `tactrace_testdata`). Every frame of both parts of the 331-pin set is
//! compared by `examples/order_timing.rs --plain --compare` and `--dump`.
//! So is the split pass started from the first pass's pins
//! (`PinTracker::with_seeded_split`; `order_timing --unseeded --compare`),
//! and the first pass's propagated start
//! (`PinTracker::with_propagated_start`; `order_timing --unpropagated
//! --compare`, and `--dump` of both builds on every frame of both sets).

use crate::common;

use common::{load, merged_dropped_shuffled, real_127_extractors, rings, shear_set_331};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_vision::{Detection, Frame, KeyPoint, PinTracker, Tracked};

/// `a` and `b` the same, bit for bit (pins, flags and counts).
fn assert_same(a: &Tracked, b: &Tracked, what: &str) {
    let bits = |t: &Tracked| -> Vec<[u64; 2]> {
        t.pins
            .iter()
            .map(|p| [p[0].to_bits(), p[1].to_bits()])
            .collect()
    };
    assert_eq!(bits(a), bits(b), "{what}: pins differ");
    assert_eq!(a.matched, b.matched, "{what}: matched flags differ");
    assert_eq!((a.missing, a.extra), (b.missing, b.extra), "{what}");
}

/// Held-out frames and their detections.
type HeldFrames = Vec<(std::path::PathBuf, Detection)>;

/// The 600 val frames of the 331-pin shear set with the default tracker
/// and one with `change` made, or `None` when the set is absent.
fn trackers_331(
    change: impl FnOnce(PinTracker) -> PinTracker,
) -> Option<(HeldFrames, PinTracker, PinTracker)> {
    let set = tactrace_testdata::shared_set("tactip331-edge2d-shear", "README.md")?;
    let (held, rest) = shear_set_331(&set);
    let usual = PinTracker::new(rest.clone()).expect("tracker");
    let changed = change(PinTracker::new(rest).expect("tracker"));
    Some((held, usual, changed))
}

/// Every 5th frame of the shared 127-pin set, as `PinExtractor::extract`
/// reads it, with the default tracker and one with `change` made: the same
/// pins bit for bit (or the same refusal).
fn same_on_127_frames(change: impl FnOnce(PinTracker) -> PinTracker) {
    let Some((usual, changed, frames)) = real_127_extractors(change) else {
        return;
    };
    for path in frames.iter().step_by(5) {
        let frame: Frame = load(path).to_luma8();
        match (usual.extract(&frame), changed.extract(&frame)) {
            (Ok(a), Ok(b)) => assert_same(&a, &b, &path.display().to_string()),
            (a, b) => assert_eq!(a.is_ok(), b.is_ok(), "{}", path.display()),
        }
    }
}

/// A tap on `reference` (spacing `s` px, centre `c`): sheared and bumped,
/// pins dropped, neighbouring pairs merged at their midpoint, shuffled.
fn tap(reference: &[[f64; 2]], s: f64, c: f64, rng: &mut ChaCha8Rng) -> Vec<KeyPoint> {
    let shear = rng.random_range(-0.15..0.15);
    let bump = s * rng.random_range(0.0..0.5);
    let points: Vec<[f64; 2]> = reference
        .iter()
        .map(|r| {
            let (x, y) = (r[0] - c, r[1] - c);
            let g = bump * (-(x * x + y * y) / (12.0 * s * s)).exp();
            let j = 0.06 * s;
            [
                r[0] + shear * y + g + rng.random_range(-j..j),
                r[1] + 0.5 * g + rng.random_range(-j..j),
            ]
        })
        .collect();
    merged_dropped_shuffled(points, 5, 0.96, rng)
}

/// A 127-pin hexagonal lattice, 11 px apart, centred at (100, 100).
fn hexagon() -> Vec<[f64; 2]> {
    let mut pins = Vec::new();
    for q in -6i32..=6 {
        for r in -6i32..=6 {
            if (q + r).abs() <= 6 && pins.len() < 127 {
                let (q, r) = (f64::from(q), f64::from(r));
                pins.push([100.0 + 11.0 * (q + 0.5 * r), 100.0 + 11.0 * 0.866 * r]);
            }
        }
    }
    pins
}

/// On 80 synthetic taps of each layout (331-pin rings, 127-pin lattice)
/// with pins missing and merged, the cuts give the same pins bit for bit.
#[test]
fn speed_cuts_order_synthetic_taps_bit_for_bit() {
    for (reference, s, c) in [(rings(), 5.0, 64.0), (hexagon(), 11.0, 100.0)] {
        let fast = PinTracker::new(reference.clone()).expect("tracker");
        let plain = PinTracker::new(reference.clone())
            .expect("tracker")
            .with_speed_cuts(false);
        let mut rng = ChaCha8Rng::seed_from_u64(331);
        let mut missing = 0;
        for trial in 0..80 {
            let keypoints = tap(&reference, s, c, &mut rng);
            let (a, b) = (fast.order(&keypoints), plain.order(&keypoints));
            missing += usize::from(b.missing > 0);
            assert_same(&a, &b, &format!("{} pins, trial {trial}", reference.len()));
        }
        assert!(missing >= 20, "only {missing} taps with pins missing");
    }
}

/// 600 held-out frames of the 331-pin shear set (val part), as
/// `tests/it/speed.rs` reads them: the same pins bit for bit with the cuts.
#[test]
fn speed_cuts_order_331_pin_frames_bit_for_bit() {
    let Some((held, fast, plain)) = trackers_331(|t| t.with_speed_cuts(false)) else {
        return;
    };
    let mut split = 0;
    for (path, detection) in &held {
        let (a, b) = (fast.track(detection), plain.track(detection));
        split += usize::from(!detection.clusters.is_empty());
        assert_same(&a, &b, &path.display().to_string());
    }
    assert!(split >= 100, "only {split} frames with touching pins");
}

/// The same 600 val frames: the split pass started from the first
/// pass's pins (the default) gives the pins of the split pass from scratch
/// (`PinTracker::with_seeded_split(false)`), bit for bit.
#[test]
fn seeded_split_pass_orders_331_pin_frames_bit_for_bit() {
    let Some((held, seeded, scratch)) = trackers_331(|t| t.with_seeded_split(false)) else {
        return;
    };
    let mut split = 0;
    for (path, detection) in &held {
        let (a, b) = (seeded.track(detection), scratch.track(detection));
        let first = seeded.first_pass(&detection.points);
        split += usize::from(first.tracked().missing > 0 && !detection.clusters.is_empty());
        assert_same(&a, &b, &path.display().to_string());
    }
    assert!(split >= 100, "only {split} frames through the split pass");
}

/// Every 5th frame of the shared 127-pin set, as `PinExtractor::extract`
/// reads it: the same pins bit for bit with the cuts.
#[test]
fn speed_cuts_order_127_pin_frames_bit_for_bit() {
    same_on_127_frames(|t| t.with_speed_cuts(false));
}

/// The same 600 val frames: the first pass from the propagated start (the
/// default) gives the pins of the tracker without it
/// (`PinTracker::with_propagated_start(false)`), bit for bit, with and
/// without the split pass.
#[test]
fn propagated_start_orders_331_pin_frames_bit_for_bit() {
    let Some((held, on, off)) = trackers_331(|t| t.with_propagated_start(false)) else {
        return;
    };
    for (path, detection) in &held {
        let what = path.display().to_string();
        assert_same(&on.track(detection), &off.track(detection), &what);
        let (a, b) = (
            on.first_pass(&detection.points),
            off.first_pass(&detection.points),
        );
        assert_same(a.tracked(), b.tracked(), &what);
    }
}

/// Every 5th frame of the shared 127-pin set, as `PinExtractor::extract`
/// reads it: the same pins bit for bit with the propagated start as
/// without.
#[test]
fn propagated_start_orders_127_pin_frames_bit_for_bit() {
    same_on_127_frames(|t| t.with_propagated_start(false));
}
