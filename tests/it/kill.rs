//! kill -9 in the middle of `collect`, `train`, `follow` and `reproduce`
//! (issue 10, item 5) leaves nothing that looks complete: `--out` either
//! does not exist or is complete (read back per kind), and beside it there
//! is only what is clearly partial (a hidden `.OUT.partial-*` staging
//! folder, or a follow run's `OUT.partial` whose trajectory holds whole
//! rows). A re-run with the same `--out` then succeeds without `--force`.
//!
//! The kill delays are a fixed schedule from "before the process starts
//! working" to well inside the run; the assertions hold wherever the kill
//! lands, so the tests do not depend on timing.
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

/// Milliseconds between spawning and SIGKILL (`Child::kill` on Unix).
const DELAYS_MS: [u64; 5] = [0, 4, 25, 120, 500];

fn tactrace(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("binary runs")
}

fn ok(dir: &Path, args: &[&str]) {
    let out = tactrace(dir, args);
    assert!(
        out.status.success(),
        "tactrace {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Start `tactrace args` in `dir` and kill -9 it after `delay_ms`.
fn kill_after(dir: &Path, args: &[&str], delay_ms: u64) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("binary starts");
    std::thread::sleep(Duration::from_millis(delay_ms));
    // SIGKILL; an error only means the process had already finished.
    let _ = child.kill();
    child.wait().expect("child reaped");
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Dataset,
    Model,
    FollowRun,
    Reproduction,
}

/// Whether `dir` is a complete output of `kind`, read back; panics with
/// the reason when it is not.
fn assert_complete(kind: Kind, dir: &Path) {
    match kind {
        Kind::Dataset => {
            let data = tactrace_store::dataset::read_dataset(dir)
                .unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
            assert!(!data.is_empty(), "{}", dir.display());
        }
        Kind::Model => {
            tactrace_store::StoredModel::load(dir)
                .unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        }
        Kind::FollowRun => {
            let m = metrics(dir);
            assert!(m["succeeded"].is_boolean(), "{m}");
            let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
            assert_whole_rows(&csv);
        }
        Kind::Reproduction => {
            let m = metrics(dir);
            assert!(m.is_object(), "{m}");
            let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
            assert!(
                html.trim_end().ends_with("</html>"),
                "report.html cut short"
            );
        }
    }
}

fn metrics(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("metrics.json"))
        .unwrap_or_else(|e| panic!("{}/metrics.json: {e}", dir.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}/metrics.json: {e}", dir.display()))
}

/// A trajectory written step by step: a header, then rows of 8 fields,
/// steps numbered from 0, each row ended by a newline.
fn assert_whole_rows(csv: &str) {
    if csv.is_empty() {
        return; // created, nothing written yet
    }
    assert!(csv.ends_with('\n'), "a cut row: {csv:?}");
    let mut lines = csv.lines();
    assert!(lines.next().unwrap().starts_with("step,"), "{csv}");
    for (k, row) in lines.enumerate() {
        let fields: Vec<&str> = row.split(',').collect();
        assert_eq!(fields.len(), 8, "{row}");
        assert_eq!(fields[0], k.to_string(), "{row}");
    }
}

/// After a kill: `root` holds `out` only if complete, a follow run's
/// `out.partial` only with whole rows, and otherwise only hidden staging
/// folders. Returns whether `out` exists and whether a partial trajectory
/// with at least one row was left.
fn assert_nothing_looks_complete(kind: Kind, root: &Path, out: &str) -> (bool, bool) {
    let partial = format!("{out}.partial");
    let staging = format!(".{out}.partial-");
    let mut rows = false;
    for entry in std::fs::read_dir(root).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        if name == out {
            assert_complete(kind, &root.join(out));
        } else if name == partial && kind == Kind::FollowRun {
            let csv = root.join(&partial).join("trajectory.csv");
            if csv.exists() {
                let text = std::fs::read_to_string(csv).unwrap();
                assert_whole_rows(&text);
                rows |= text.lines().count() > 1;
            }
        } else if name == format!(".{out}.lock") || name == format!(".{partial}.lock") {
            // The killed run's output lock: unlocked now that it is dead,
            // taken over (and removed) by the next run.
        } else if !INPUTS.contains(&name.as_str()) {
            assert!(
                name.starts_with(&staging),
                "{name} left beside {out} in {}",
                root.display()
            );
        }
    }
    (root.join(out).exists(), rows)
}

/// What the runs read, copied beside `out`.
const INPUTS: [&str; 3] = ["ds", "model", "rep.toml"];

/// For each delay: kill `long` (writing `out`), check what is left, and
/// once the kill left no `out`, re-run `short` into the same `out` (no
/// `--force`) and check it is complete. Returns how many kills landed
/// before the output was complete, and how many left a partial
/// trajectory with rows.
fn kill_and_rerun(kind: Kind, setup: &Path, long: &[&str], short: &[&str]) -> (usize, usize) {
    let mut interrupted = 0;
    let mut with_rows = 0;
    let mut rerun = false;
    for delay in DELAYS_MS {
        let root = tempfile::tempdir().unwrap();
        link_inputs(setup, root.path());
        kill_after(root.path(), long, delay);
        let (exists, rows) = assert_nothing_looks_complete(kind, root.path(), "out");
        with_rows += rows as usize;
        if exists {
            continue;
        }
        interrupted += 1;
        let leftover = root.path().join("out.partial").exists();
        if !rerun || leftover {
            ok(root.path(), short);
            assert_complete(kind, &root.path().join("out"));
            assert!(!root.path().join("out.partial").exists());
            assert!(!root.path().join(".out.lock").exists());
            rerun = true;
        }
    }
    assert!(rerun, "{kind:?}: every kill landed after the run was over");
    (interrupted, with_rows)
}

/// The inputs every run reads (`ds`, `model`, `rep.toml`), copied in.
fn link_inputs(setup: &Path, root: &Path) {
    for entry in std::fs::read_dir(setup).unwrap() {
        let entry = entry.unwrap();
        copy_tree(&entry.path(), &root.join(entry.file_name()));
    }
}

fn copy_tree(from: &Path, to: &Path) {
    if from.is_dir() {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap() {
            let e = e.unwrap();
            copy_tree(&e.path(), &to.join(e.file_name()));
        }
    } else {
        std::fs::copy(from, to).unwrap();
    }
}

/// The inputs: a small dataset (`ds`), a model trained on it (`model`) as
/// `what` asks, and a small reproduce config (`rep.toml`).
fn setup(dataset: bool, model: bool) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().to_path_buf();
    if dataset || model {
        ok(
            &p,
            &["collect", "--samples", "300", "--seed", "3", "--out", "ds"],
        );
    }
    if model {
        let args = ["train", "--train", "ds", "--epochs", "15", "--out", "model"];
        ok(&p, &args);
    }
    let rep = "train_samples = 200\nval_samples = 100\nepochs = 3\n";
    std::fs::write(p.join("rep.toml"), rep).unwrap();
    (dir, p)
}

#[test]
fn kill_9_during_collect_leaves_no_complete_looking_dataset() {
    let (_keep, setup) = setup(false, false);
    let (n, _) = kill_and_rerun(
        Kind::Dataset,
        &setup,
        &["collect", "--samples", "2500", "--out", "out"],
        &["collect", "--samples", "20", "--out", "out"],
    );
    assert!(n >= 3, "only {n} kills landed during the collection");
}

#[test]
fn kill_9_during_train_leaves_no_complete_looking_model() {
    let (_keep, setup) = setup(true, false);
    let (n, _) = kill_and_rerun(
        Kind::Model,
        &setup,
        &["train", "--train", "ds", "--epochs", "600", "--out", "out"],
        &["train", "--train", "ds", "--epochs", "1", "--out", "out"],
    );
    assert!(n >= 3, "only {n} kills landed during the training");
}

#[test]
fn kill_9_during_follow_leaves_a_partial_run_and_a_rerun_replaces_it() {
    let (_keep, setup) = setup(true, true);
    let common = [
        "follow", "--model", "model", "--shape", "disk", "--out", "out",
    ];
    let long: Vec<&str> = common.iter().copied().chain(["--steps", "3000"]).collect();
    let short: Vec<&str> = common.iter().copied().chain(["--steps", "3"]).collect();
    let (n, _) = kill_and_rerun(Kind::FollowRun, &setup, &long, &short);
    assert!(n >= 3, "only {n} kills landed during the run");

    // And once surely in the middle: when the trajectory has rows.
    let root = tempfile::tempdir().unwrap();
    link_inputs(&setup, root.path());
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(&long)
        .current_dir(root.path())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("binary starts");
    let csv = root.path().join("out.partial/trajectory.csv");
    let deadline = std::time::Instant::now() + Duration::from_secs(30);
    while std::fs::read_to_string(&csv).map_or(true, |t| t.lines().count() < 3)
        && std::time::Instant::now() < deadline
    {
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = child.kill();
    child.wait().unwrap();
    let (exists, rows) = assert_nothing_looks_complete(Kind::FollowRun, root.path(), "out");
    assert!(!exists && rows, "the run was not killed in the middle");
    ok(root.path(), &short);
    assert_complete(Kind::FollowRun, &root.path().join("out"));
    assert!(!root.path().join("out.partial").exists());
}

#[test]
fn kill_9_during_reproduce_leaves_no_complete_looking_report() {
    let (_keep, setup) = setup(false, false);
    let args = ["reproduce", "--config", "rep.toml", "--out", "out"];
    let (n, _) = kill_and_rerun(Kind::Reproduction, &setup, &args, &args);
    assert!(n >= 3, "only {n} kills landed during the reproduction");
}
