//! Held out by construction (issue 20): a model folder records which rows
//! of which dataset it was trained on; `validate` says how many of the
//! rows it scores the model has seen and can score exactly the rows
//! `train --val-fraction` held out; `follow --replay` says when its bank
//! holds frames the model was trained on; a folder of the wrong kind is
//! named. Each test runs the real binary through `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{
    collect, dataset_and_model, follow_disk_replay, import_labelled, json, ok, real_data,
    real_paths, tactrace, Run, TempDir,
};

/// `ds` (60 simulated taps, seed 3) and `m`, trained on 45 of them with
/// 15 held out (--val-fraction 0.25 --split-seed 3); returns train's
/// output.
fn dataset_and_held_out_model(dir: &Path) -> Run {
    let split = ["--val-fraction", "0.25", "--split-seed", "3"];
    dataset_and_model(dir, "60", &["--seed", "3"], &split)
}

fn validate(dir: &Path, args: &[&str]) -> Run {
    tactrace(
        dir,
        &[&["validate", "--model", "m", "--json"], args].concat(),
    )
}

/// `validate` of `m` on `data`, scoring only the rows that
/// `--val-fraction 0.25 --split-seed SPLIT_SEED` holds out.
fn validate_held_out(dir: &Path, data: &str, split_seed: &str) -> Run {
    let split = ["--val-fraction", "0.25", "--split-seed", split_seed];
    validate(dir, &[&["--data", data], &split[..]].concat())
}

#[test]
fn a_model_folder_records_the_rows_it_trained_on() {
    let t = TempDir::new("record");
    dataset_and_held_out_model(&t.0);
    let rec = json(&std::fs::read_to_string(t.join("m/training.json")).unwrap());
    let ds = &rec["dataset"];
    assert_eq!(ds["rows"], 60, "{rec}");
    assert_eq!(ds["source"], "simulated");
    assert_eq!(ds["path"], "ds");
    assert!(
        ds["sha256"].as_str().unwrap().starts_with("sha256:"),
        "{rec}"
    );
    assert_eq!(rec["split"]["val_fraction"], 0.25);
    assert_eq!(rec["split"]["split_seed"], 3);
    let rows = |v: &serde_json::Value| -> Vec<u64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|r| r.as_u64().unwrap())
            .collect()
    };
    let (mut train, held) = (rows(&rec["train_rows"]), rows(&rec["split"]["rows"]));
    assert_eq!((train.len(), held.len()), (45, 15));
    assert_eq!(rec["row_hashes"].as_array().unwrap().len(), 45);
    train.extend(&held);
    train.sort_unstable();
    assert_eq!(
        train,
        (0..60).collect::<Vec<u64>>(),
        "disjoint, every row once"
    );
}

#[test]
fn validate_counts_the_rows_seen_in_training_in_any_copy() {
    let t = TempDir::new("seen");
    dataset_and_held_out_model(&t.0);
    let r = validate(&t.0, &["--data", "ds"]);
    ok(&r, "validate");
    assert_eq!(json(&r.stdout)["rows_seen_in_training"], 45, "{}", r.stdout);
    assert!(
        r.stderr
            .contains("warning: 45 of the 60 samples are rows the model was trained on"),
        "{}",
        r.stderr
    );
    // A renamed copy is the same rows.
    std::fs::create_dir(t.join("copy")).unwrap();
    for f in ["inputs.npy", "targets.npy", "meta.json"] {
        std::fs::copy(t.join("ds").join(f), t.join("copy").join(f)).unwrap();
    }
    let r = validate(&t.0, &["--data", "copy"]);
    ok(&r, "validate copy");
    assert_eq!(json(&r.stdout)["rows_seen_in_training"], 45);
    // Other taps: none seen, no warning.
    ok(&collect(&t.0, "20", &["--seed", "9"], "other"), "collect");
    let r = validate(&t.0, &["--data", "other"]);
    ok(&r, "validate other");
    assert_eq!(json(&r.stdout)["rows_seen_in_training"], 0);
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
}

#[test]
fn validate_val_fraction_scores_exactly_the_held_out_rows() {
    let t = TempDir::new("heldout");
    let trained = dataset_and_held_out_model(&t.0);
    let r = validate_held_out(&t.0, "ds", "3");
    ok(&r, "validate held out");
    let v = json(&r.stdout);
    assert_eq!(v["samples"], 15, "{v}");
    assert_eq!(v["rows_seen_in_training"], 0, "{v}");
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
    // The same rows train scored after training.
    let line = format!(
        "validation: position {:.3} mm, angle {:.3} deg over 15 samples",
        v["position_mae_mm"].as_f64().unwrap(),
        v["angle_mae_deg"].as_f64().unwrap()
    );
    assert!(trained.stdout.contains(&line), "{line}\n{}", trained.stdout);

    // Another split, another dataset, a model without a held-out part:
    // refused (exit 2), saying why.
    let r = validate_held_out(&t.0, "ds", "4");
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("held out --val-fraction 0.25 --split-seed 3"),
        "{}",
        r.stderr
    );
    ok(&collect(&t.0, "20", &["--seed", "9"], "other"), "collect");
    let r = validate_held_out(&t.0, "other", "3");
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("not the dataset the model was trained on"),
        "{}",
        r.stderr
    );
    ok(
        &tactrace(
            &t.0,
            &["train", "--train", "ds", "--epochs", "1", "--out", "all"],
        ),
        "train all",
    );
    let r = tactrace(
        &t.0,
        &[
            "validate",
            "--model",
            "all",
            "--data",
            "ds",
            "--val-fraction",
            "0.25",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("trained on every row"), "{}", r.stderr);
}

#[test]
fn older_model_folders_load_and_say_unknown() {
    let t = TempDir::new("older");
    dataset_and_held_out_model(&t.0);
    std::fs::remove_file(t.join("m/training.json")).unwrap();
    let r = validate(&t.0, &["--data", "ds"]);
    ok(&r, "validate");
    let v = json(&r.stdout);
    assert!(v["rows_seen_in_training"].is_null(), "{v}");
    assert!(
        r.stderr
            .contains("does not record what the model was trained on"),
        "{}",
        r.stderr
    );
    // The split is recomputed: the same 15 rows.
    let r = validate_held_out(&t.0, "ds", "3");
    ok(&r, "validate held out");
    assert_eq!(json(&r.stdout)["samples"], 15);
    // A damaged record is bad input, not ignored.
    std::fs::write(t.join("m/training.json"), "{\"format\": 1}").unwrap();
    let r = validate(&t.0, &["--data", "ds"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("training.json"), "{}", r.stderr);
}

#[test]
fn a_folder_of_the_wrong_kind_is_named_with_what_was_expected() {
    let t = TempDir::new("kinds");
    dataset_and_held_out_model(&t.0);
    let r = tactrace(&t.0, &["validate", "--model", "ds", "--data", "ds"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains(
            "ds: not a model directory: this is a dataset folder (from `tactrace collect`, \
             `import` or `twin`); a model folder holds model.json"
        ),
        "{}",
        r.stderr
    );
    let r = tactrace(&t.0, &["validate", "--model", "m", "--data", "m"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains(
            "m: not a dataset directory: this is a model folder (from `tactrace train`); a \
             dataset folder holds inputs.npy, targets.npy and meta.json"
        ),
        "{}",
        r.stderr
    );
}

/// `follow --replay` with a bank holding frames the model trained on
/// warns (stderr and metrics.json); with held-out frames only, it does not.
#[test]
fn follow_replay_warns_when_the_bank_holds_training_frames() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("replay-seen");
    // The first 250 labelled rows whose frame number N has N % 5 != 0.
    let text = std::fs::read_to_string(data.join("targets.csv")).unwrap();
    let mut lines = text.lines();
    let mut part = vec![lines.next().unwrap().to_string()];
    part.extend(
        lines
            .filter(|l| {
                let name = l.split(',').next().unwrap_or_default();
                tactrace_store::collection::frame_number(name).is_some_and(|n| n % 5 != 0)
            })
            .take(250)
            .map(str::to_string),
    );
    std::fs::write(t.join("fit.csv"), part.join("\n") + "\n").unwrap();
    let [frames, _, init] = real_paths(&data);
    let r = import_labelled(&t.0, [&frames, "fit.csv", &init], &[], "fit");
    ok(&r, "import");
    ok(
        &tactrace(
            &t.0,
            &["train", "--train", "fit", "--epochs", "3", "--out", "m"],
        ),
        "train",
    );
    let rec = json(&std::fs::read_to_string(t.join("m/training.json")).unwrap());
    assert_eq!(
        rec["images"].as_array().unwrap().len(),
        250,
        "real frames named"
    );
    let follow = |extra: &[&str], out: &str| follow_disk_replay(&t.0, "m", &data, "8", extra, out);
    let metrics = |run: &str| {
        let dir = [run.to_string(), format!("{run}.partial")]
            .into_iter()
            .find(|d| t.join(d).join("metrics.json").is_file())
            .expect("metrics.json written");
        json(&std::fs::read_to_string(t.join(&dir).join("metrics.json")).unwrap())
    };
    // The whole collection: its 250 training frames are in the bank.
    let r = follow(&[], "all");
    assert!(r.code == 0 || r.code == 1, "{}", r.stderr);
    assert!(
        r.stderr.contains("of the bank's")
            && r.stderr.contains("are frames the model was trained on"),
        "{}",
        r.stderr
    );
    let m = metrics("all");
    assert_eq!(m["replay"]["bank_frames_seen_in_training"], 250, "{m}");
    assert!(
        m["replay"]["taps_answered_by_training_frames"].is_u64(),
        "{m}"
    );
    assert!(
        m["warning"]
            .as_str()
            .is_some_and(|w| w.contains("frames the model was trained on")),
        "{m}"
    );
    // Held-out frames only: none seen, no such warning.
    let r = follow(&["--replay-keep", "N%5==0"], "held");
    assert!(r.code == 0 || r.code == 1, "{}", r.stderr);
    assert!(!r.stderr.contains("trained on"), "{}", r.stderr);
    let m = metrics("held");
    assert_eq!(m["replay"]["bank_frames_seen_in_training"], 0, "{m}");
    assert_eq!(m["replay"]["taps_answered_by_training_frames"], 0, "{m}");
}
