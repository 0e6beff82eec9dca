//! The whole calibration on simulated "real" taps (a known affine
//! distortion of label-driven fields): it picks spanning taps, fits, scores
//! the rest, and refuses bad input with the documented errors.
use crate::common;
use common::{distorted, distortion, labelled_fields};
use tactrace_calib::{
    calibrate, check_span, real_tap_repeats, CalibError, CalibrationPlan, SpanRule, MIN_TAPS,
};

#[test]
fn calibration_corrects_held_out_taps_of_a_known_distortion() {
    let (labels, sim) = labelled_fields(800, 40, 1);
    let (a, b) = distortion(40, 2);
    let real = distorted(&sim, &a, &b, 0.05, 3);
    let cal = calibrate(&sim, &real, &labels, &CalibrationPlan::default()).unwrap();
    let rec = &cal.record;
    assert_eq!(rec.selection.indices.len(), 100);
    assert_eq!(rec.pins, 20);
    check_span(&cal.labels, &SpanRule::default()).unwrap();
    let (before, after) = (rec.held_out_before.unwrap(), rec.held_out_after.unwrap());
    assert_eq!(before.taps, 700);
    assert!(
        after.rms_px < 0.2 * before.rms_px,
        "{before:?} -> {after:?}"
    );
    assert!(after.median_cosine > 0.99, "{after:?}");
    // Seeded: the same plan gives the same taps and correction.
    let again = calibrate(&sim, &real, &labels, &CalibrationPlan::default()).unwrap();
    assert_eq!(again.record, cal.record);
    assert_eq!(again.correction, cal.correction);
}

#[test]
fn error_grows_smaller_with_more_taps() {
    let (labels, sim) = labelled_fields(1500, 30, 4);
    let (a, b) = distortion(30, 5);
    let real = distorted(&sim, &a, &b, 0.05, 6);
    let rms = |n| {
        let plan = CalibrationPlan {
            samples: Some(n),
            ..Default::default()
        };
        calibrate(&sim, &real, &labels, &plan)
            .unwrap()
            .record
            .held_out_after
            .unwrap()
            .rms_px
    };
    let (r10, r30, r300) = (rms(10), rms(30), rms(300));
    assert!(r300 < r30 && r30 < r10, "{r10} {r30} {r300}");
}

#[test]
fn bad_input_gives_the_documented_errors() {
    let (labels, sim) = labelled_fields(200, 20, 7);
    let plan = CalibrationPlan::default();
    // Too few taps given: says how many are needed.
    let err = calibrate(
        &sim.subset(&[0, 1, 2]),
        &sim.subset(&[0, 1, 2]),
        &labels[..3],
        &plan,
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            CalibError::TooFewTaps {
                got: 3,
                needed: 100,
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("at least 100"), "{err}");
    let tiny = CalibrationPlan {
        samples: Some(5),
        ..Default::default()
    };
    assert!(matches!(
        calibrate(&sim, &sim, &labels, &tiny),
        Err(CalibError::TooFewTaps { needed, .. }) if needed == MIN_TAPS
    ));
    // Taps that do not span theta.
    let narrow: Vec<usize> = (0..200).filter(|&i| labels[i].1.abs() < 10.0).collect();
    let few = CalibrationPlan {
        samples: Some(MIN_TAPS),
        ..Default::default()
    };
    let sub = sim.subset(&narrow);
    let lab: Vec<_> = narrow.iter().map(|&i| labels[i]).collect();
    assert!(matches!(
        calibrate(&sub, &sub, &lab, &few),
        Err(CalibError::NoSpan { .. })
    ));
    // Pin counts that differ.
    let (_, other) = labelled_fields(200, 22, 7);
    assert!(matches!(
        calibrate(&sim, &other, &labels, &plan),
        Err(CalibError::Dimension { .. })
    ));
    // A NaN label.
    let mut bad = labels.clone();
    bad[9].0 = f64::NAN;
    assert!(matches!(
        calibrate(&sim, &sim, &bad, &plan),
        Err(CalibError::BadLabel { index: 9, .. })
    ));
    // Labels missing for some taps.
    assert!(matches!(
        calibrate(&sim, &sim, &labels[..150], &plan),
        Err(CalibError::Dimension { .. })
    ));
}

#[test]
fn real_tap_repeats_make_half_the_twin() {
    assert_eq!(real_tap_repeats(3762, 100), 19);
    assert_eq!(real_tap_repeats(3762, 5000), 1);
    assert_eq!(real_tap_repeats(100, 0), 50);
}
