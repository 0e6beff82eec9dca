//! A heavier weight for the rows whose target lies in a band
//! (`band_weight`): a weight of `w` over every row is the set repeated `w`
//! times (the weighted loss of per-sample SGD), a weighted band is fitted
//! more closely than without the weight, the setting is kept in the model
//! file, and bad settings are refused by name.
use crate::support;

use support::correlated_rows;
use tactrace_learn::{
    BandWeight, Dataset, ModelConfig, ModelKind, ModelTarget, PoseModel, Preset, Unit,
};

fn outputs() -> Vec<ModelTarget> {
    vec![
        ModelTarget::new("pose_2", Unit::Mm),
        ModelTarget::new("pose_6", Unit::Deg),
    ]
}

fn rows(n: usize, seed: u64) -> Dataset {
    let (x, y) = correlated_rows(n, 24, seed);
    Dataset::new(x, y, n, 24, 2).unwrap()
}

/// A small PCADenNN, `epochs` epochs, with `band`.
fn small(band: Option<BandWeight>, epochs: usize) -> ModelConfig {
    let mut cfg = ModelConfig::preset(ModelKind::PcaDenNN, Preset::Default);
    cfg.set_epochs(epochs);
    cfg.band_weight = band;
    let net = cfg.pose.as_mut().unwrap();
    net.hidden = vec![24];
    net.n_components = Some(8);
    cfg
}

fn band(min: Option<f64>, max: Option<f64>, weight: usize) -> BandWeight {
    BandWeight {
        target: "pose_2".into(),
        min,
        max,
        weight,
    }
}

fn fit(cfg: &ModelConfig, data: &Dataset) -> PoseModel {
    PoseModel::fit_targets(cfg, &outputs(), data, None, &mut |_| {})
        .unwrap()
        .0
}

/// `data` followed by itself.
fn twice(data: &Dataset) -> Dataset {
    let x = [data.x.as_slice(), &data.x].concat();
    let y = [data.y.as_slice(), &data.y].concat();
    Dataset::new(x, y, 2 * data.n, data.dim_x, data.dim_y).unwrap()
}

/// Mean absolute error of target `t` over the rows of `data` `keep` picks.
fn mae_where(model: &PoseModel, data: &Dataset, t: usize, keep: impl Fn(&[f32]) -> bool) -> f64 {
    let pred = model.predict_targets_batch(data).unwrap();
    let picked: Vec<f64> = (0..data.n)
        .filter(|&i| keep(data.y_row(i)))
        .map(|i| (pred[i][t] - f64::from(data.y_row(i)[t])).abs())
        .collect();
    assert!(!picked.is_empty());
    picked.iter().sum::<f64>() / picked.len() as f64
}

/// The largest difference between two models' predictions, target by target.
fn largest_difference(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_weight_over_every_row_is_the_set_repeated() {
    // Per-sample SGD visits each row `w` times an epoch: the same shuffle
    // of 2n positions, each position the same row, as the doubled set
    // (whose standardiser and PCA agree up to rounding).
    let data = rows(120, 1);
    let weighted = fit(&small(Some(band(Some(-100.0), None, 2)), 3), &data);
    let doubled = fit(&small(None, 3), &twice(&data));
    let test = rows(40, 2);
    let (a, b) = (
        weighted.predict_targets_batch(&test).unwrap(),
        doubled.predict_targets_batch(&test).unwrap(),
    );
    let worst = largest_difference(&a, &b);
    assert!(worst < 1e-3, "largest difference {worst}");
    // And not the set seen once.
    let once = fit(&small(None, 3), &data)
        .predict_targets_batch(&test)
        .unwrap();
    let apart = largest_difference(&a, &once);
    assert!(apart > 1e-2, "a weight that changes nothing: {apart}");
}

#[test]
fn the_weighted_band_is_fitted_more_closely() {
    let data = rows(400, 3);
    let in_band = |y: &[f32]| y[0] > 3.0;
    let plain = fit(&small(None, 2), &data);
    let weighted = fit(&small(Some(band(Some(3.0), None, 8)), 2), &data);
    let (p, w) = (
        mae_where(&plain, &data, 0, in_band),
        mae_where(&weighted, &data, 0, in_band),
    );
    assert!(w < 0.9 * p, "band rows: weighted {w} mm, plain {p} mm");
}

#[test]
fn the_band_is_kept_in_the_model_file_and_changes_no_prediction() {
    let data = rows(120, 4);
    let plain = fit(&small(None, 2), &data);
    assert!(!plain.to_bytes().unwrap().0.contains("band_weight"));
    let model = fit(&small(Some(band(Some(1.0), Some(4.0), 3)), 2), &data);
    let (json, weights) = model.to_bytes().unwrap();
    assert!(json.contains("\"band_weight\""), "{json}");
    let again = PoseModel::from_bytes(&json, &weights).unwrap();
    assert_eq!(
        again.config().band_weight,
        Some(band(Some(1.0), Some(4.0), 3))
    );
    assert_eq!(
        again.predict_targets_batch(&data).unwrap(),
        model.predict_targets_batch(&data).unwrap()
    );
}

#[test]
fn bad_bands_are_refused_by_name() {
    for b in [
        band(Some(1.0), None, 1),
        band(Some(1.0), None, 17),
        band(None, None, 2),
        band(Some(2.0), Some(1.0), 2),
        band(Some(f64::NAN), None, 2),
    ] {
        let err = small(Some(b.clone()), 1).validate().unwrap_err();
        assert!(err.to_string().contains("band_weight"), "{b:?}: {err}");
    }
    let data = rows(60, 5);
    let unknown = BandWeight {
        target: "pose_3".into(),
        ..band(Some(1.0), None, 2)
    };
    let err = PoseModel::fit_targets(
        &small(Some(unknown), 1),
        &outputs(),
        &data,
        None,
        &mut |_| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("pose_3"), "{err}");
    let mut circular = outputs();
    circular[1].circular = true;
    let angle = BandWeight {
        target: "pose_6".into(),
        ..band(Some(1.0), None, 2)
    };
    let err = PoseModel::fit_targets(&small(Some(angle), 1), &circular, &data, None, &mut |_| {})
        .unwrap_err();
    assert!(err.to_string().contains("circular"), "{err}");
}
