//! `train --init MODEL`: an image model started from a trained one and
//! fine-tuned (pretrain on simulated frames, then the real ones). The new
//! folder records where it started (`init.toml`); it starts from the
//! trained weights, so one epoch from them beats one epoch from fresh
//! ones; other networks, a pin model to start from, and a pin model to
//! train are refused as bad input. The real binary through `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{expect_code, expect_refusal, json, tactrace, train, TempDir};

/// The synthetic dataset of `n` frames in `dir`.
fn dataset(dir: &Path, n: usize) {
    util::spot_frames_dataset(dir, "tests/it/image_init.rs", n);
}

const SMALL: &str = "dense = [16]\nlearning_rate = 0.003\nbatch_size = 8\n\
                     [[conv]]\nchannels = 6\nkernel = 3\nstride = 2\n";

/// The x MAE of `model` on the held-out quarter of `ds`.
fn x_mae(dir: &Path, model: &str) -> f64 {
    let data = ["--data", "ds", "--val-fraction", "0.25", "--json"];
    let r = tactrace(dir, &[&["validate", "--model", model], &data[..]].concat());
    expect_code(&r, 0, "validate");
    json(&r.stdout)["per_target"]["x"]["mae"].as_f64().unwrap()
}

#[test]
fn train_init_fine_tunes_a_trained_image_model_and_records_it() {
    let t = TempDir::new("image-init");
    dataset(&t.join("ds"), 200);
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let held = ["--val-fraction", "0.25", "--config", "small.toml"];
    let r = train(&t.0, "conv-mlp", "ds", "25", "pre", &held);
    expect_code(&r, 0, "pretrain");
    let mut from = held.to_vec();
    from.extend(["--seed", "4"]);
    expect_code(
        &train(&t.0, "conv-mlp", "ds", "1", "fresh", &from),
        0,
        "fresh",
    );
    from.extend(["--init", "pre"]);
    let r = train(&t.0, "conv-mlp", "ds", "1", "tuned", &from);
    expect_code(&r, 0, "train --init");
    let record = std::fs::read_to_string(t.join("tuned").join("init.toml")).unwrap();
    assert!(
        record.contains("model = \"pre\"")
            && record.contains("kind = \"conv-mlp\"")
            && record.contains("seed = 0"),
        "{record}"
    );
    let (pre, fresh, tuned) = (
        x_mae(&t.0, "pre"),
        x_mae(&t.0, "fresh"),
        x_mae(&t.0, "tuned"),
    );
    assert!(
        tuned < 0.5 * fresh,
        "x MAE: pretrained {pre}, one epoch fresh {fresh}, one epoch from it {tuned}"
    );
    assert!(!t.join("fresh").join("init.toml").exists());
}

#[test]
fn train_init_refuses_other_networks_and_pin_models() {
    let t = TempDir::new("image-init-refused");
    dataset(&t.join("ds"), 40);
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let small = ["--config", "small.toml"];
    expect_code(&train(&t.0, "conv-mlp", "ds", "1", "pre", &small), 0, "pre");
    std::fs::write(t.join("wider.toml"), SMALL.replace("[16]", "[20]")).unwrap();
    let r = train(
        &t.0,
        "conv-mlp",
        "ds",
        "1",
        "wide",
        &["--config", "wider.toml", "--init", "pre"],
    );
    expect_refusal(&r, 2, "other dense layers", "dense");
    assert!(!t.join("wide").exists());
    let r = train(&t.0, "pdennn", "ds", "1", "pins", &["--init", "pre"]);
    expect_refusal(&r, 2, "a pin model with --init", "--init");
    expect_code(
        &train(&t.0, "pdennn", "ds", "1", "pins", &[]),
        0,
        "a pin model",
    );
    let r = train(
        &t.0,
        "conv-mlp",
        "ds",
        "1",
        "from-pins",
        &["--init", "pins"],
    );
    expect_refusal(&r, 2, "an image model from a pin model", "a pin model");
}
