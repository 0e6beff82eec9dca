//! `calibrate --pin-jitter fit` on synthetic "real" sensors (the
//! simulator with a known field distortion) whose frames were rendered
//! with a known pin jitter: the fitted jitter recovers it, a noiseless
//! sensor gets under 0.08 px, the sensor written renders with it and
//! records the evidence; a given jitter is written as given, and the
//! default keeps the sensor's own with nothing recorded.
use tactrace_lab::calibrate::calibrate_sensor;
use tactrace_lab::pin_jitter::PinJitter;
use tactrace_sensor::TacTipConfig;

use crate::common;
use common::{calibration, sensor_set};

/// The jitter `calibrate --pin-jitter fit` finds on 100 of 120 taps of
/// the distorted sensor rendered with `px` of pin jitter.
fn fitted(px: f64) -> tactrace_store::SensorFolder {
    let root = tempfile::tempdir().unwrap();
    let mut real = TacTipConfig::default();
    real.nuisance.pin_jitter_px = px;
    let set = sensor_set(root.path(), 120, real);
    let mut cfg = calibration(set, 100);
    cfg.pin_jitter = PinJitter::Fit;
    calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {})
        .unwrap()
        .sensor
}

#[test]
fn a_known_jitter_is_recovered_and_recorded() {
    let px = 0.3;
    let sensor = fitted(px);
    let fit = sensor.spec.calibration.pin_jitter.clone().unwrap();
    assert!(
        (fit.pin_jitter_px - px).abs() < 0.06,
        "rendered with {px} px: {}",
        fit.describe()
    );
    assert_eq!(sensor.spec.sensor.nuisance.pin_jitter_px, fit.pin_jitter_px);
    assert_eq!(fit.taps, 100);
    assert!(!fit.beyond_grid);
}

#[test]
fn a_noiseless_sensor_gets_next_to_no_jitter() {
    let sensor = fitted(0.0);
    let fit = sensor.spec.calibration.pin_jitter.unwrap();
    // Not exactly 0: the "real" sensor's field is 1.3 times the
    // simulator's (its known distortion), which the binarised renders'
    // quantisation reads a little rougher (0.057 px measured).
    assert!(fit.pin_jitter_px < 0.08, "{}", fit.describe());
}

#[test]
fn a_given_jitter_is_written_and_the_default_keeps_the_sensors_own() {
    let root = tempfile::tempdir().unwrap();
    let set = sensor_set(root.path(), 40, TacTipConfig::default());
    let mut cfg = calibration(set, 20);
    let own = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap();
    assert_eq!(own.sensor.spec.sensor.nuisance.pin_jitter_px, 0.0);
    assert!(own.sensor.spec.calibration.pin_jitter.is_none());
    cfg.pin_jitter = "0.15".parse().unwrap();
    let given = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap();
    assert_eq!(given.sensor.spec.sensor.nuisance.pin_jitter_px, 0.15);
    assert!(given.sensor.spec.calibration.pin_jitter.is_none());
    // The correction is fitted to the same noiseless renders either way.
    assert_eq!(given.sensor.correction, own.sensor.correction);
    for bad in ["-0.1", "NaN", "inf", "some"] {
        let err = bad.parse::<PinJitter>().unwrap_err();
        assert!(err.to_string().contains(bad), "{err}");
    }
    assert_eq!("FIT".parse::<PinJitter>().unwrap(), PinJitter::Fit);
}
