//! The residual image model (`input = "pin_model_and_pixels"`): `train`
//! fits its pin model (kept in the folder's `base/`) and the training
//! rows' out-of-fold base predictions (recorded in `training.json`); the
//! folder moves whole and predicts the same; a fresh model predicts what
//! its pin model predicts; `[base]` without the residual input, and
//! `--init` from a residual model, are refused. The real binary through
//! `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{expect_code, expect_refusal, json, tactrace, train, TempDir};

const RESIDUAL: &str = "input = \"pin_model_and_pixels\"\ndense = [16]\n\
                        learning_rate = 0.003\nbatch_size = 8\n\
                        [[conv]]\nchannels = 6\nkernel = 3\nstride = 2\n\
                        [base]\nmodel = \"disdennn\"\nfolds = 3\n\
                        [base.settings]\nepochs = 30\n";

/// The synthetic dataset of 90 frames in `dir`/ds and the configuration
/// `residual.toml` with `learning_rate` set.
fn set_up(dir: &Path, learning_rate: &str) {
    util::spot_frames_dataset(&dir.join("ds"), "tests/it/image_residual.rs", 90);
    let text = RESIDUAL.replace("0.003", learning_rate);
    std::fs::write(dir.join("residual.toml"), text).unwrap();
}

/// `validate --json` of `model` on ds: the per-target figures.
fn per_target(dir: &Path, model: &str) -> serde_json::Value {
    util::per_target(dir, model, "ds")
}

#[test]
fn a_residual_model_carries_its_pin_model_and_moves_whole() {
    let t = TempDir::new("image-residual");
    set_up(&t.0, "0.003");
    let cfg = ["--config", "residual.toml"];
    expect_code(&train(&t.0, "conv-mlp", "ds", "2", "res", &cfg), 0, "train");
    for file in ["model.json", "pins.json", "weights.safetensors"] {
        assert!(
            t.join("res").join("base").join(file).is_file(),
            "base/{file}"
        );
    }
    let record = std::fs::read_to_string(t.join("res").join("training.json")).unwrap();
    let base = &json(&record)["base"];
    assert_eq!(base["folds"], 3);
    assert_eq!(base["model"], "disdennn");
    assert_eq!(base["fold_of_row"].as_array().unwrap().len(), 90);
    let resolved = std::fs::read_to_string(t.join("res").join("config.toml")).unwrap();
    assert!(
        resolved.contains("[base]") && resolved.contains("folds = 3"),
        "{resolved}"
    );
    let before = per_target(&t.0, "res");
    let predicted = tactrace(&t.0, &["predict", "--model", "res", "--data", "ds"]);
    expect_code(&predicted, 0, "predict");
    std::fs::create_dir(t.join("elsewhere")).unwrap();
    std::fs::rename(t.join("res"), t.join("elsewhere").join("moved")).unwrap();
    assert_eq!(per_target(&t.0, "elsewhere/moved"), before);
    let again = tactrace(
        &t.0,
        &["predict", "--model", "elsewhere/moved", "--data", "ds"],
    );
    assert_eq!(again.stdout, predicted.stdout);
}

#[test]
fn a_fresh_residual_model_predicts_its_pin_models_figures() {
    let t = TempDir::new("image-residual-start");
    set_up(&t.0, "1e-30");
    let cfg = ["--config", "residual.toml"];
    expect_code(&train(&t.0, "conv-mlp", "ds", "1", "res", &cfg), 0, "train");
    let (image, pins) = (per_target(&t.0, "res"), per_target(&t.0, "res/base"));
    for target in ["x", "angle"] {
        let (a, b) = (
            image[target]["mae"].as_f64().unwrap(),
            pins[target]["mae"].as_f64().unwrap(),
        );
        assert!(
            (a - b).abs() < 1e-4 * (1.0 + b),
            "{target}: {a} against {b}"
        );
    }
}

#[test]
fn base_settings_and_init_are_refused_where_they_do_not_apply() {
    let t = TempDir::new("image-residual-refused");
    set_up(&t.0, "0.003");
    let pixels = RESIDUAL.replace("input = \"pin_model_and_pixels\"\n", "");
    std::fs::write(t.join("pixels.toml"), pixels).unwrap();
    let r = train(
        &t.0,
        "conv-mlp",
        "ds",
        "1",
        "p",
        &["--config", "pixels.toml"],
    );
    expect_refusal(&r, 2, "[base] on a pixels model", "pin_model_and_pixels");
    let bad = RESIDUAL.replace("folds = 3", "folds = 1");
    std::fs::write(t.join("bad.toml"), bad).unwrap();
    let r = train(&t.0, "conv-mlp", "ds", "1", "b", &["--config", "bad.toml"]);
    expect_refusal(&r, 2, "one fold", "folds");
    let cfg = ["--config", "residual.toml"];
    expect_code(&train(&t.0, "conv-mlp", "ds", "1", "res", &cfg), 0, "train");
    let init = ["--config", "residual.toml", "--init", "res"];
    let r = train(&t.0, "conv-mlp", "ds", "1", "again", &init);
    expect_refusal(&r, 2, "--init from a residual model", "out-of-fold");
}

/// `[base] fit_on = "first_dataset"` with `--train ds --train more`: the
/// first dataset's rows alone are dealt into the folds, the second's
/// marked past them (predicted by the whole base), and the record and
/// the resolved configuration say so; with one dataset it is refused.
#[test]
fn a_base_of_the_first_dataset_is_recorded_and_needs_two_datasets() {
    let t = TempDir::new("image-residual-first");
    set_up(&t.0, "0.003");
    util::spot_frames_dataset(&t.join("more"), "tests/it/image_residual.rs", 30);
    let first = RESIDUAL.replace("folds = 3\n", "folds = 3\nfit_on = \"first_dataset\"\n");
    std::fs::write(t.join("first.toml"), first).unwrap();
    let cfg = ["--train", "more", "--config", "first.toml"];
    expect_code(&train(&t.0, "conv-mlp", "ds", "1", "res", &cfg), 0, "train");
    let record = std::fs::read_to_string(t.join("res").join("training.json")).unwrap();
    let base = &json(&record)["base"];
    assert_eq!(base["first_dataset_only"], true);
    let folds: Vec<u64> = (base["fold_of_row"].as_array().unwrap().iter())
        .map(|f| f.as_u64().unwrap())
        .collect();
    assert_eq!(folds.len(), 120);
    assert!(folds[..90].iter().all(|&f| f < 3), "{folds:?}");
    assert!(folds[90..].iter().all(|&f| f == 3), "{folds:?}");
    let resolved = std::fs::read_to_string(t.join("res").join("config.toml")).unwrap();
    assert!(
        resolved.contains("fit_on = \"first_dataset\""),
        "{resolved}"
    );
    let one = ["--config", "first.toml"];
    let r = train(&t.0, "conv-mlp", "ds", "1", "alone", &one);
    expect_refusal(&r, 2, "fit_on with one dataset", "two datasets");
}
