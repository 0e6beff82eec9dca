//! The report's figures through the public API: what their titles and axes
//! say.
use std::path::Path;
use tactrace_learn::{EpochReport, ModelKind, NetEpoch, TrainingHistory};
use tactrace_report::figures::{
    model_on_data_title, predicted_vs_true, training_curves, Predicted,
};

/// Issue 20: `validate --plots DIR` titled both panels "model" and showed
/// no error. Each panel now names the model's kind, its folder and the
/// dataset, and shows its mean absolute error with its unit.
#[test]
fn validation_plots_name_the_model_and_data_and_show_the_mae() {
    let title = model_on_data_title(
        ModelKind::PDenNN,
        Path::new("models/pdennn/"),
        Path::new("data/val"),
    );
    assert_eq!(title, "PDenNN pdennn on val");
    let long = model_on_data_title(
        ModelKind::Mlp,
        Path::new("m"),
        Path::new("a-dataset-folder-with-a-very-long-name"),
    );
    assert_eq!(long, "MLP m on a-dataset-folder-with-a\u{2026}");
    let truth = [[1.0, 10.0], [-1.0, -10.0], [0.5, 0.0]];
    let predictions = [[1.25, 12.0], [-0.75, -8.0], [0.25, 2.0]];
    let dir = tempfile::tempdir().unwrap();
    let stem = dir.path().join("predicted_vs_true");
    let paths = predicted_vs_true(
        &stem,
        &title,
        &Predicted {
            truth: &truth,
            predictions: &predictions,
            mae: [0.25, 2.0],
        },
    )
    .unwrap();
    let svg = std::fs::read_to_string(&paths[0]).unwrap();
    assert!(
        svg.contains("PDenNN pdennn on val: position r, MAE 0.250 mm"),
        "{svg}"
    );
    assert!(svg.contains("PDenNN pdennn on val: angle theta, MAE 2.000 deg"));
    assert!(!svg.contains(">model:"), "the old title");
}

/// The numbers printed along the bottom of a figure's SVG: the x axes'
/// tick labels (they sit lower than any y axis label).
fn x_tick_labels(svg: &str) -> Vec<f64> {
    let numbers: Vec<(f64, f64)> = svg
        .split("<text")
        .skip(1)
        .filter_map(|element| {
            let y = element
                .split("y=\"")
                .nth(1)?
                .split('"')
                .next()?
                .parse()
                .ok()?;
            let text = element.split('>').nth(1)?.split('<').next()?;
            Some((y, text.trim().parse().ok()?))
        })
        .collect();
    let bottom = numbers.iter().map(|n| n.0).fold(f64::MIN, f64::max);
    numbers
        .iter()
        .filter(|n| n.0 == bottom)
        .map(|n| n.1)
        .collect()
}

/// A made-up history of `epochs` epochs of one net, the loss halving.
fn history(epochs: usize) -> TrainingHistory {
    TrainingHistory {
        epochs: (0..epochs)
            .map(|epoch| EpochReport {
                epoch,
                nets: vec![NetEpoch {
                    name: "net".into(),
                    loss: 0.5f64.powi(epoch as i32),
                    energy: 2.0 * 0.5f64.powi(epoch as i32),
                    val_loss: None,
                }],
            })
            .collect(),
        ..TrainingHistory::default()
    }
}

/// Session 13's new user: the loss figure of a 5-epoch run had ticks at
/// 1.5, 2.5, ...; an epoch axis now ticks at whole epochs only, on short
/// runs and long ones, with at least one tick.
#[test]
fn the_epoch_axis_ticks_at_whole_epochs() {
    let dir = tempfile::tempdir().unwrap();
    for epochs in [1, 2, 3, 5, 7, 12, 40] {
        let stem = dir.path().join(format!("loss_{epochs}"));
        let paths = training_curves(&stem, &history(epochs)).unwrap();
        let svg = std::fs::read_to_string(&paths[0]).unwrap();
        let ticks = x_tick_labels(&svg);
        assert!(!ticks.is_empty(), "{epochs} epochs: no x tick");
        for tick in &ticks {
            assert_eq!(tick.fract(), 0.0, "{epochs} epochs: a tick at {tick}");
            // On the padded axis: epoch 0 or one past the last may show.
            assert!(
                (0.0..=epochs as f64 + 1.0).contains(tick),
                "{epochs}: {tick}"
            );
        }
    }
}
