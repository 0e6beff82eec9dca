//! A TacTip whose pins lie on concentric rings (the 331-pin sensor's
//! layout) calibrated as `tactrace calibrate` does between reading the
//! taps and writing the sensor file: the simulator's layout fitted to the
//! measured rest pins (`tactrace_sensor::fit_layouts`), the twin built on
//! those pins in their measured order, its taps paired with the real ones,
//! and the correction fitted and scored on the taps left out. Nothing of
//! the calibration depends on the layout: the fields are 2P coordinates in
//! the measured pins' order.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_calib::{calibrate, CalibrationPlan, Fields, Label};
use tactrace_sensor::{
    fit_layouts, EdgeTap, FieldCorrection, PinLayout, TacTipConfig, TacTipModel,
};

/// The "real" sensor: 10 rings (331 pins) with their own phases in a
/// 128 x 128 frame, seen through a perspective unlike the default's.
fn ring_sensor() -> TacTipConfig {
    let mut cfg = TacTipConfig::default();
    cfg.geometry.layout = PinLayout::Rings;
    cfg.geometry.rings = 10;
    cfg.geometry.pin_spacing_mm *= 0.6;
    cfg.geometry.pin_radius_mm *= 0.6;
    cfg.geometry.ring_phase_deg = (1..=10).map(|k| 2.0 / k as f64).collect();
    cfg.camera.width = 128;
    cfg.camera.height = 128;
    cfg.camera.centre_px = [63.4, 63.3];
    cfg.camera.focal_px = 136.0;
    cfg.camera.height_mm = 69.0;
    cfg
}

/// A known distortion of the field: 30 % larger, x and y mixed a little,
/// a constant 0.3 px shift in x.
fn distortion(pins: usize) -> FieldCorrection {
    let d = 2 * pins;
    let mut w = vec![0.0f32; d * d];
    for k in 0..d {
        w[k * d + k] = 0.3;
        w[k * d + (k + pins) % d] = 0.1;
    }
    let b = (0..d).map(|k| if k < pins { 0.3 } else { 0.0 }).collect();
    FieldCorrection::new(pins, w, b).unwrap()
}

/// A tap's displacement field from `rest`: all x, then all y.
fn field(pins: &[[f64; 2]], rest: &[[f64; 2]]) -> Vec<f32> {
    let d = |axis: usize| {
        pins.iter()
            .zip(rest)
            .map(move |(p, r)| (p[axis] - r[axis]) as f32)
    };
    d(0).chain(d(1)).collect()
}

#[test]
fn a_rings_sensor_is_laid_out_paired_and_calibrated() {
    let truth = ring_sensor();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    // The measured rest pins: in the order a detector met them, each a
    // little off the model's.
    let mut rest = TacTipModel::new(truth.clone())
        .unwrap()
        .rest_pins()
        .to_vec();
    for i in (1..rest.len()).rev() {
        rest.swap(i, rng.random_range(0..=i));
    }
    for p in &mut rest {
        p[0] += rng.random_range(-0.1..0.1);
        p[1] += rng.random_range(-0.1..0.1);
    }
    let real = TacTipModel::with_rest_pins(truth, rest.clone())
        .unwrap()
        .with_correction(distortion(rest.len()))
        .unwrap();
    let fit = fit_layouts(&TacTipConfig::default(), &rest, (128, 128)).unwrap();
    assert_eq!(fit.layout(), PinLayout::Rings);
    assert!(fit.rings.residual_px < 0.15, "{}", fit.rings.residual_px);
    let twin = TacTipModel::with_rest_pins(fit.config, rest.clone()).unwrap();
    assert_eq!(twin.rest_pins(), rest.as_slice());
    let (mut sim, mut seen, mut labels) = (Vec::new(), Vec::new(), Vec::<Label>::new());
    for _ in 0..300 {
        let tap = EdgeTap {
            r_mm: rng.random_range(-5.0..5.0),
            theta_deg: rng.random_range(-45.0..45.0),
            ..EdgeTap::default()
        };
        sim.push(field(&twin.edge_tap_pins(&tap), &rest));
        seen.push(field(&real.seen_pins(real.edge_tap_pins(&tap)), &rest));
        labels.push((tap.r_mm, tap.theta_deg));
    }
    let sim = Fields::from_rows(&sim, "twin").unwrap();
    let seen = Fields::from_rows(&seen, "real").unwrap();
    let cal = calibrate(&sim, &seen, &labels, &CalibrationPlan::default()).unwrap();
    assert_eq!(cal.record.pins, 331);
    let before = cal.record.held_out_before.unwrap();
    let after = cal.record.held_out_after.unwrap();
    assert_eq!(after.taps, 200);
    assert!(before.rms_px > 0.2, "{before:?}");
    assert!(after.rms_px < 0.05, "{before:?} -> {after:?}");
}
