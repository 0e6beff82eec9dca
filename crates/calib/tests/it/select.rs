//! The tap selection spans r and theta, is seeded and reproducible, and
//! the span guard refuses taps bunched on one side.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_calib::{check_span, select_taps, CalibError, Label, SpanRule};

/// A pool like the Bristol edge set: r in -5..5 mm, theta in -45..45 deg.
fn pool(n: usize, seed: u64) -> Vec<Label> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| (rng.random_range(-5.0..5.0), rng.random_range(-45.0..45.0)))
        .collect()
}

fn span(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)))
}

#[test]
fn chosen_taps_span_r_and_theta() {
    let labels = pool(2000, 1);
    for n in [10, 30, 100] {
        let idx = select_taps(&labels, n, 1).unwrap();
        assert_eq!(idx.len(), n);
        let mut dedup = idx.clone();
        dedup.dedup();
        assert_eq!(dedup.len(), n, "no tap twice");
        let chosen: Vec<Label> = idx.iter().map(|&i| labels[i]).collect();
        check_span(&chosen, &SpanRule::default()).unwrap();
        // Every cell of a k x k grid over the pool's box holds a chosen tap
        // (k = floor(sqrt n)).
        let k = (n as f64).sqrt() as usize;
        let (r0, r1) = span(labels.iter().map(|l| l.0));
        let (t0, t1) = span(labels.iter().map(|l| l.1));
        let bin =
            |v: f64, lo: f64, hi: f64| (((v - lo) / (hi - lo) * k as f64) as usize).min(k - 1);
        let mut cover = vec![false; k * k];
        for &(r, t) in &chosen {
            cover[bin(t, t0, t1) * k + bin(r, r0, r1)] = true;
        }
        assert!(cover.iter().all(|&c| c), "n {n}: cells {cover:?}");
        // The extremes come close to the pool's.
        let rmax = chosen.iter().map(|l| l.0).fold(f64::MIN, f64::max);
        let rmin = chosen.iter().map(|l| l.0).fold(f64::MAX, f64::min);
        let tmax = chosen.iter().map(|l| l.1).fold(f64::MIN, f64::max);
        let tmin = chosen.iter().map(|l| l.1).fold(f64::MAX, f64::min);
        let frac = 1.0 - 2.0 / k as f64;
        assert!(
            rmax - rmin > 10.0 * frac && tmax - tmin > 90.0 * frac,
            "n {n}"
        );
    }
}

#[test]
fn selection_is_seeded() {
    let labels = pool(500, 2);
    assert_eq!(
        select_taps(&labels, 30, 4).unwrap(),
        select_taps(&labels, 30, 4).unwrap()
    );
    assert_ne!(
        select_taps(&labels, 30, 4).unwrap(),
        select_taps(&labels, 30, 5).unwrap()
    );
}

#[test]
fn whole_pool_when_all_asked() {
    let labels = pool(12, 3);
    assert_eq!(
        select_taps(&labels, 12, 1).unwrap(),
        (0..12).collect::<Vec<_>>()
    );
    assert!(matches!(
        select_taps(&labels, 13, 1),
        Err(CalibError::TooFewTaps {
            got: 12,
            needed: 13,
            ..
        })
    ));
}

#[test]
fn span_guard_refuses_one_sided_taps() {
    let labels = pool(400, 4);
    let neg_theta: Vec<Label> = labels.iter().copied().filter(|l| l.1 < 0.0).collect();
    assert!(
        check_span(&neg_theta, &SpanRule::default()).is_ok(),
        "half of theta is 45 deg"
    );
    let narrow: Vec<Label> = labels
        .iter()
        .copied()
        .filter(|l| l.1.abs() < 10.0)
        .collect();
    assert!(matches!(
        check_span(&narrow, &SpanRule::default()),
        Err(CalibError::NoSpan { .. })
    ));
    // A diagonal: both ranges covered, two quadrants empty.
    let diag: Vec<Label> = (0..20)
        .map(|i| (i as f64 - 10.0) / 2.0)
        .map(|r| (r, 9.0 * r))
        .collect();
    let err = check_span(&diag, &SpanRule::default()).unwrap_err();
    assert!(err.to_string().contains("no tap with"), "{err}");
}

#[test]
fn bad_labels_are_refused() {
    let mut labels = pool(50, 5);
    labels[7].1 = f64::NAN;
    assert!(matches!(
        select_taps(&labels, 10, 1),
        Err(CalibError::BadLabel { index: 7, .. })
    ));
    assert!(matches!(
        check_span(&labels, &SpanRule::default()),
        Err(CalibError::BadLabel { index: 7, .. })
    ));
}
