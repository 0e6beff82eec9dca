//! `train` on several datasets at once (`--train A --train B`): a dataset
//! cut in two trains, half after half, to the very model the whole one
//! does (pin and image models alike), the model folder records both
//! halves, and datasets a model cannot be trained across are refused by
//! what differs, before any training.
use crate::util;
use std::path::Path;
use tactrace_store::{read_dataset, read_dataset_frames, write_dataset_with};
use util::{collect, expect_refusal, json, ok, spot_frames_dataset, tactrace, TempDir};

/// Writes the rows `rows` of the dataset `from` (with its frames, if it
/// has any) as the dataset `to`, both in `dir`.
fn write_rows(dir: &Path, from: &str, rows: std::ops::Range<usize>, to: &str) {
    let data = read_dataset(&dir.join(from)).unwrap();
    let frames = read_dataset_frames(&dir.join(from), &data).unwrap();
    let rows: Vec<usize> = rows.collect();
    let frames = frames.map(|f| f.subset(&rows));
    let part = data.subset(&rows);
    write_dataset_with(&dir.join(to), &part, &[], frames.as_ref(), false).unwrap();
}

/// The files of two model folders that must be equal, byte for byte.
fn same_model(dir: &Path, a: &str, b: &str) {
    for file in ["model.json", "weights.safetensors", "history.csv"] {
        let read = |m: &str| std::fs::read(dir.join(m).join(file)).unwrap();
        assert!(read(a) == read(b), "{a}/{file} and {b}/{file} differ");
    }
}

/// `train` with `common` arguments on the dataset `whole` into `m-whole`
/// and on `a` then `b` into `m-halves`, in `dir`: both succeed and say
/// the same validation.
fn whole_and_halves(dir: &Path, common: &[&str]) {
    let whole = [common, &["--train", "whole", "--out", "m-whole"]].concat();
    let halves = [
        common,
        &["--train", "a", "--train", "b", "--out", "m-halves"],
    ]
    .concat();
    let (w, h) = (tactrace(dir, &whole), tactrace(dir, &halves));
    ok(&w, "train on the whole");
    ok(&h, "train on the halves");
    assert_eq!(w.stdout, h.stdout, "the same validation");
}

/// `training.json` of the model folder `m` in `dir`.
fn training(dir: &Path, m: &str) -> serde_json::Value {
    json(&std::fs::read_to_string(dir.join(m).join("training.json")).unwrap())
}

#[test]
fn two_halves_train_the_pin_model_the_whole_set_trains() {
    let t = TempDir::new("train-sets-pins");
    ok(&collect(&t.0, "60", &["--seed", "3"], "whole"), "collect");
    write_rows(&t.0, "whole", 0..25, "a");
    write_rows(&t.0, "whole", 25..60, "b");
    let common = ["train", "--epochs", "2", "--val-fraction", "0.2"];
    whole_and_halves(&t.0, &common);
    same_model(&t.0, "m-whole", "m-halves");
    let (rw, rh) = (training(&t.0, "m-whole"), training(&t.0, "m-halves"));
    assert_eq!(rh["dataset"]["sha256"], rw["dataset"]["sha256"]);
    assert_eq!(rh["train_rows"], rw["train_rows"]);
    assert!(rw.get("datasets").is_none(), "one dataset lists none");
    assert_eq!(rh["dataset"]["path"], serde_json::Value::Null);
    let parts = rh["datasets"].as_array().expect("both halves listed");
    assert_eq!(
        (parts[0]["path"].as_str(), parts[0]["rows"].as_u64()),
        (Some("a"), Some(25))
    );
    assert_eq!(
        (parts[1]["path"].as_str(), parts[1]["rows"].as_u64()),
        (Some("b"), Some(35))
    );
    // Its held-out rows are of the halves joined: not of one dataset.
    let one = ["validate", "--model", "m-halves", "--data", "a"];
    let held = [&one[..], &["--val-fraction", "0.2"]].concat();
    expect_refusal(
        &tactrace(&t.0, &held),
        2,
        "held out of one",
        "2 datasets together",
    );
    let v = tactrace(&t.0, &[&one[..], &["--json"]].concat());
    ok(&v, "validate on a half");
    assert!(json(&v.stdout)["rows_seen_in_training"].as_u64().unwrap() > 0);
}

#[test]
fn two_halves_train_the_image_model_the_whole_set_trains() {
    let t = TempDir::new("train-sets-images");
    spot_frames_dataset(&t.join("whole"), "tests/it/train_sets.rs", 40);
    util::write_small_conv(&t.0);
    write_rows(&t.0, "whole", 0..15, "a");
    write_rows(&t.0, "whole", 15..40, "b");
    let common = [
        "train",
        "--model",
        "conv-mlp",
        "--epochs",
        "2",
        "--seed",
        "3",
        "--config",
        "small.toml",
        "--val-fraction",
        "0.25",
    ];
    whole_and_halves(&t.0, &common);
    for file in ["weights.safetensors", "history.csv"] {
        let read = |m: &str| std::fs::read(t.join(m).join(file)).unwrap();
        assert!(read("m-whole") == read("m-halves"), "{file} differs");
    }
    let parts = training(&t.0, "m-halves")["datasets"].clone();
    assert_eq!(parts.as_array().map(Vec::len), Some(2));
}

#[test]
fn datasets_that_differ_are_refused_by_name_before_training() {
    let t = TempDir::new("train-sets-refused");
    ok(&collect(&t.0, "20", &["--seed", "3"], "a"), "collect");
    let data = read_dataset(&t.join("a")).unwrap();
    let write = |name: &str, edit: &dyn Fn(&mut tactrace_store::TapData)| {
        let mut d = data.clone();
        edit(&mut d);
        tactrace_store::write_dataset(&t.join(name), &d, &[], false).unwrap();
    };
    write("swapped", &|d| d.meta.reference_pins.swap(0, 60));
    write("renamed", &|d| d.meta.targets[1] = "angle".into());
    write("fewer", &|d| {
        let dim = d.dim();
        d.meta.reference_pins.pop();
        d.inputs = (d.inputs.chunks(dim))
            .flat_map(|row| [&row[..dim / 2 - 1], &row[dim / 2..dim - 1]].concat())
            .collect();
    });
    for (other, says) in [
        (
            "swapped",
            "a and swapped cannot be trained on together: their reference pins differ",
        ),
        (
            "renamed",
            "their targets differ: r_mm (mm), theta_deg (deg) against r_mm (mm), angle (deg)",
        ),
        (
            "fewer",
            "their pin counts differ: 127 pins (254 inputs a row) against 126 pins",
        ),
    ] {
        let run = tactrace(
            &t.0,
            &["train", "--train", "a", "--train", other, "--out", "m"],
        );
        expect_refusal(&run, 2, other, says);
        assert!(!t.join("m").exists(), "{other}: nothing trained");
    }
    spot_frames_dataset(&t.join("frames16"), "tests/it/train_sets.rs", 12);
    let spots = read_dataset(&t.join("frames16")).unwrap();
    let eight = |k: usize| (0..64).map(move |i| ((i + k) % 7 * 30) as u8);
    let pixels = (0..12).flat_map(eight).collect();
    let (inputs, targets) = (spots.inputs.clone(), spots.targets.clone());
    util::write_spot_frames(
        &t.join("frames8"),
        "tests/it/train_sets.rs",
        8,
        inputs,
        targets,
        pixels,
    );
    tactrace_store::write_dataset(&t.join("no-frames"), &spots, &[], false).unwrap();
    for (other, says) in [
        (
            "frames8",
            "their frames differ: 16 x 16 px, no preprocessing recorded against 8 x 8 px",
        ),
        (
            "no-frames",
            "no-frames: the dataset holds pin displacements only",
        ),
    ] {
        let mut args = vec!["train", "--model", "conv-mlp", "--train", "frames16"];
        args.extend(["--train", other, "--out", "m"]);
        expect_refusal(&tactrace(&t.0, &args), 2, other, says);
    }
}
