//! `[base] from = "MODEL"`: a residual image model trained on the base
//! (pin model, folds, out-of-fold predictions) of a residual model folder
//! instead of fitting it again. For the same seed it is the model trained
//! with the base refitted, digit for digit, and `training.json` says
//! whose base it took; another dataset, or other base settings, are
//! refused with what differs. The real binary through `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{expect_code, expect_refusal, json, per_target, train, TempDir};

const RESIDUAL: &str = "input = \"pin_model_and_pixels\"\ndense = [16]\n\
                        learning_rate = 0.003\nbatch_size = 8\n\
                        [[conv]]\nchannels = 6\nkernel = 3\nstride = 2\n\
                        [base]\nmodel = \"disdennn\"\nfolds = 3\n\
                        [base.settings]\nepochs = 30\n";

/// RESIDUAL with `from = "res"` in its `[base]` table and `change`
/// applied, as `name` in `dir`.
fn reusing(dir: &Path, name: &str, change: (&str, &str)) {
    let text = RESIDUAL
        .replace("[base]\n", "[base]\nfrom = \"res\"\n")
        .replace(change.0, change.1);
    std::fs::write(dir.join(name), text).unwrap();
}

fn read(dir: &Path, file: &str) -> Vec<u8> {
    std::fs::read(dir.join(file)).unwrap()
}

#[test]
fn a_reused_base_gives_the_refitted_models_figures_digit_for_digit() {
    let t = TempDir::new("image-base-reuse");
    util::spot_frames_dataset(&t.join("ds"), "tests/it/image_base_reuse.rs", 90);
    std::fs::write(t.join("residual.toml"), RESIDUAL).unwrap();
    reusing(&t.0, "reuse.toml", ("", ""));
    let seed = ["--seed", "4"];
    let fitted = [&["--config", "residual.toml"][..], &seed].concat();
    expect_code(
        &train(&t.0, "conv-mlp", "ds", "2", "res", &fitted),
        0,
        "fit",
    );
    let fitted = [&["--config", "residual.toml"][..], &["--seed", "5"]].concat();
    expect_code(
        &train(&t.0, "conv-mlp", "ds", "2", "res5", &fitted),
        0,
        "fit",
    );
    let reused = [&["--config", "reuse.toml"][..], &seed].concat();
    expect_code(
        &train(&t.0, "conv-mlp", "ds", "2", "again", &reused),
        0,
        "reuse",
    );
    for file in [
        "weights.safetensors",
        "base/weights.safetensors",
        "history.csv",
    ] {
        let (a, b) = (read(&t.join("res"), file), read(&t.join("again"), file));
        assert!(a == b, "{file} differs");
    }
    assert_eq!(
        per_target(&t.0, "again", "ds"),
        per_target(&t.0, "res", "ds")
    );
    let record = |m: &str| json(&String::from_utf8(read(&t.join(m), "training.json")).unwrap());
    let (first, second) = (
        record("res")["base"].clone(),
        record("again")["base"].clone(),
    );
    assert_eq!(second["reused_from"], "res");
    assert!(first.get("reused_from").is_none());
    for key in ["fold_of_row", "predictions", "seed", "folds", "model"] {
        assert_eq!(first[key], second[key], "{key}");
    }
    assert_eq!(first["predictions"].as_array().unwrap().len(), 90 * 2);
    let other_seed = record("res5")["base"].clone();
    assert_ne!(other_seed["fold_of_row"], first["fold_of_row"]);
    let config = String::from_utf8(read(&t.join("again"), "config.toml")).unwrap();
    assert!(config.contains("from = \"res\""), "{config}");
}

#[test]
fn another_dataset_or_other_base_settings_are_refused_by_name() {
    let t = TempDir::new("image-base-reuse-refused");
    util::spot_frames_dataset(&t.join("ds"), "tests/it/image_base_reuse.rs", 90);
    util::spot_frames_dataset(&t.join("fewer"), "tests/it/image_base_reuse.rs", 60);
    std::fs::write(t.join("residual.toml"), RESIDUAL).unwrap();
    let cfg = ["--config", "residual.toml"];
    expect_code(&train(&t.0, "conv-mlp", "ds", "1", "res", &cfg), 0, "fit");
    reusing(&t.0, "reuse.toml", ("", ""));
    let r = train(
        &t.0,
        "conv-mlp",
        "fewer",
        "1",
        "x",
        &["--config", "reuse.toml"],
    );
    expect_refusal(
        &r,
        2,
        "another dataset",
        "fitted on 90 training rows, these are 60",
    );
    let held = ["--config", "reuse.toml", "--val-fraction", "0.2"];
    let r = train(&t.0, "conv-mlp", "ds", "1", "x", &held);
    expect_refusal(&r, 2, "another split", "training rows");
    for (change, named) in [
        (("folds = 3", "folds = 4"), "(folds differs)"),
        (
            ("epochs = 30", "epochs = 31"),
            "([base.settings] epochs differs)",
        ),
        (("disdennn", "pdennn"), "(model differs)"),
    ] {
        reusing(&t.0, "other.toml", change);
        let r = train(
            &t.0,
            "conv-mlp",
            "ds",
            "1",
            "x",
            &["--config", "other.toml"],
        );
        expect_refusal(&r, 2, named, named);
    }
    reusing(&t.0, "pins.toml", ("\"res\"", "\"res/base\""));
    let r = train(&t.0, "conv-mlp", "ds", "1", "x", &["--config", "pins.toml"]);
    expect_refusal(&r, 2, "a pin model's folder", "not a residual image model");
    assert!(!t.join("x").exists(), "a refused training left a folder");
}
