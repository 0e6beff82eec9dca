//! `train --init MODEL` with a pin model: the model trained further on the
//! rows it was trained on. At constant rates two epochs on from a model of
//! two predict as four from scratch, digit for digit; the new folder
//! records where it started (`init.toml`, `epochs_before`); other nets,
//! other rows and an --out that is the starting folder are refused as bad
//! input. The real binary through `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{expect_code, expect_refusal, tactrace, train, TempDir};

/// A small PCADenNN at constant rates (no anneal) low enough not to
/// diverge (a retry would halve the rates of one fit and not the other's).
const SMALL: &str = "anneal_fraction = 0.0\n[pose]\nn_components = 5\nhidden = [8]\n\
                     learning_rate = 18.0\noutput_learning_rate = 2.5\n";

/// `predict` of `model` on ds: its rows as text.
fn predicted(dir: &Path, model: &str) -> String {
    let r = tactrace(dir, &["predict", "--model", model, "--data", "ds"]);
    expect_code(&r, 0, "predict");
    r.stdout
}

#[test]
fn two_epochs_on_from_two_are_four_from_scratch() {
    let t = TempDir::new("pin-init");
    expect_code(&util::collect(&t.0, "40", &["--seed", "3"], "ds"), 0, "ds");
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let small = ["--config", "small.toml"];
    expect_code(&train(&t.0, "pcadennn", "ds", "2", "m2", &small), 0, "m2");
    expect_code(&train(&t.0, "pcadennn", "ds", "4", "m4", &small), 0, "m4");
    let on = ["--config", "small.toml", "--init", "m2"];
    let r = train(&t.0, "pcadennn", "ds", "2", "m2on", &on);
    expect_code(&r, 0, "on");
    assert!(!r.stderr.contains("diverged"), "{}", r.stderr);
    assert_eq!(predicted(&t.0, "m2on"), predicted(&t.0, "m4"));
    assert_ne!(predicted(&t.0, "m2"), predicted(&t.0, "m4"));
    let init = std::fs::read_to_string(t.join("m2on").join("init.toml")).unwrap();
    assert!(
        init.contains("model = \"m2\"") && init.contains("epochs = 2"),
        "{init}"
    );
    let json = std::fs::read_to_string(t.join("m2on").join("model.json")).unwrap();
    assert!(json.contains("\"epochs_before\": 2"), "model.json");
    assert!(!t.join("m4").join("init.toml").exists());
}

#[test]
fn other_nets_other_rows_and_the_start_as_out_are_refused() {
    let t = TempDir::new("pin-init-refused");
    expect_code(&util::collect(&t.0, "40", &["--seed", "3"], "ds"), 0, "ds");
    expect_code(
        &util::collect(&t.0, "40", &["--seed", "4"], "ds2"),
        0,
        "ds2",
    );
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    std::fs::write(t.join("wide.toml"), SMALL.replace("[8]", "[9]")).unwrap();
    let small = ["--config", "small.toml"];
    expect_code(&train(&t.0, "pcadennn", "ds", "1", "m1", &small), 0, "m1");
    let wide = ["--config", "wide.toml", "--init", "m1"];
    let r = train(&t.0, "pcadennn", "ds", "1", "w", &wide);
    expect_refusal(&r, 2, "other hidden layers", "pose.hidden");
    let on = ["--config", "small.toml", "--init", "m1"];
    let r = train(&t.0, "pcadennn", "ds2", "1", "other", &on);
    expect_refusal(&r, 2, "other rows", "the rows it was trained on");
    let into_start = ["--config", "small.toml", "--init", "m1", "--force"];
    let r = train(&t.0, "pcadennn", "ds", "1", "m1", &into_start);
    expect_refusal(&r, 2, "--out the starting folder", "--init");
    for out in ["w", "other"] {
        assert!(!t.join(out).exists(), "{out}");
    }
    predicted(&t.0, "m1");
}
