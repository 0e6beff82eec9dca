//! Continuing a fitted pin model (`PoseModel::continue_on_pins`, what
//! `train --init` does for a pin model): no epochs more predict as the
//! model did, N more epochs at constant rates from a model of N are the
//! model of 2N from scratch (its shuffles and noise continued), and a
//! configuration of other nets or other pins is refused.
use tactrace_learn::{
    check_continuable, Dataset, ModelConfig, ModelKind, ModelTarget, PoseModel, Preset, Rotations,
    Unit,
};

use crate::support;
use support::hex_layout;

/// Edges over `pins` at a few distances (px) and angles all round, the
/// angle a circular target.
fn edges(pins: &[[f64; 2]]) -> Dataset {
    let poses: Vec<(f64, f64)> = (0..30)
        .map(|i| (f64::from(i % 5) - 2.0, 12.0 * f64::from(i) - 170.0))
        .collect();
    let (x, y) = support::edge_rows(pins, &poses);
    Dataset::new(x, y, poses.len(), 2 * pins.len(), 2).unwrap()
}

fn circular_edge() -> Vec<ModelTarget> {
    vec![
        ModelTarget::new("pose_2", Unit::Mm),
        ModelTarget::circular("pose_6"),
    ]
}

/// The recipe of the 331-pin edge, small: a PCADenNN of two hidden
/// layers on the taps and their six turns, views averaged, two members.
fn recipe(epochs: usize, anneal: f64) -> ModelConfig {
    let mut cfg = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
    cfg.epochs = epochs;
    cfg.anneal_fraction = anneal;
    cfg.ensemble = 2;
    cfg.input_noise = 0.05;
    cfg.rotations = Some(Rotations {
        order: 6,
        angle_sign: -1,
        at_prediction: true,
    });
    let net = cfg.pose.as_mut().unwrap();
    net.hidden = vec![12, 6];
    net.n_components = Some(6);
    cfg
}

fn fit(cfg: &ModelConfig, data: &Dataset, pins: &[[f64; 2]]) -> PoseModel {
    PoseModel::fit_targets_on_pins(cfg, &circular_edge(), data, None, Some(pins), &mut |_| {})
        .unwrap()
        .0
}

fn continued(start: &PoseModel, cfg: &ModelConfig, data: &Dataset, pins: &[[f64; 2]]) -> PoseModel {
    start
        .continue_on_pins(cfg, data, None, Some(pins), &mut |_| {})
        .unwrap()
        .0
}

fn predictions(model: &PoseModel, data: &Dataset) -> Vec<Vec<f64>> {
    model.predict_targets_batch(data).unwrap()
}

#[test]
fn no_more_epochs_predict_as_the_model_did_after_a_save_and_load() {
    let pins = hex_layout(3);
    let data = edges(&pins);
    let start = fit(&recipe(3, 0.25), &data, &pins);
    let (json, weights) = start.to_bytes().unwrap();
    let loaded = PoseModel::from_bytes(&json, &weights).unwrap();
    let same = continued(&loaded, &recipe(0, 0.25), &data, &pins);
    assert_eq!(predictions(&same, &data), predictions(&start, &data));
    assert!(same.averages_turned_views());
    assert_eq!(same.epochs_before(), 3);
}

#[test]
fn n_more_epochs_at_constant_rates_are_the_model_of_2n() {
    let pins = hex_layout(3);
    let data = edges(&pins);
    let half = fit(&recipe(2, 0.0), &data, &pins);
    let whole = fit(&recipe(4, 0.0), &data, &pins);
    let (json, weights) = continued(&half, &recipe(2, 0.0), &data, &pins)
        .to_bytes()
        .unwrap();
    let on = PoseModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(on.epochs_before(), 2);
    assert_eq!(predictions(&on, &data), predictions(&whole, &data));
    assert_ne!(predictions(&half, &data), predictions(&whole, &data));
    // Another seed shuffles (and draws noise) otherwise: not the same fit.
    let reseeded = ModelConfig {
        seed: 9,
        ..recipe(2, 0.0)
    };
    let other = continued(&half, &reseeded, &data, &pins);
    assert_ne!(predictions(&other, &data), predictions(&whole, &data));
}

#[test]
fn other_nets_or_pins_are_refused_a_new_schedule_is_not() {
    let start = recipe(3, 0.25);
    let mut schedule = recipe(40, 1.0);
    schedule.seed = 5;
    schedule.input_noise = 0.0;
    schedule.rotations.as_mut().unwrap().at_prediction = false;
    let net = schedule.pose.as_mut().unwrap();
    net.learning_rate /= 4.0;
    net.output_learning_rate = Some(1.0);
    assert!(check_continuable(&start, &schedule).is_ok());
    let refusal = |change: &dyn Fn(&mut ModelConfig)| {
        let mut cfg = recipe(3, 0.25);
        change(&mut cfg);
        check_continuable(&start, &cfg).unwrap_err().to_string()
    };
    let hidden = refusal(&|c| c.pose.as_mut().unwrap().hidden = vec![12, 7]);
    assert!(hidden.contains("`pose.hidden`"), "{hidden}");
    let order = refusal(&|c| c.rotations.as_mut().unwrap().order = 3);
    assert!(order.contains("`rotations.order`"), "{order}");
    let members = refusal(&|c| c.ensemble = 1);
    assert!(members.contains("`ensemble`"), "{members}");
    let kind = refusal(&|c| c.kind = ModelKind::DisDenNN);
    assert!(kind.contains("`kind`"), "{kind}");

    let pins = hex_layout(3);
    let data = edges(&pins);
    let model = fit(&recipe(1, 0.25), &data, &pins);
    let moved: Vec<[f64; 2]> = pins.iter().map(|p| [p[0] + 1.0, p[1]]).collect();
    let err = model
        .continue_on_pins(&recipe(1, 0.25), &data, None, Some(&moved), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("pins"), "{err}");
}
