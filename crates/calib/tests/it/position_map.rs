//! The position map: an exact quadratic is recovered, the identity when
//! the readings are right, and a map that folds is refused.
use tactrace_calib::{CalibError, PositionMap};

fn positions(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| -6.0 + 12.0 * i as f64 / (n - 1) as f64)
        .collect()
}

#[test]
fn an_exact_quadratic_misreading_is_recovered() {
    // Readings 0.4 mm too far and 5 % stretched, labels an exact
    // quadratic of them: the fit returns its coefficients.
    let read: Vec<f64> = positions(40).iter().map(|r| 0.4 + 1.05 * r).collect();
    let c = [-0.3, -0.08, 0.012];
    let labelled: Vec<f64> = read
        .iter()
        .map(|p| p + c[0] + c[1] * p + c[2] * p * p)
        .collect();
    let map = PositionMap::fit(&read, &labelled).unwrap();
    for (got, want) in map.coefficients.iter().zip(c) {
        assert!((got - want).abs() < 1e-9, "{:?} vs {c:?}", map.coefficients);
    }
    assert!(map.rms_after_mm < 1e-9 && map.rms_before_mm > 0.1);
    assert!((map.apply(2.0) - (2.0 - 0.3 - 0.16 + 0.048)).abs() < 1e-9);
    assert_eq!(map.taps, 40);
}

#[test]
fn right_readings_give_the_identity() {
    let r = positions(20);
    let map = PositionMap::fit(&r, &r).unwrap();
    assert!(map.coefficients.iter().all(|c| c.abs() < 1e-9));
    assert_eq!(map.apply(3.5), 3.5);
}

#[test]
fn the_fit_is_least_squares_under_noise() {
    // Residuals of +-0.1 alternating about a constant offset of 0.2: the
    // fitted map's RMS is no more than the constant's, which is 0.1.
    let read = positions(50);
    let labelled: Vec<f64> = read
        .iter()
        .enumerate()
        .map(|(i, p)| p + 0.2 + if i % 2 == 0 { 0.1 } else { -0.1 })
        .collect();
    let map = PositionMap::fit(&read, &labelled).unwrap();
    assert!(map.rms_after_mm <= 0.1 + 1e-9, "{}", map.describe());
    assert!((map.coefficients[0] - 0.2).abs() < 0.05);
}

#[test]
fn a_map_that_folds_is_refused() {
    // Labels that fall as the reading rises: slope 1 + c1 < 0.
    let read = positions(30);
    let labelled: Vec<f64> = read.iter().map(|p| -p).collect();
    let err = PositionMap::fit(&read, &labelled).unwrap_err();
    assert!(
        matches!(err, CalibError::Param(ref m) if m.contains("folds")),
        "{err}"
    );
}

#[test]
fn too_few_or_bad_taps_are_refused() {
    let r = positions(5);
    assert!(matches!(
        PositionMap::fit(&r, &r),
        Err(CalibError::TooFewTaps { got: 5, .. })
    ));
    let mut r = positions(20);
    let l = r.clone();
    r[3] = f64::NAN;
    assert!(matches!(
        PositionMap::fit(&r, &l),
        Err(CalibError::BadLabel { index: 3, .. })
    ));
    assert!(matches!(
        PositionMap::fit(&[1.0; 20], &l),
        Err(CalibError::Param(_))
    ));
    assert!(matches!(
        PositionMap::fit(&l[..19], &l),
        Err(CalibError::Dimension { .. })
    ));
}
