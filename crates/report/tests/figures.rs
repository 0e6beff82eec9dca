//! The report's figures through the public API: what their titles and axes
//! say.
use std::path::Path;
use tactrace_learn::ModelKind;
use tactrace_report::figures::{model_on_data_title, predicted_vs_true, Predicted};

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
