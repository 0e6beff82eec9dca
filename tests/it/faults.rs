//! A fault in the servo loop through the binary (issue 10, item 5): a
//! model that predicts NaN makes `follow` stop safely, keep the run folder
//! with `succeeded: false`, and exit 1 naming the reason on stderr. The
//! other injected faults (frames, pins, the UR5) are in
//! crates/lab/tests/it/faults.rs; the binary reports them the same way.
use std::path::Path;
use std::process::{Command, Output};

fn tactrace(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("binary runs")
}

fn ok(dir: &Path, args: &[&str]) {
    let out = tactrace(dir, args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "tactrace {args:?}: {stderr}");
}

#[test]
fn follow_with_a_model_predicting_nan_stops_safely_and_exits_1_with_the_reason() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path();
    ok(dir, &["collect", "--samples", "150", "--out", "ds"]);
    ok(
        dir,
        &["train", "--train", "ds", "--epochs", "5", "--out", "model"],
    );
    // Input scaling of 1e-300: every input overflows, the output is NaN.
    let path = dir.join("model/model.json");
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    for s in doc["standardiser"]["std"].as_array_mut().unwrap() {
        *s = serde_json::json!(1e-300);
    }
    std::fs::write(&path, doc.to_string()).unwrap();

    let args = ["follow", "--model", "model", "--shape", "disk"];
    let out = tactrace(
        dir,
        &[&args[..], &["--steps", "20", "--out", "run"]].concat(),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("stopped safely at step 0") && stderr.contains("non-finite"),
        "{stderr}"
    );
    let run = dir.join("run");
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["succeeded"], false, "{metrics}");
    assert_eq!(metrics["ending"], "fault", "{metrics}");
    let csv = std::fs::read_to_string(run.join("trajectory.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1, "only the header: {csv}");
    assert!(!dir.join("run.partial").exists());
}
