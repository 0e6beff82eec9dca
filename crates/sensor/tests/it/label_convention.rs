//! The label convention found from labelled taps (`fit_convention`): a
//! synthetic sensor whose labels turn the other way, start a quarter
//! turn away, and put the object on the other side of the edge is
//! recovered from its taps alone; a sensor labelled like the simulator
//! keeps its own convention untouched.
use crate::common;

use tactrace_sensor::{
    fit_convention, wrap_deg, ConventionSearch, EdgeTap, FitSample, TacTipConfig, TacTipModel,
};

/// 24 taps of `truth` (no slide), labels spread over r in [-3, 3] mm and
/// the whole circle of angles, measured against the rest pins.
fn taps(truth: &TacTipConfig) -> (Vec<[f64; 2]>, Vec<FitSample>) {
    let model = TacTipModel::new(truth.clone()).unwrap();
    let rest = model.rest_pins().to_vec();
    let samples = (0..24)
        .map(|k| {
            let tap = EdgeTap {
                r_mm: -3.0 + 6.0 * ((k * 7) % 24) as f64 / 23.0,
                theta_deg: -180.0 + 15.0 * k as f64,
                ..EdgeTap::default()
            };
            common::fit_sample(&model, &rest, tap)
        })
        .collect();
    (rest, samples)
}

fn search() -> ConventionSearch {
    ConventionSearch {
        angle_step_deg: 20.0,
        iterations: 40,
        threads: 2,
    }
}

#[test]
fn a_sensor_labelled_another_way_round_has_its_convention_recovered() {
    let own = TacTipConfig::default();
    let mut truth = own.clone();
    let k = &mut truth.calibration;
    k.angle_scale = -1.0;
    k.angle_offset_deg = own.calibration.angle_offset_deg + 90.0;
    k.object_side = -own.calibration.object_side;
    let (rest, samples) = taps(&truth);
    let fit = fit_convention(&own, &rest, &samples, &search()).unwrap();
    assert!(!fit.kept_own, "{}", fit.describe());
    // The object on the other side is the object on this side seen half
    // a turn round: the angle offset turned by 180 deg, the position
    // negated.
    let c = fit.chosen;
    assert_eq!(
        (c.angle_sign, c.edge_sign),
        (-1.0, -1.0),
        "{}",
        fit.describe()
    );
    let want = wrap_deg(truth.calibration.angle_offset_deg + 180.0);
    assert!(
        wrap_deg(c.angle_offset_deg - want).abs() < 2.0,
        "angle offset {} for {want}: {}",
        c.angle_offset_deg,
        fit.describe()
    );
    let edge = -truth.calibration.edge_offset_mm;
    assert!((c.edge_offset_mm - edge).abs() < 0.3, "{}", fit.describe());
    assert!(
        c.cosine > 0.99 && fit.own.cosine < 0.9,
        "{}",
        fit.describe()
    );
    // The fitted configuration simulates the same taps.
    let fitted = TacTipModel::with_rest_pins(fit.apply(&own), rest.clone()).unwrap();
    let (rms, cos) = tactrace_sensor::field_misfit(&fitted, &samples);
    assert!(rms < 0.1 && cos > 0.99, "rms {rms} px, cosine {cos}");
}

#[test]
fn a_sensor_labelled_like_the_simulator_keeps_its_convention() {
    let own = TacTipConfig::default();
    let (rest, samples) = taps(&own);
    let fit = fit_convention(&own, &rest, &samples, &search()).unwrap();
    assert!(fit.kept_own, "{}", fit.describe());
    assert_eq!(fit.apply(&own), own);
    assert_eq!(fit.chosen, fit.own);
}
