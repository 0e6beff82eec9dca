//! Pin ordering under large synthetic deformations, where plain
//! nearest-neighbour matching would swap pins, plus the error paths of the
//! extractor.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_testdata::layouts::hex_lattice;
use tactrace_vision::{BlobParams, Frame, KeyPoint, PinExtractor, PinTracker, VisionError};

const SPACING: f64 = 11.0;

/// The 127 centres of a hexagonal patch of 6 rings, spacing 11 px, centred at (128, 128).
fn hex_reference() -> Vec<[f64; 2]> {
    hex_lattice([128.0, 128.0], SPACING, 6)
}

/// Translation + radial bump + swirl around an off-centre point: smooth and
/// fold-free (its Jacobian stays near the identity).
fn raw_field(p: [f64; 2]) -> [f64; 2] {
    let c = [143.0, 118.0];
    let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
    let g = (-(dx * dx + dy * dy) / (2.0 * 25.0f64.powi(2))).exp();
    let (radial, swirl) = (0.7 * g, 0.3 * g);
    [
        6.0 + radial * dx - swirl * dy,
        -5.0 + radial * dy + swirl * dx,
    ]
}

/// The field scaled so that its largest displacement over the pins is 20 px.
fn field(reference: &[[f64; 2]]) -> impl Fn([f64; 2]) -> [f64; 2] {
    let peak = reference
        .iter()
        .map(|&p| {
            let d = raw_field(p);
            d[0].hypot(d[1])
        })
        .fold(0.0, f64::max);
    move |p| {
        let d = raw_field(p);
        [d[0] * 20.0 / peak, d[1] * 20.0 / peak]
    }
}

fn keypoint(p: [f64; 2]) -> KeyPoint {
    KeyPoint {
        x: p[0],
        y: p[1],
        size: 5.0,
    }
}

#[test]
fn large_smooth_field_with_a_dropped_and_an_added_blob_keeps_every_pin() {
    let reference = hex_reference();
    assert_eq!(reference.len(), 127);
    let tracker = PinTracker::new(reference.clone()).expect("tracker");
    assert!((tracker.spacing() - SPACING).abs() < 1e-9);
    let displace = field(&reference);
    let largest = reference
        .iter()
        .map(|&p| displace(p)[0].hypot(displace(p)[1]))
        .fold(0.0, f64::max);
    assert!((largest - 20.0).abs() < 1e-9);
    for seed in 0..20u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let truth: Vec<[f64; 2]> = reference
            .iter()
            .map(|&p| {
                let d = displace(p);
                [
                    p[0] + d[0] + rng.random_range(-0.3..0.3),
                    p[1] + d[1] + rng.random_range(-0.3..0.3),
                ]
            })
            .collect();
        let dropped = rng.random_range(0..truth.len());
        let mut blobs: Vec<KeyPoint> = truth
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != dropped)
            .map(|(_, &p)| keypoint(p))
            .collect();
        blobs.push(keypoint([
            rng.random_range(20.0..40.0),
            rng.random_range(20.0..236.0),
        ]));
        blobs.shuffle(&mut rng);

        let tracked = tracker.order(&blobs);
        assert_eq!((tracked.missing, tracked.extra), (1, 1), "seed {seed}");
        for (i, (pin, want)) in tracked.pins.iter().zip(&truth).enumerate() {
            let err = (pin[0] - want[0]).hypot(pin[1] - want[1]);
            if i == dropped {
                assert!(!tracked.matched[i]);
                // Kernel interpolation of a 20 px bump only 25 px wide: the
                // fill is an estimate, good to a fraction of the spacing.
                assert!(
                    err < 0.4 * SPACING,
                    "seed {seed}: filled pin {i} off by {err:.2} px"
                );
            } else {
                assert!(
                    tracked.matched[i] && err < 1e-9,
                    "seed {seed}: pin {i} wrong ({err:.2} px)"
                );
            }
        }
    }
}

#[test]
fn nearest_neighbour_would_swap_pins_under_this_field() {
    // Guards the test above: the field really is beyond nearest-neighbour reach.
    let reference = hex_reference();
    let displace = field(&reference);
    let swapped = reference
        .iter()
        .enumerate()
        .filter(|&(i, &p)| {
            let d = displace(p);
            let moved = [p[0] + d[0], p[1] + d[1]];
            let nearest = reference
                .iter()
                .enumerate()
                .min_by(|a, b| {
                    let da = (a.1[0] - moved[0]).hypot(a.1[1] - moved[1]);
                    let db = (b.1[0] - moved[0]).hypot(b.1[1] - moved[1]);
                    da.total_cmp(&db)
                })
                .map(|(j, _)| j);
            nearest != Some(i)
        })
        .count();
    assert!(swapped > 20, "only {swapped} pins would be confused");
}

#[test]
fn no_keypoints_leaves_every_pin_missing_at_rest() {
    let tracker = PinTracker::new(hex_reference()).expect("tracker");
    let tracked = tracker.order(&[]);
    assert_eq!((tracked.missing, tracked.extra), (127, 0));
    assert!(tracked
        .displacement(tracker.reference())
        .iter()
        .all(|d| *d == 0.0));
}

#[test]
fn displacement_lists_all_x_then_all_y() {
    let reference = vec![[0.0, 0.0], [10.0, 0.0], [0.0, 10.0]];
    let tracker = PinTracker::new(reference.clone()).expect("tracker");
    let moved: Vec<KeyPoint> = reference
        .iter()
        .map(|p| keypoint([p[0] + 1.0, p[1] - 2.0]))
        .collect();
    let d = tracker.order(&moved).displacement(&reference);
    assert_eq!(d, vec![1.0, 1.0, 1.0, -2.0, -2.0, -2.0]);
}

#[test]
fn bad_references_are_rejected() {
    assert!(matches!(
        PinTracker::new(vec![[0.0, 0.0], [1.0, 1.0]]),
        Err(VisionError::TooFewReferencePins { found: 2, .. })
    ));
    assert!(matches!(
        PinTracker::new(vec![[0.0, 0.0], [1.0, f64::NAN], [2.0, 2.0]]),
        Err(VisionError::NonFiniteReference { index: 1 })
    ));
    assert!(matches!(
        PinTracker::new(vec![[1.0, 1.0]; 4]),
        Err(VisionError::DegenerateReference)
    ));
}

/// White discs of radius 3 at the hex centres.
fn render(pins: &[[f64; 2]]) -> Frame {
    Frame::from_fn(256, 256, |x, y| {
        let (x, y) = (f64::from(x), f64::from(y));
        let hit = pins.iter().any(|p| (p[0] - x).hypot(p[1] - y) <= 3.0);
        image::Luma([if hit { 255 } else { 0 }])
    })
}

#[test]
fn blank_frame_is_an_error_not_a_panic() {
    let params = BlobParams::preset("real256").expect("preset");
    let extractor =
        PinExtractor::from_reference_frame(&render(&hex_reference()), params).expect("extractor");
    assert_eq!(extractor.tracker.reference().len(), 127);
    match extractor.extract(&Frame::new(256, 256)) {
        Err(VisionError::TooFewPins {
            matched: 0,
            total: 127,
            required,
        }) => assert_eq!(required, 115),
        other => panic!("expected TooFewPins, got {other:?}"),
    }
}

#[test]
fn blank_reference_frame_is_an_error() {
    let params = BlobParams::preset("real256").expect("preset");
    assert!(matches!(
        PinExtractor::from_reference_frame(&Frame::new(64, 64), params),
        Err(VisionError::TooFewReferencePins { found: 0, .. })
    ));
}

#[test]
fn rendered_deformed_frame_round_trips() {
    let reference = hex_reference();
    let params = BlobParams::preset("real256").expect("preset");
    let extractor =
        PinExtractor::from_reference_frame(&render(&reference), params).expect("extractor");
    let displace = field(&reference);
    // The extractor's reference order is its own detection order.
    let moved: Vec<[f64; 2]> = extractor
        .tracker
        .reference()
        .iter()
        .map(|&p| {
            let d = displace(p);
            [p[0] + d[0], p[1] + d[1]]
        })
        .collect();
    let tracked = extractor.extract(&render(&moved)).expect("extract");
    assert_eq!(tracked.missing, 0);
    for (pin, want) in tracked.pins.iter().zip(&moved) {
        // Disc centres are rasterised to whole pixels: up to ~0.5 px error.
        assert!((pin[0] - want[0]).hypot(pin[1] - want[1]) < 0.75);
    }
}
