//! Configuration checks and measured rest layouts.
use crate::common;
use common::*;
use tactrace_sensor::{SensorError, TacTipConfig, TacTipModel};

#[test]
fn default_config_is_valid_and_has_127_pins_in_256_px() {
    let model = TacTipModel::new(TacTipConfig::default()).expect("valid");
    assert_eq!(model.rest_pins().len(), 127);
    assert_eq!(model.image_size(), (256, 256));
    for p in model.rest_pins() {
        assert!(
            p[0] > 5.0 && p[0] < 251.0 && p[1] > 5.0 && p[1] < 251.0,
            "pin {p:?} inside the frame"
        );
    }
    let rest = model.rest_pins();
    let centre_spacing = (1..7)
        .map(|i| (rest[i][0] - rest[0][0]).hypot(rest[i][1] - rest[0][1]))
        .sum::<f64>()
        / 6.0;
    assert!(
        (9.0..13.0).contains(&centre_spacing),
        "centre spacing {centre_spacing} px"
    );
}

#[test]
fn bad_values_are_rejected_with_the_field_named() {
    let mut cfg = TacTipConfig::default();
    cfg.mechanics.kernel_width_mm = -1.0;
    let err = TacTipModel::new(cfg).expect_err("negative width");
    assert!(matches!(
        err,
        SensorError::InvalidConfig {
            field: "mechanics.kernel_width_mm",
            ..
        }
    ));
    let mut cfg = TacTipConfig::default();
    cfg.camera.height_mm = 1.0;
    assert!(TacTipModel::new(cfg).is_err(), "camera below the pins");
    let mut cfg = TacTipConfig::default();
    cfg.geometry.pin_spacing_mm = 10.0;
    assert!(TacTipModel::new(cfg).is_err(), "pins past the equator");
}

#[test]
fn measured_rest_pins_keep_their_order() {
    let model = plain_model();
    let mut shuffled = model.rest_pins().to_vec();
    shuffled.reverse();
    shuffled.swap(3, 70);
    let nudged: Vec<[f64; 2]> = shuffled.iter().map(|p| [p[0] + 0.4, p[1] - 0.3]).collect();
    let measured =
        TacTipModel::with_rest_pins(model.config().clone(), nudged.clone()).expect("matches");
    assert_eq!(measured.rest_pins(), nudged.as_slice());
    let object = square([0.0, -30.0], 30.0);
    let pose = tap(0.0, 1.0, 3.0, 10.0);
    let a = model.pins(&object, pose, None);
    let b = measured.pins(&object, pose, None);
    for (i, p) in shuffled.iter().enumerate() {
        let k = model
            .rest_pins()
            .iter()
            .position(|q| q == p)
            .expect("same pins");
        assert!((b[i][0] - 0.4 - a[k][0]).abs() < 1e-9 && (b[i][1] + 0.3 - a[k][1]).abs() < 1e-9);
    }
}

#[test]
fn wrong_rest_layouts_are_rejected() {
    let model = plain_model();
    let cfg = model.config().clone();
    let short = model.rest_pins()[..100].to_vec();
    assert!(matches!(
        TacTipModel::with_rest_pins(cfg.clone(), short),
        Err(SensorError::RestPins { got: 100, .. })
    ));
    let mut far = model.rest_pins().to_vec();
    far[5] = [1000.0, 1000.0];
    assert!(TacTipModel::with_rest_pins(cfg.clone(), far).is_err());
    let mut nan = model.rest_pins().to_vec();
    nan[0] = [f64::NAN, 0.0];
    assert!(TacTipModel::with_rest_pins(cfg, nan).is_err());
}

/// Issue 20: `patch_grid_mm = 0.01` (5 GB of tables), `distance_grid_mm =
/// 1e-6` and `dome_radius_mm = 1e9` aborted the process on allocation;
/// they are refused with the bound, and the spacing the message suggests
/// is accepted.
#[test]
fn configs_implying_huge_tables_are_refused_with_the_bound() {
    let suggested = |err: &SensorError| -> f64 {
        let msg = err.to_string();
        let tail = msg.rsplit("at least ").next().unwrap();
        tail.trim_end_matches(" mm").parse().unwrap()
    };
    let mut cfg = TacTipConfig::default();
    cfg.mechanics.patch_grid_mm = 0.01;
    let err = cfg.validate().expect_err("a 0.01 mm patch grid");
    let msg = err.to_string();
    assert!(
        matches!(
            err,
            SensorError::TooLarge {
                field: "mechanics.patch_grid_mm",
                ..
            }
        ) && msg.contains("kernel weights, more than the 2e7 allowed"),
        "{msg}"
    );
    cfg.mechanics.patch_grid_mm = suggested(&err);
    cfg.validate().expect("the suggested patch grid");
    cfg.mechanics.patch_grid_mm = suggested(&err) - 0.002;
    assert!(cfg.validate().is_err(), "just finer than the suggestion");

    let mut cfg = TacTipConfig::default();
    cfg.mechanics.distance_grid_mm = 1e-6;
    let err = cfg.validate().expect_err("a 1e-6 mm distance grid");
    assert!(
        matches!(
            err,
            SensorError::TooLarge {
                field: "mechanics.distance_grid_mm",
                ..
            }
        ) && err.to_string().contains("more than the 4e6 allowed"),
        "{err}"
    );
    cfg.mechanics.distance_grid_mm = suggested(&err);
    cfg.validate().expect("the suggested distance grid");

    let mut cfg = TacTipConfig::default();
    cfg.geometry.dome_radius_mm = 1e9;
    let err = TacTipModel::new(cfg).expect_err("a 1e9 mm dome");
    assert!(err.to_string().contains("must be at most 500 mm"), "{err}");
    TacTipConfig::default().validate().expect("the defaults");
}
