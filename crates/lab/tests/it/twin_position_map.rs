//! The position map of a calibrated sensor's twin (docs/calibration.md,
//! "The position map"): fitted from a model trained on the twin without
//! the real calibration taps, refused for a model trained on them, and
//! applied to the simulated taps only.
use tactrace_calib::PositionMap;
use tactrace_lab::calibrate::{calibrate_sensor, CalibrateConfig};
use tactrace_lab::train::{resolve_config, train};
use tactrace_lab::twin::{fit_position_map, relabel_positions, simulate_twin_calibrated};
use tactrace_learn::{ModelKind, Preset};
use tactrace_sensor::TacTipConfig;
use tactrace_store::{StoredModel, TrainingRecord};

use crate::common;
use common::distorted_sensor_set;

#[test]
fn the_map_needs_a_model_without_the_real_taps_and_moves_only_simulated_taps() {
    let root = tempfile::tempdir().unwrap();
    let set = distorted_sensor_set(root.path(), 60);
    let cfg = CalibrateConfig {
        collection: set.clone(),
        render_seed: 1,
        samples: Some(30),
        seed: 3,
        allowed_rows: None,
        score_rows: None,
        fit_physics: false,
        labelled_depth: false,
        pin_jitter: Default::default(),
    };
    let sensor = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {})
        .unwrap()
        .sensor;
    let simulated = simulate_twin_calibrated(&set, &sensor, 1, (false, None), &|| {}).unwrap();
    let mut with_taps = simulate_twin_calibrated(&set, &sensor, 1, (true, None), &|| {}).unwrap();
    let mcfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, Some(5)).unwrap();
    let (model, _) = train(&mcfg, &simulated.data, &mut |_| {}).unwrap();
    let pins = simulated.data.meta.reference_pins.clone();
    let record = |d| TrainingRecord::all_rows(d, None);
    let clean =
        StoredModel::new(model.clone(), pins.clone()).with_training(record(&simulated.data));
    let map = fit_position_map(&sensor, &clean).unwrap();
    assert_eq!(map.taps, 30);
    assert!(map.rises() && map.rms_after_mm <= map.rms_before_mm + 1e-12);
    // A model that saw the calibration taps reads them as labelled: refused.
    let seen = StoredModel::new(model, pins).with_training(record(&with_taps.data));
    let err = fit_position_map(&sensor, &seen).unwrap_err();
    assert!(err.is_bad_input(), "{err}");
    assert!(err.to_string().contains("--no-real-taps"), "{err}");
    // A shift by 0.5 mm moves the simulated taps' positions, not their
    // angles, and not the real taps appended after them.
    let xs: Vec<f64> = (0..20).map(|i| f64::from(i) * 0.5 - 5.0).collect();
    let shifted: Vec<f64> = xs.iter().map(|x| x + 0.5).collect();
    let shift = PositionMap::fit(&xs, &shifted).unwrap();
    let before = with_taps.data.targets.clone();
    relabel_positions(&mut with_taps, &shift);
    let c = with_taps.composition.as_ref().unwrap();
    let real = c.real_taps * c.real_tap_repeats;
    let n = before.len() / 2;
    assert!(real > 0 && n > real);
    for (k, (a, b)) in before
        .chunks(2)
        .zip(with_taps.data.targets.chunks(2))
        .enumerate()
    {
        let moved = if k < n - real { 0.5 } else { 0.0 };
        assert!(
            (b[0] - a[0] - moved).abs() < 1e-5,
            "row {k}: {a:?} -> {b:?}"
        );
        assert_eq!(a[1], b[1], "row {k}: the angle is kept");
    }
    let recorded = &with_taps.data.meta.settings["position_map"]["coefficients"];
    assert!(
        (recorded[0].as_f64().unwrap() - 0.5).abs() < 1e-9,
        "{recorded}"
    );
}
