//! The tap depth law and slide response found from labelled taps
//! (`fit_depth`): a synthetic sensor whose depth column is the absolute
//! tap depth (as the shared 331-pin set's) and whose skin lags half as
//! far behind a slide is recovered from its taps alone; a sensor whose
//! taps the simulator already makes keeps its own values untouched.
use crate::common;

use tactrace_sensor::{
    field_misfit, fit_depth, DepthSearch, EdgeTap, FitSample, Shear, TacTipConfig, TacTipModel,
};

/// 30 taps of `truth`, labels spread over r in [-3, 3] mm, theta in
/// [-60, 60] deg, dz in [3, 5] and slides of up to 3 mm and 3 deg,
/// measured against the rest pins.
fn taps(truth: &TacTipConfig) -> (Vec<[f64; 2]>, Vec<FitSample>) {
    let model = TacTipModel::new(truth.clone()).unwrap();
    let rest = model.rest_pins().to_vec();
    let n = 30;
    let samples = (0..n)
        .map(|k| {
            let u = |m: usize| ((k * m) % n) as f64 / (n - 1) as f64;
            let tap = EdgeTap {
                r_mm: -3.0 + 6.0 * u(7),
                theta_deg: -60.0 + 120.0 * u(11),
                dz_mm: 3.0 + 2.0 * u(13),
                shear: Some(Shear {
                    dx_mm: -3.0 + 6.0 * u(17),
                    dy_mm: -3.0 + 6.0 * u(19),
                    drz_deg: -3.0 + 6.0 * u(23),
                }),
            };
            common::fit_sample(&model, &rest, tap)
        })
        .collect();
    (rest, samples)
}

fn search() -> DepthSearch {
    DepthSearch {
        threads: 2,
        ..DepthSearch::default()
    }
}

#[test]
fn a_sensor_with_absolute_tap_depths_and_a_weaker_slide_is_recovered() {
    let own = TacTipConfig::default();
    let mut truth = own.clone();
    truth.calibration.tap_depth_mm = 0.5;
    truth.calibration.depth_per_offset = 1.0;
    truth.mechanics.stick_gain *= 0.5;
    truth.mechanics.shear_limit_mm *= 0.5;
    let (rest, samples) = taps(&truth);
    let fit = fit_depth(&own, &rest, &samples, &search()).unwrap();
    assert!(!fit.kept_own, "{}", fit.describe());
    let c = fit.chosen;
    for dz in [3.0, 5.0] {
        let want = 0.5 + dz;
        assert!(
            (c.depth_at(dz) - want).abs() < 0.25,
            "depth at dz {dz}: {} for {want}; {}",
            c.depth_at(dz),
            fit.describe()
        );
    }
    assert!(
        (c.slide_scale - 0.5).abs() < 0.15,
        "slide scale {} for 0.5; {}",
        c.slide_scale,
        fit.describe()
    );
    assert!(
        c.rms_px < 0.25 * fit.own.rms_px,
        "RMS {} px, own {} px",
        c.rms_px,
        fit.own.rms_px
    );
    // The fitted configuration simulates the same taps.
    let fitted = TacTipModel::with_rest_pins(fit.apply(&own), rest).unwrap();
    let (rms, cos) = field_misfit(&fitted, &samples);
    assert!(rms < 0.1 && cos > 0.99, "rms {rms} px, cosine {cos}");
}

#[test]
fn a_sensor_the_simulator_already_matches_keeps_its_depth_and_slide() {
    let mut own = TacTipConfig::default();
    // A depth law for dz in [3, 5] that reaches the skin: 3.6-5.6 mm.
    own.calibration.tap_depth_mm = 0.6;
    own.calibration.depth_per_offset = 1.0;
    let (rest, samples) = taps(&own);
    let fit = fit_depth(&own, &rest, &samples, &search()).unwrap();
    assert!(fit.kept_own, "{}", fit.describe());
    assert_eq!(fit.apply(&own), own);
    assert!(fit.own.rms_px < 1e-9, "{}", fit.describe());
}
