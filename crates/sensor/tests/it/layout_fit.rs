//! The layout fit (`fit_layouts`) on synthetic sensors of both kinds,
//! their undeformed frames rendered and their pins found again, and on the
//! shared 331-pin TacTip's rest layout estimated from its taps
//! (docs/calibration.md, "Any TacTip"). The shared-set test fails when the
//! data is absent unless TACTRACE_SKIP_REAL_DATA=1 (`tactrace_testdata`).
use crate::common;
use common::centroids;
use std::path::{Path, PathBuf};
use tactrace_sensor::{fit_layouts, PinLayout, SensorError, TacTipConfig, TacTipModel};

/// A sensor of `rings` rings of kind `layout` seen by another camera in a
/// 320 x 240 frame; the spacing keeps the default sensor's extent on the
/// dome, as the fit assumes. Its camera keeps the default orientation.
fn other_sensor(layout: PinLayout, rings: usize) -> TacTipConfig {
    let mut cfg = TacTipConfig::default();
    let scale = cfg.geometry.rings as f64 / rings as f64;
    cfg.geometry.layout = layout;
    cfg.geometry.rings = rings;
    cfg.geometry.pin_spacing_mm *= scale;
    cfg.geometry.pin_radius_mm *= scale;
    if layout == PinLayout::Rings {
        cfg.geometry.ring_phase_deg = (1..=rings)
            .map(|k| 25.0 / k as f64 * ((k * 7 % 5) as f64 - 2.0) / 2.0)
            .collect();
    }
    cfg.camera.width = 320;
    cfg.camera.height = 240;
    cfg.camera.centre_px = [163.3, 118.6];
    cfg.camera.focal_px = 95.0;
    cfg.camera.height_mm = 38.0;
    cfg
}

/// The pins found in the sensor's rendered (binarised) undeformed frame,
/// in the order the scan meets them.
fn seen_pins(cfg: &TacTipConfig) -> Vec<[f64; 2]> {
    let model = TacTipModel::new(cfg.clone()).unwrap();
    let found = centroids(&model.render(model.rest_pins(), None));
    assert_eq!(found.len(), model.rest_pins().len(), "one blob per pin");
    found
        .into_iter()
        .map(|(_, thresholded)| thresholded)
        .collect()
}

/// Difference of two angles modulo `period`, in [0, period / 2].
fn turn(a: f64, b: f64, period: f64) -> f64 {
    let d = (a - b).rem_euclid(period);
    d.min(period - d)
}

#[test]
fn a_rendered_rings_sensor_is_fitted_as_rings() {
    for rings in [5, 10] {
        let truth = other_sensor(PinLayout::Rings, rings);
        let pins = seen_pins(&truth);
        let fit = fit_layouts(&TacTipConfig::default(), &pins, (320, 240)).unwrap();
        let got = &fit.config;
        assert_eq!(fit.layout(), PinLayout::Rings, "{rings} rings");
        assert_eq!(got.geometry.rings, rings);
        assert_eq!(got.geometry.pin_spacing_mm, truth.geometry.pin_spacing_mm);
        let (r, h) = (fit.rings.residual_px, fit.hex.residual_px);
        assert!(fit.rings.matched && r < 0.3, "rings residual {r} px");
        assert!(h > 3.0 * r, "hex residual {h} px against rings {r} px");
        let (c, t) = (&got.camera, &truth.camera);
        assert_eq!((c.width, c.height), (320, 240));
        assert!((c.centre_px[0] - t.centre_px[0]).abs() < 0.1, "{c:?}");
        assert!((c.centre_px[1] - t.centre_px[1]).abs() < 0.1, "{c:?}");
        assert!((c.focal_px / t.focal_px - 1.0).abs() < 0.01, "{c:?}");
        assert!((c.height_mm / t.height_mm - 1.0).abs() < 0.01, "{c:?}");
        assert_eq!((c.rotation_deg, c.mirror), (t.rotation_deg, t.mirror));
        let phases = got.geometry.ring_phase_deg.iter();
        for (k, (a, b)) in phases.zip(&truth.geometry.ring_phase_deg).enumerate() {
            let step = 60.0 / (k + 1) as f64;
            assert!(turn(*a, *b, step) < 0.3, "ring {}: {a} vs {b}", k + 1);
        }
        // The simulator takes the pins as its rest layout.
        TacTipModel::with_rest_pins(got.clone(), pins).unwrap();
    }
}

#[test]
fn a_rendered_lattice_is_fitted_as_a_lattice() {
    for rings in [4, 8] {
        let mut truth = other_sensor(PinLayout::Hex, rings);
        truth.camera.height_mm = TacTipConfig::default().camera.height_mm;
        truth.camera.rotation_deg = 160.0;
        let pins = seen_pins(&truth);
        let fit = fit_layouts(&TacTipConfig::default(), &pins, (320, 240)).unwrap();
        let got = &fit.config;
        assert_eq!(fit.layout(), PinLayout::Hex, "{rings} rings");
        assert_eq!(got.geometry.rings, rings);
        let (r, h) = (fit.rings.residual_px, fit.hex.residual_px);
        assert!(fit.hex.matched && h < 0.3, "hex residual {h} px");
        assert!(r > 3.0 * h, "rings residual {r} px against hex {h} px");
        let (c, t) = (&got.camera, &truth.camera);
        assert!((c.centre_px[0] - t.centre_px[0]).abs() < 0.1, "{c:?}");
        assert!((c.centre_px[1] - t.centre_px[1]).abs() < 0.1, "{c:?}");
        assert!((c.focal_px / t.focal_px - 1.0).abs() < 0.01, "{c:?}");
        assert!(turn(c.rotation_deg, t.rotation_deg, 60.0) < 0.5, "{c:?}");
        assert!(got.geometry.ring_phase_deg.is_empty());
    }
}

#[test]
fn a_rings_sensor_that_already_fits_keeps_its_configuration() {
    let base = other_sensor(PinLayout::Rings, 10);
    let pins = TacTipModel::new(base.clone()).unwrap().rest_pins().to_vec();
    let fit = fit_layouts(&base, &pins, (320, 240)).unwrap();
    assert_eq!(fit.config, base);
    assert!(fit.rings.kept && fit.rings.residual_px < 1e-9);
    assert!(!fit.hex.kept && !fit.hex.matched);
}

#[test]
fn pins_that_fit_no_layout_are_refused_with_both_residuals() {
    // 127 points scattered at random over the frame.
    let mut k = 1u64;
    let mut next = || {
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (k >> 11) as f64 / (1u64 << 53) as f64
    };
    let pins: Vec<[f64; 2]> = (0..127)
        .map(|_| [20.0 + 216.0 * next(), 20.0 + 216.0 * next()])
        .collect();
    let err = fit_layouts(&TacTipConfig::default(), &pins, (256, 256)).unwrap_err();
    let text = err.to_string();
    assert!(
        matches!(err, SensorError::NoLayoutFits { pins: 127, .. }),
        "{text}"
    );
    assert!(
        text.contains("hexagonal") && text.contains("concentric"),
        "{text}"
    );
    assert!(err.is_config());
    let source = std::error::Error::source(&err).expect("the closer fit's failure");
    assert!(source.to_string().contains("free model pin"), "{source}");
}

/// Frames `image_N.png` of `dir` with N % 5 != 0 (the fitting part), every
/// `len / k`-th.
fn fitting_frames(dir: &Path, k: usize) -> Vec<PathBuf> {
    let mut frames: Vec<(u32, PathBuf)> = std::fs::read_dir(dir)
        .expect("frames folder")
        .filter_map(|e| {
            let path = e.ok()?.path();
            let name = path.file_name()?.to_str()?.strip_prefix("image_")?;
            let digits: String = name.chars().take_while(char::is_ascii_digit).collect();
            let n: u32 = digits.parse().ok()?;
            (!n.is_multiple_of(5)).then_some((n, path))
        })
        .collect();
    frames.sort();
    let step = frames.len().div_ceil(k).max(1);
    frames.into_iter().step_by(step).map(|(_, p)| p).collect()
}

#[test]
fn the_shared_331_pin_sensor_fits_concentric_rings_and_not_a_lattice() {
    use tactrace_vision::{estimate_rest, inspect, Frame, RestParams, SightParams};
    let Some(set) =
        tactrace_testdata::shared_set("tactip331-edge2d-shear", "train/frames/image_1.png")
    else {
        return;
    };
    let load = |p: &PathBuf| image::open(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let dir = set.join("train/frames");
    let frames: Vec<Frame> = fitting_frames(&dir, 20)
        .iter()
        .map(|p| load(p).to_luma8())
        .collect();
    let found = inspect(&frames, None).expect("inspection");
    let detector = SightParams {
        preprocess: found.preprocess,
        detect: found.detect,
    }
    .check(128, 128)
    .expect("proposal is valid");
    let detections: Vec<_> = fitting_frames(&dir, 150)
        .iter()
        .map(|p| detector.detect(&load(p)).expect("detect"))
        .collect();
    let rest = estimate_rest(&detections, found.pins, &RestParams::default()).expect("rest");
    assert_eq!(rest.pins.len(), 331);
    let fit = fit_layouts(&TacTipConfig::default(), &rest.pins, (128, 128)).unwrap();
    let (r, h) = (fit.rings.residual_px, fit.hex.residual_px);
    assert_eq!(fit.layout(), PinLayout::Rings, "rings {r} px, hex {h} px");
    assert!(fit.rings.matched && r < 0.45, "rings residual {r} px");
    assert!(!fit.hex.matched && h > 1.5, "hex residual {h} px");
    TacTipModel::with_rest_pins(fit.config.clone(), rest.pins.clone()).expect("rings fit");
    // What `calibrate` met before: the best lattice leaves pins unpaired.
    let Err(err) = TacTipModel::with_rest_pins(fit.hex.config.clone(), rest.pins) else {
        panic!("the lattice took the 331-pin sensor's pins");
    };
    assert!(err.to_string().contains("free model pin"), "{err}");
}
