//! `tactrace calibrate` end to end on a synthetic "real" sensor: frames
//! rendered by the simulator with a known field distortion stand in for a
//! real TacTip. Calibration must find the distortion (the held-out field
//! misfit falls to the rendering noise), the sensor folder must round-trip
//! exactly, and `twin --sensor` must give identical taps from the original
//! and the reloaded folder, in the reference's pin order.
use tactrace_lab::calibrate::{calibrate_sensor, CalibrateConfig};
use tactrace_lab::twin::simulate_twin_calibrated;
use tactrace_sensor::TacTipConfig;
use tactrace_store::SensorFolder;

use crate::common;
use common::{distorted_sensor_set, PINS};

#[test]
fn calibration_finds_a_known_distortion_and_the_sensor_round_trips() {
    let root = tempfile::tempdir().unwrap();
    let twin = distorted_sensor_set(root.path(), 160);
    let cfg = CalibrateConfig {
        collection: twin.clone(),
        render_seed: 1,
        samples: Some(100),
        seed: 3,
        allowed_rows: None,
        score_rows: None,
        fit_physics: false,
        labelled_depth: false,
        pin_jitter: Default::default(),
    };
    let got = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap();
    let record = &got.sensor.spec.calibration;
    let (before, after) = (
        record.held_out_before.unwrap(),
        record.held_out_after.unwrap(),
    );
    assert_eq!(after.taps, 60, "the 60 taps not chosen score the fit");
    assert!(
        after.rms_px < 0.5 * before.rms_px && after.rms_px < 0.5,
        "held-out field RMS {} -> {} px",
        before.rms_px,
        after.rms_px
    );
    assert_eq!(record.selection.indices.len(), 100);
    // The simulator's correction is the fitted one: moving the rest pins by
    // a field and correcting them gives the fitted map's field.
    let rest = &got.sensor.spec.reference_pins;
    let field: Vec<f32> = (0..2 * PINS)
        .map(|k| ((k * 7) % 11) as f32 * 0.3 - 1.5)
        .collect();
    let moved: Vec<[f64; 2]> = (0..PINS)
        .map(|i| {
            [
                rest[i][0] + f64::from(field[i]),
                rest[i][1] + f64::from(field[PINS + i]),
            ]
        })
        .collect();
    let seen = got.sensor.field_correction().unwrap().apply(rest, &moved);
    let fitted = got
        .sensor
        .correction
        .apply(&tactrace_calib::Fields::from_flat(&field, 2 * PINS, "field").unwrap())
        .unwrap()
        .row(0);
    for i in 0..PINS {
        for (axis, k) in [(0, i), (1, PINS + i)] {
            let d = seen[i][axis] - rest[i][axis];
            assert!(
                (d - f64::from(fitted[k])).abs() < 1e-3,
                "pin {i}: {d} vs {}",
                fitted[k]
            );
        }
    }
    // The folder round-trips and gives identical taps.
    let dir = root.path().join("sensor");
    got.sensor.write(&dir, false).unwrap();
    let back = SensorFolder::read(&dir).unwrap();
    assert_eq!(
        back.field_correction().unwrap(),
        got.sensor.field_correction().unwrap()
    );
    assert_eq!(back.real_fields, got.sensor.real_fields);
    let a = simulate_twin_calibrated(&twin, &got.sensor, 1, (true, None), &|| {}).unwrap();
    let b = simulate_twin_calibrated(&twin, &back, 1, (true, None), &|| {}).unwrap();
    assert_eq!(a.data.inputs, b.data.inputs);
    assert_eq!(a.data.meta.reference_pins, got.sensor.spec.reference_pins);
    // Three renders of the 160 labels plus the 100 real taps, repeated.
    assert!(a.data.len() > 3 * 160, "{} taps", a.data.len());
    // Nothing overwritten without --force; another version is refused.
    assert!(got.sensor.write(&dir, false).is_err());
    let toml = dir.join("sensor.toml");
    let text = std::fs::read_to_string(&toml).unwrap();
    std::fs::write(
        &toml,
        text.replace("format_version = 1", "format_version = 99"),
    )
    .unwrap();
    let err = SensorFolder::read(&dir).unwrap_err().to_string();
    assert!(err.contains("version 99"), "{err}");
}

#[test]
fn too_few_or_one_sided_taps_are_refused_with_how_many_are_needed() {
    let root = tempfile::tempdir().unwrap();
    let twin = distorted_sensor_set(root.path(), 8);
    let cfg = CalibrateConfig {
        collection: twin,
        render_seed: 1,
        samples: None,
        seed: 1,
        allowed_rows: None,
        score_rows: None,
        fit_physics: false,
        labelled_depth: false,
        pin_jitter: Default::default(),
    };
    let err = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {})
        .err()
        .expect("8 taps are too few");
    assert!(err.is_bad_input(), "{err}");
    assert!(err.to_string().contains("10"), "{err}");
    // Asking for fewer taps than needed is refused before any frame is read.
    let cfg = CalibrateConfig {
        collection: cfg
            .collection
            .clone()
            .with_frames(root.path().join("no-such-folder")),
        samples: Some(5),
        ..cfg
    };
    let err = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {})
        .err()
        .expect("5 taps are too few");
    assert!(
        err.is_bad_input() && err.to_string().contains("10"),
        "{err}"
    );
}

/// A key appended to the end of sensor.toml (where it reads as a top-level
/// key but lands in the last table, `[calibration.held_out_after]`) was
/// accepted: every table of the file refuses unknown keys now.
#[test]
fn an_unknown_key_anywhere_in_sensor_toml_is_refused() {
    let root = tempfile::tempdir().unwrap();
    let cfg = common::calibration(distorted_sensor_set(root.path(), 40), 20);
    let got = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap();
    let dir = root.path().join("sensor");
    got.sensor.write(&dir, false).unwrap();
    let toml = dir.join("sensor.toml");
    let text = std::fs::read_to_string(&toml).unwrap();
    SensorFolder::read(&dir).expect("as written");
    for (at, extra) in [
        ("end", format!("{text}\nsurprise = 1\n")),
        ("top", format!("surprise = 1\n{text}")),
        (
            "selection",
            text.replace(
                "[calibration.selection]\n",
                "[calibration.selection]\nsurprise = 1\n",
            ),
        ),
        (
            "params",
            text.replace(
                "[calibration.params]\n",
                "[calibration.params]\nsurprise = 1\n",
            ),
        ),
    ] {
        assert_ne!(extra, text, "{at}: the key was added");
        std::fs::write(&toml, &extra).unwrap();
        let err = SensorFolder::read(&dir).expect_err(at);
        assert!(err.is_bad_input(), "{at}: {err}");
        assert!(
            err.to_string().contains("unknown field `surprise`"),
            "{at}: {err}"
        );
    }
}
