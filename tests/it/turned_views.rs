//! `--views on|off` of `validate`, `predict` and `follow`: a model fitted
//! on turned copies (`rotations`) predicts with or without the mean over
//! each frame's turned views whatever its file says, the choice recorded
//! (`validate --json`'s `turned_views`, a follow run's `metrics.json`),
//! and a model fitted without rotations is refused by name (exit 2). The
//! real binary through `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{expect_code, expect_refusal, json, tactrace, train, TempDir};

/// A small network fitted on every frame and its copies turned by 90,
/// 180 and 270 deg.
const TURNED: &str = "dense = [8]\nlearning_rate = 0.003\nbatch_size = 8\n\
                      [[conv]]\nchannels = 4\nkernel = 3\nstride = 2\n\
                      [rotations]\norder = 4\nangle_sign = 1\n";

/// A dataset `ds` of `samples` simulated taps on the disk with their
/// 16 px frames.
fn frames_dataset(dir: &Path, samples: &str) {
    let extra = ["--shape", "disk", "--seed", "7", "--frames-size", "16"];
    expect_code(&util::collect(dir, samples, &extra, "ds"), 0, "collect");
}

/// The dataset `ds` (60 taps) and a turned-copies model `turned` fitted
/// on it for 2 epochs, its file's views off.
fn set_up(dir: &Path) {
    frames_dataset(dir, "60");
    std::fs::write(dir.join("turned.toml"), TURNED).unwrap();
    let cfg = ["--config", "turned.toml", "--seed", "4"];
    expect_code(
        &train(dir, "conv-mlp", "ds", "2", "turned", &cfg),
        0,
        "train",
    );
}

/// `validate --json` of `model` on ds with `extra` arguments.
fn validate(dir: &Path, model: &str, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["validate", "--model", model, "--data", "ds", "--json"];
    args.extend(extra);
    let r = tactrace(dir, &args);
    expect_code(&r, 0, "validate");
    json(&r.stdout)
}

#[test]
fn views_switch_at_prediction_and_are_recorded() {
    let t = TempDir::new("turned-views");
    set_up(&t.0);
    let (plain, on, off) = (
        validate(&t.0, "turned", &[]),
        validate(&t.0, "turned", &["--views", "on"]),
        validate(&t.0, "turned", &["--views", "off"]),
    );
    assert_eq!(plain["turned_views"], false, "the file's setting: off");
    assert_eq!(on["turned_views"], true);
    assert_eq!(off["turned_views"], false);
    assert_eq!(plain["per_target"], off["per_target"]);
    for target in ["r_mm", "theta_deg"] {
        let mae = |v: &serde_json::Value| v["per_target"][target]["mae"].as_f64().unwrap();
        assert!(
            (mae(&on) - mae(&off)).abs() > 1e-6,
            "{target}: the mean over four turned views predicts as the frame alone"
        );
    }
    let predict = |views: &str| {
        let args = [
            "predict", "--model", "turned", "--data", "ds", "--views", views,
        ];
        let r = tactrace(&t.0, &args);
        expect_code(&r, 0, "predict");
        r.stdout
    };
    let plain = tactrace(&t.0, &["predict", "--model", "turned", "--data", "ds"]);
    assert_eq!(plain.stdout, predict("off"));
    assert_ne!(predict("on"), predict("off"));
}

/// `follow --model turned --views VIEWS` (or the file's setting, `None`)
/// for 3 steps on the disk into `out`: its `metrics.json`.
fn follow(dir: &Path, views: Option<&str>, out: &str) -> serde_json::Value {
    let mut args = vec![
        "follow", "--model", "turned", "--shape", "disk", "--steps", "3",
    ];
    args.extend(views.map(|v| ["--views", v]).iter().flatten());
    args.extend(["--out", out]);
    expect_code(&tactrace(dir, &args), 0, "follow");
    json(&std::fs::read_to_string(dir.join(out).join("metrics.json")).unwrap())
}

#[test]
fn a_follow_run_records_its_views() {
    let t = TempDir::new("turned-views-follow");
    set_up(&t.0);
    assert_eq!(follow(&t.0, None, "plain")["turned_views"], false);
    assert_eq!(follow(&t.0, Some("on"), "on")["turned_views"], true);
    assert_eq!(follow(&t.0, Some("off"), "off")["turned_views"], false);
    let trajectory =
        |run: &str| std::fs::read_to_string(t.join(run).join("trajectory.csv")).unwrap();
    assert_eq!(trajectory("plain"), trajectory("off"));
    assert_ne!(trajectory("on"), trajectory("off"));
}

#[test]
fn a_model_without_rotations_is_refused_by_name() {
    let t = TempDir::new("turned-views-refused");
    frames_dataset(&t.0, "40");
    util::write_small_conv(&t.0);
    let cfg = ["--config", "small.toml"];
    expect_code(
        &train(&t.0, "conv-mlp", "ds", "1", "plain", &cfg),
        0,
        "train",
    );
    let says = "not fitted with rotations";
    for command in ["validate", "predict"] {
        let args = [command, "--model", "plain", "--data", "ds", "--views", "on"];
        let r = tactrace(&t.0, &args);
        expect_refusal(&r, 2, command, says);
        assert!(r.stderr.contains("plain"), "{command}: {}", r.stderr);
    }
    let args = [
        "follow", "--model", "plain", "--shape", "disk", "--steps", "2", "--views", "off", "--out",
        "run",
    ];
    let r = tactrace(&t.0, &args);
    expect_refusal(&r, 2, "follow", says);
    assert!(!t.join("run").exists() && !t.join("run.partial").exists());
    // Without the flag the run goes, and says nothing of views it has not.
    let args = [
        "follow", "--model", "plain", "--shape", "disk", "--steps", "2", "--out", "run",
    ];
    expect_code(&tactrace(&t.0, &args), 0, "follow");
    let metrics = json(&std::fs::read_to_string(t.join("run").join("metrics.json")).unwrap());
    assert!(metrics.get("turned_views").is_none(), "{metrics}");
    assert!(validate(&t.0, "plain", &[]).get("turned_views").is_none());
}
