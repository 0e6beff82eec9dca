//! The ridge correction against theory: it recovers a known affine
//! distortion better as taps grow, leave-one-out picks a smaller penalty
//! when the noise is low, a fitted identity changes nothing, and the
//! closed-form leave-one-out equals brute-force refits.
use crate::common;
use common::{distorted, distortion, sim_fields};
use nalgebra::DMatrix;
use tactrace_calib::{field_stats, CalibError, CorrectionParams, Fields, LinearCorrection};

/// Max abs error of the fitted (I + W, b) against the true (A, b).
fn recovery_error(n: usize, seed: u64) -> (f64, f64) {
    let dim = 12;
    let sim = sim_fields(n, dim, dim, seed); // full-rank inputs
    let (a, b) = distortion(dim, 7);
    let real = distorted(&sim, &a, &b, 0.01, seed + 100);
    let fit = LinearCorrection::fit(&sim, &real, &CorrectionParams::default()).unwrap();
    let a_hat = DMatrix::identity(dim, dim) + &fit.correction.w;
    ((a_hat - a).amax(), (&fit.correction.b - b).amax())
}

#[test]
fn recovers_known_affine_distortion_as_taps_grow() {
    let errs: Vec<(f64, f64)> = [20, 200, 2000]
        .iter()
        .map(|&n| recovery_error(n, 3))
        .collect();
    assert!(errs[2].0 < errs[0].0 && errs[2].1 < errs[0].1, "{errs:?}");
    assert!(errs[2].0 < 0.02, "A error with 2000 taps: {errs:?}");
    assert!(errs[2].1 < 0.02, "b error with 2000 taps: {errs:?}");
}

#[test]
fn few_shot_correction_predicts_new_taps_in_high_dimension() {
    // 254 coordinates, 8 latent modes, 100 taps: W cannot be identified,
    // but on the span of the simulated fields the correction must hold.
    let (dim, modes) = (254, 8);
    let (a, b) = distortion(dim, 11);
    let train = sim_fields(100, dim, modes, 1);
    let test = sim_fields(500, dim, modes, 1); // same basis, more taps
    let test = test.subset(&(100..500).collect::<Vec<_>>());
    let fit = LinearCorrection::fit(
        &train,
        &distorted(&train, &a, &b, 0.02, 2),
        &Default::default(),
    )
    .unwrap();
    let real = distorted(&test, &a, &b, 0.02, 3);
    let before = field_stats(&test, &real).unwrap();
    let after = field_stats(&fit.correction.apply(&test).unwrap(), &real).unwrap();
    assert!(
        after.rms_px < 0.25 * before.rms_px,
        "{before:?} -> {after:?}"
    );
    assert!(after.median_cosine > before.median_cosine);
}

#[test]
fn leave_one_out_prefers_less_penalty_when_noise_is_low() {
    let dim = 30;
    let sim = sim_fields(60, dim, dim, 5);
    let (a, b) = distortion(dim, 6);
    let pen = |noise| {
        let real = distorted(&sim, &a, &b, noise, 9);
        LinearCorrection::fit(&sim, &real, &Default::default())
            .unwrap()
            .penalty
    };
    let (low, high) = (pen(0.001), pen(1.0));
    assert!(low < high, "penalty low noise {low} vs high noise {high}");
}

#[test]
fn fitted_identity_changes_nothing() {
    let sim = sim_fields(40, 20, 5, 8);
    let fit = LinearCorrection::fit(&sim, &sim, &Default::default()).unwrap();
    let out = fit.correction.apply(&sim).unwrap();
    let diff = (out.matrix() - sim.matrix()).amax();
    assert!(diff < 1e-9, "max change {diff}");
    let id = LinearCorrection::identity(20).apply(&sim).unwrap();
    assert_eq!(id, sim);
}

#[test]
fn closed_form_leave_one_out_matches_refits() {
    let (n, dim) = (14, 6);
    let sim = sim_fields(n, dim, 3, 21);
    let (a, b) = distortion(dim, 22);
    let real = distorted(&sim, &a, &b, 0.2, 23);
    // One penalty only: the grid of a single point.
    let params = CorrectionParams {
        log10_min: -2.0,
        log10_max: -2.0,
        steps: 1,
        ..Default::default()
    };
    let full = LinearCorrection::fit(&sim, &real, &params).unwrap();
    // Brute force: a hand-written ridge refitted without tap i, at the
    // absolute penalty the fit chose.
    let lam = full.penalty;
    let mut total = 0.0;
    for i in 0..n {
        let keep: Vec<usize> = (0..n).filter(|&k| k != i).collect();
        let pred = hand_ridge(
            &sim.subset(&keep),
            &real.subset(&keep),
            lam,
            &sim.subset(&[i]),
        );
        total += (pred - real.subset(&[i]).matrix()).norm_squared();
    }
    let brute = (total / (n * dim) as f64).sqrt();
    assert!(
        (brute - full.loo_rms).abs() < 1e-8 * brute.max(1.0),
        "{brute} vs {}",
        full.loo_rms
    );
}

/// Ridge with unpenalised intercept by the normal equations, predicting `x`.
fn hand_ridge(sim: &Fields, real: &Fields, lam: f64, x: &Fields) -> DMatrix<f64> {
    let (xs, d) = (sim.matrix(), sim.dim());
    let r = real.matrix() - xs;
    let mx = xs.row_mean();
    let mr = r.row_mean();
    let xc = DMatrix::from_fn(xs.nrows(), d, |i, j| xs[(i, j)] - mx[j]);
    let rc = DMatrix::from_fn(xs.nrows(), d, |i, j| r[(i, j)] - mr[j]);
    let g = xc.transpose() * &xc + DMatrix::identity(d, d) * lam;
    let coef = g.lu().solve(&(xc.transpose() * rc)).unwrap();
    let xq = x.matrix();
    let xqc = DMatrix::from_fn(xq.nrows(), d, |i, j| xq[(i, j)] - mx[j]);
    let change = xqc * coef + DMatrix::from_fn(xq.nrows(), d, |_, j| mr[j]);
    xq + change
}

#[test]
fn standardised_and_low_rank_fits_also_correct() {
    let (dim, modes) = (40, 4);
    let (a, b) = distortion(dim, 31);
    let sim = sim_fields(300, dim, modes, 32);
    let real = distorted(&sim, &a, &b, 0.02, 33);
    let (train, test) = ((0..150).collect::<Vec<_>>(), (150..300).collect::<Vec<_>>());
    for params in [
        CorrectionParams {
            standardise: true,
            ..Default::default()
        },
        CorrectionParams {
            rank: Some(modes + 1),
            ..Default::default()
        },
    ] {
        let fit =
            LinearCorrection::fit(&sim.subset(&train), &real.subset(&train), &params).unwrap();
        let out = fit.correction.apply(&sim.subset(&test)).unwrap();
        let before = field_stats(&sim.subset(&test), &real.subset(&test)).unwrap();
        let after = field_stats(&out, &real.subset(&test)).unwrap();
        assert!(
            after.rms_px < 0.3 * before.rms_px,
            "{params:?}: {before:?} -> {after:?}"
        );
    }
}

#[test]
fn bad_input_is_refused() {
    let sim = sim_fields(30, 10, 3, 1);
    let few = sim.subset(&[0, 1, 2]);
    assert!(matches!(
        LinearCorrection::fit(&few, &few, &Default::default()),
        Err(CalibError::TooFewTaps {
            got: 3,
            needed: 10,
            ..
        })
    ));
    let other = sim_fields(30, 12, 3, 1);
    assert!(matches!(
        LinearCorrection::fit(&sim, &other, &Default::default()),
        Err(CalibError::Dimension { .. })
    ));
    assert!(matches!(
        LinearCorrection::identity(12).apply(&sim),
        Err(CalibError::Dimension {
            expected: 12,
            found: 10,
            ..
        })
    ));
    let mut flat = sim.to_flat();
    flat[25] = f32::NAN;
    assert!(matches!(
        Fields::from_flat(&flat, 10, "real"),
        Err(CalibError::BadField {
            index: 2,
            coord: 5,
            ..
        })
    ));
    assert!(matches!(
        Fields::from_flat(&flat[..15], 10, "real"),
        Err(CalibError::Dimension { .. })
    ));
}
