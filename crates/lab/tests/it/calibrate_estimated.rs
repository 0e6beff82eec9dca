//! `calibrate` and `twin` on a sensor with no undeformed frame: the rest
//! layout estimated from the taps (as `import` does without
//! `--reference`), the simulator laid out by both kinds of layout (the
//! better kept, both reported), the correction fitted, and the calibrated
//! sensor's twin ordered by its estimated rest pins. Synthetic "real"
//! sensors (the simulator with a known field distortion) of both layouts.
use tactrace_lab::calibrate::calibrate_sensor;
use tactrace_lab::twin::{simulate_twin_calibrated, simulate_twin_laid_out};
use tactrace_sensor::{PinLayout, TacTipConfig};
use tactrace_store::collection::Reference;
use tactrace_store::SensorFolder;

use crate::common;
use common::{calibration, sensor_set, sensor_set_over};

/// 127 pins on 6 concentric rings, each ring its own phase, in the
/// default 256 x 256 frame (pins the Bristol blob preset finds).
fn ring_sensor() -> TacTipConfig {
    let mut cfg = TacTipConfig::default();
    cfg.geometry.layout = PinLayout::Rings;
    cfg.geometry.ring_phase_deg = (1..=6).map(|k| 3.0 / k as f64).collect();
    cfg
}

/// Taps up to this edge position (mm) barely touch: the least pressed
/// taps the rest layout is estimated from.
const R_MAX: f64 = 25.0;

#[test]
fn calibrate_from_an_estimated_rest_layout_on_a_ring_sensor() {
    let root = tempfile::tempdir().unwrap();
    let taps = sensor_set_over(root.path(), 160, ring_sensor(), R_MAX);
    // No undeformed frame: the rest layout is estimated from the taps.
    std::fs::remove_file(root.path().join("frames/init_0.png")).unwrap();
    let collection = taps.with_reference(Reference::Estimate { pins: Some(127) });
    let got = calibrate_sensor(
        &calibration(collection.clone(), 100),
        &TacTipConfig::default(),
        &|| {},
    )
    .unwrap();
    let estimated = got.estimated.as_ref().expect("estimated from the taps");
    assert_eq!(estimated.pins.len(), 127);
    // Both layouts fitted; the rings kept, paired, closer than the lattice.
    let layout = got.layout;
    assert_eq!(layout.kept, PinLayout::Rings, "{}", layout.describe());
    assert!(layout.rings.1, "{}", layout.describe());
    assert!(layout.rings.0 < layout.hex.0, "{}", layout.describe());
    let text = layout.describe();
    assert!(text.contains("hexagonal lattice") && text.contains("concentric rings"));
    let spec = &got.sensor.spec;
    assert_eq!(spec.sensor.geometry.layout, PinLayout::Rings);
    assert_eq!(spec.reference_pins, estimated.pins);
    let record = &spec.calibration;
    let (before, after) = (
        record.held_out_before.unwrap(),
        record.held_out_after.unwrap(),
    );
    assert_eq!(after.taps, 60);
    assert!(
        after.rms_px < 0.5 * before.rms_px && after.rms_px < 0.5,
        "held-out field RMS {} -> {} px",
        before.rms_px,
        after.rms_px
    );
    // No real undeformed frame: reference.png is the simulator's rest frame.
    assert_eq!(got.sensor.reference.dimensions(), (256, 256));
    // The folder round-trips; its twin with no reference given is ordered
    // by the sensor's own (estimated) rest pins, as is the twin of the
    // collection whose estimate is recorded.
    let dir = root.path().join("sensor");
    got.sensor.write(&dir, false).unwrap();
    let back = SensorFolder::read(&dir).unwrap();
    let own = simulate_twin_calibrated(&collection, &back, 1, (false, None), &|| {}).unwrap();
    assert_eq!(own.data.meta.reference_pins, estimated.pins);
    assert_eq!(own.data.len(), 3 * 160);
    let recorded = collection.with_reference(Reference::Estimated(estimated.clone()));
    let again = simulate_twin_calibrated(&recorded, &back, 1, (false, None), &|| {}).unwrap();
    assert_eq!(again.data.inputs, own.data.inputs);
}

#[test]
fn an_uncalibrated_twin_is_laid_out_like_the_estimated_rest_pins() {
    let root = tempfile::tempdir().unwrap();
    let taps = sensor_set_over(root.path(), 40, ring_sensor(), R_MAX);
    let estimate = taps.with_reference(Reference::Estimate { pins: None });
    let (resolved, est) = tactrace_lab::sim_sight::resolve_reference(estimate).unwrap();
    let est = est.expect("estimated");
    // The default simulator is a lattice: the twin lays it out as rings.
    let (got, layout) =
        simulate_twin_laid_out(&resolved, &TacTipConfig::default(), 1, None, &|| {}).unwrap();
    assert_eq!(layout.kept, PinLayout::Rings);
    assert_eq!(got.data.meta.reference_pins, est.pins);
    assert_eq!(got.data.len() + got.rejected.len(), 40);
    // A lattice sensor keeps the lattice (and says the rings fit worse).
    let lattice = tempfile::tempdir().unwrap();
    let taps = sensor_set(lattice.path(), 20, TacTipConfig::default());
    let (_, layout) =
        simulate_twin_laid_out(&taps, &TacTipConfig::default(), 1, None, &|| {}).unwrap();
    assert_eq!(layout.kept, PinLayout::Hex, "{}", layout.describe());
    assert!(layout.hex.0 < layout.rings.0, "{}", layout.describe());
}
