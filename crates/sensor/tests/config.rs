//! Configuration checks and measured rest layouts.
mod common;
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
