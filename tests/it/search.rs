//! `tactrace search` end to end (issue 24): the outputs, `best.toml` taken
//! by `train --config`, seeded reproducibility, a search killed with -9
//! and resumed giving the uninterrupted search's trials, and refusals.
use crate::util;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use util::{expect_code, expect_refusal, tactrace, TempDir};

/// The shipped PDenNN space, as an absolute path.
fn space() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs/search/pdennn.toml")
        .display()
        .to_string()
}

/// A small simulated dataset `ds` in `dir`.
fn dataset(dir: &Path) {
    let r = tactrace(
        dir,
        &["collect", "--samples", "120", "--seed", "3", "--out", "ds"],
    );
    expect_code(&r, 0, "collect");
}

fn search_args<'a>(space: &'a str, out: &'a str, trials: &'a str, epochs: &'a str) -> Vec<&'a str> {
    vec![
        "search",
        "--train",
        "ds",
        "--space",
        space,
        "--trials",
        trials,
        "--epochs",
        epochs,
        "--startup",
        "3",
        "--batch",
        "2",
        "--out",
        out,
    ]
}

/// The trials of a finished search, without their timings.
fn trials(dir: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("trials.jsonl")).unwrap();
    text.lines()
        .map(|l| {
            let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
            v.as_object_mut().unwrap().remove("seconds");
            v
        })
        .collect()
}

#[test]
fn search_writes_its_outputs_and_a_config_train_accepts() {
    let t = TempDir::new("search-out");
    dataset(&t.0);
    let space = space();
    let r = tactrace(&t.0, &search_args(&space, "s", "6", "3"));
    expect_code(&r, 0, "search");
    assert!(r.stdout.contains("best: trial"), "{}", r.stdout);
    for f in [
        "config.toml",
        "trials.jsonl",
        "trials.csv",
        "best.toml",
        "convergence.png",
        "convergence.svg",
    ] {
        assert!(t.join("s").join(f).is_file(), "no {f}");
    }
    assert!(!t.join("s.partial").exists());
    assert_eq!(trials(&t.join("s")).len(), 6);
    // The table: a header and one row per trial, the settings by name.
    let csv = std::fs::read_to_string(t.join("s/trials.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(
        lines[0].split(',').any(|h| h == "angle.n_components"),
        "{}",
        lines[0]
    );
    assert_eq!(lines.len(), 7, "{csv}");
    // The seed and split are recorded.
    let config = std::fs::read_to_string(t.join("s/config.toml")).unwrap();
    assert!(
        config.contains("val_fraction = 0.25") && config.contains("seed = 0"),
        "{config}"
    );
    let r = tactrace(
        &t.0,
        &[
            "train",
            "--train",
            "ds",
            "--config",
            "s/best.toml",
            "--out",
            "m",
        ],
    );
    expect_code(&r, 0, "train --config best.toml");
    // An existing output is refused without --force.
    let r = tactrace(&t.0, &search_args(&space, "s", "6", "3"));
    expect_code(&r, 2, "search into an existing output");
}

#[test]
fn search_is_seeded() {
    let t = TempDir::new("search-seed");
    dataset(&t.0);
    let space = space();
    for out in ["a", "b"] {
        expect_code(
            &tactrace(&t.0, &search_args(&space, out, "7", "2")),
            0,
            "search",
        );
    }
    let mut c = search_args(&space, "c", "7", "2");
    c.extend(["--seed", "5"]);
    expect_code(&tactrace(&t.0, &c), 0, "search --seed 5");
    assert_eq!(trials(&t.join("a")), trials(&t.join("b")));
    assert_ne!(trials(&t.join("a")), trials(&t.join("c")));
}

/// Start a search and kill -9 it once `<out>.partial/trials.jsonl` holds
/// at least `lines` trials (or the search ended).
fn kill_after_trials(dir: &Path, args: &[&str], lines: usize) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("binary starts");
    let log = dir.join("k.partial/trials.jsonl");
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(120) {
        let n = std::fs::read_to_string(&log).map_or(0, |s| s.lines().count());
        if n >= lines || child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let _ = child.kill();
    child.wait().unwrap();
}

#[test]
fn search_killed_and_resumed_gives_the_uninterrupted_trials() {
    let t = TempDir::new("search-resume");
    dataset(&t.0);
    let space = space();
    expect_code(
        &tactrace(&t.0, &search_args(&space, "full", "16", "80")),
        0,
        "search",
    );
    let args = search_args(&space, "k", "16", "80");
    kill_after_trials(&t.0, &args, 4);
    assert!(
        !t.join("k").exists(),
        "the killed search finished: make trials slower"
    );
    let kept = trials(&t.join("k.partial")).len();
    assert!((4..16).contains(&kept), "{kept} trials kept");
    // Without --resume (or --force) the stopped search's trials are kept.
    let r = tactrace(&t.0, &args);
    expect_refusal(&r, 2, "a fresh start over a stopped search", "--resume");
    // Other settings are refused.
    let mut other = search_args(&space, "k", "16", "80");
    other.extend(["--seed", "9", "--resume"]);
    expect_code(&tactrace(&t.0, &other), 2, "resume with another seed");
    let mut resume = args.clone();
    resume.push("--resume");
    expect_code(&tactrace(&t.0, &resume), 0, "search --resume");
    assert_eq!(trials(&t.join("k")), trials(&t.join("full")));
    // Nothing to resume.
    let mut none = search_args(&space, "none", "3", "2");
    none.push("--resume");
    expect_code(&tactrace(&t.0, &none), 2, "resume with no stopped search");
}

#[test]
fn a_bad_space_is_refused_before_any_work() {
    let t = TempDir::new("search-bad");
    dataset(&t.0);
    for (name, body) in [
        (
            "unknown.toml",
            "[[param]]\nname = \"gamma\"\nlow = 1.0\nhigh = 2.0\n",
        ),
        (
            "log0.toml",
            "[[param]]\nname = \"beta\"\nlow = 0.0\nhigh = 2.0\nlog = true\n",
        ),
        (
            "frac.toml",
            "[[param]]\nname = \"hidden\"\nlow = 10\nhigh = 20\n",
        ),
        (
            "net.toml",
            "[[param]]\nname = \"pose.beta\"\nlow = 0.5\nhigh = 2.0\n",
        ),
        (
            "both.toml",
            "[[param]]\nname = \"beta\"\nlow = 0.5\nhigh = 2.0\nchoices = [1.0]\n",
        ),
        (
            "key.toml",
            "[[param]]\nname = \"beta\"\nlow = 0.5\nhigh = 2.0\nstep = 1\n",
        ),
    ] {
        std::fs::write(t.join(name), body).unwrap();
        let r = tactrace(
            &t.0,
            &["search", "--train", "ds", "--space", name, "--out", "o"],
        );
        expect_code(&r, 2, name);
        assert!(
            !t.join("o").exists() && !t.join("o.partial").exists(),
            "{name}"
        );
    }
}

/// Issue 24: `--executor ray` with an interpreter that does not exist is
/// bad input (exit 2), named, before anything is written.
#[test]
fn search_on_ray_without_its_interpreter_is_refused() {
    let t = TempDir::new("search-ray-no-python");
    dataset(&t.0);
    let space = space();
    let mut args = search_args(&space, "s", "2", "1");
    args.extend(["--executor", "ray", "--python", "/no/such/python3"]);
    let r = tactrace(&t.0, &args);
    expect_refusal(
        &r,
        2,
        "search --executor ray --python /no/such/python3",
        "cannot start the Python interpreter /no/such/python3",
    );
    assert!(!t.join("s").exists() && !t.join("s.partial").exists());
}

/// A space of one output learning rate, a range or choices (TOML body).
fn output_rate_space(dir: &Path, body: &str) -> String {
    let path = dir.join("rates.toml");
    std::fs::write(
        &path,
        format!("[[param]]\nname = \"output_learning_rate\"\n{body}"),
    )
    .unwrap();
    path.display().to_string()
}

#[test]
fn a_search_whose_every_trial_diverged_fails_without_a_best() {
    let t = TempDir::new("search-diverged");
    dataset(&t.0);
    let space = output_rate_space(&t.0, "low = 1e6\nhigh = 1e8\nlog = true\n");
    let r = tactrace(&t.0, &search_args(&space, "s", "3", "3"));
    expect_refusal(
        &r,
        1,
        "a search whose every trial diverged",
        "every one of the 3 search trials failed (3 diverged",
    );
    assert!(!r.stdout.contains("best:"), "{}", r.stdout);
    assert!(!t.join("s").exists());
    // What was tried is kept, and no best written from nothing.
    assert_eq!(trials(&t.join("s.partial")).len(), 3);
    assert!(!t.join("s.partial/best.toml").exists());
}

#[test]
fn a_search_records_its_failed_trials_in_the_table_and_figure() {
    let t = TempDir::new("search-some-failed");
    dataset(&t.0);
    let space = output_rate_space(&t.0, "choices = [5.0, 1e8]\n");
    let mut args = search_args(&space, "s", "6", "3");
    args.extend(["--seed", "2"]);
    let r = tactrace(&t.0, &args);
    expect_code(&r, 0, "a search with some diverged trials");
    let csv = std::fs::read_to_string(t.join("s/trials.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].ends_with(",status"), "{csv}");
    assert!(lines[0].contains(",mae_r_mm,mae_theta_deg,"), "{csv}");
    let status: Vec<&str> = lines[1..]
        .iter()
        .map(|l| l.rsplit(',').next().unwrap())
        .collect();
    let diverged = status.iter().filter(|s| **s == "diverged").count();
    assert!(
        diverged > 0 && status.contains(&"ok"),
        "both kinds of trial: {csv}"
    );
    assert!(
        r.stderr.contains(&format!(
            "{diverged} of 6 trials failed (status in trials.csv)"
        )),
        "{}",
        r.stderr
    );
    let svg = std::fs::read_to_string(t.join("s/convergence.svg")).unwrap();
    assert!(
        svg.contains(&format!("failed ({diverged}): no score")),
        "the figure marks the failed trials"
    );
    // best.toml is the best finished trial's: the small rate.
    let best = std::fs::read_to_string(t.join("s/best.toml")).unwrap();
    assert!(best.contains("output_learning_rate = 5.0"), "{best}");
}

/// A small network for the 16 px frames, the search's base.
const SMALL_CONV: &str = "dense = [16]\nbatch_size = 8\n\
                          [[conv]]\nchannels = 6\nkernel = 3\nstride = 2\n\
                          [[conv]]\nchannels = 8\nkernel = 3\nstride = 2\n";

#[test]
fn search_of_an_image_model_on_its_frames() {
    let t = TempDir::new("search-image");
    util::spot_frames_dataset(&t.join("frames"), "tests/it/search.rs", 80);
    std::fs::write(t.join("small.toml"), SMALL_CONV).unwrap();
    dataset(&t.0);
    for kind in ["conv-dennn", "conv-mlp"] {
        let space = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("configs/search/{kind}.toml"))
            .display()
            .to_string();
        let out = format!("s-{kind}");
        let mut args = search_args(&space, &out, "3", "2");
        args[2] = "frames";
        args.extend(["--model", kind, "--config", "small.toml"]);
        let r = tactrace(&t.0, &args);
        expect_code(&r, 0, kind);
        let csv = std::fs::read_to_string(t.join(&out).join("trials.csv")).unwrap();
        let header = csv.lines().next().unwrap();
        assert!(
            header.contains(",dense.0,") && header.contains(",mae_x_mm,mae_angle_deg,"),
            "{csv}"
        );
        assert_eq!(header.contains(",ep.beta,"), kind == "conv-dennn", "{csv}");
        assert_eq!(csv.lines().count(), 4, "{csv}");
        // best.toml is an image model's configuration train takes.
        let best = std::fs::read_to_string(t.join(&out).join("best.toml")).unwrap();
        assert!(best.contains(&format!("kind = \"{kind}\"")), "{best}");
        let train = [
            "train",
            "--model",
            kind,
            "--train",
            "frames",
            "--val-fraction",
            "0.25",
            "--config",
            &format!("{out}/best.toml"),
            "--out",
            &format!("m-{kind}"),
        ];
        expect_code(&tactrace(&t.0, &train), 0, "train --config best.toml");
    }
    // A dataset of pins only is refused before any trial.
    let space = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs/search/conv-dennn.toml")
        .display()
        .to_string();
    let mut args = search_args(&space, "pins", "3", "2");
    args.extend(["--model", "conv-dennn"]);
    let r = tactrace(&t.0, &args);
    expect_refusal(&r, 2, "an image search on pins", "pin displacements only");
    // A field the image model does not have is refused.
    std::fs::write(
        t.join("bad.toml"),
        "[[param]]\nname = \"hidden\"\nlow = 2\nhigh = 9\ninteger = true\n",
    )
    .unwrap();
    let mut args = search_args("bad.toml", "bad", "3", "2");
    args[2] = "frames";
    args.extend(["--model", "conv-dennn"]);
    let r = tactrace(&t.0, &args);
    expect_refusal(
        &r,
        2,
        "an image search of a field it lacks",
        "no such setting",
    );
}
