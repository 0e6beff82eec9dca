//! `tactrace tune` end to end on a tiny budget: its outputs, a tuned
//! configuration accepted back by `follow`, bad input refused, and an
//! interrupted tuning keeping its best so far (issue 12).
use crate::util;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use util::{tactrace, TempDir};

/// A dataset and a 2-epoch model in `t`, and a base follow configuration
/// whose runs stop after 25 taps (enough to exercise the plumbing).
fn set_up(t: &TempDir) {
    let ok = |args: &[&str]| {
        let r = tactrace(&t.0, args);
        assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
    };
    ok(&["collect", "--samples", "40", "--seed", "3", "--out", "ds"]);
    ok(&[
        "train", "--model", "pdennn", "--train", "ds", "--epochs", "2", "--out", "m",
    ]);
    std::fs::write(t.join("base.toml"), "[follow]\nmax_steps = 25\n").unwrap();
    std::fs::write(
        t.join("tiny.toml"),
        "population = 2\nheld_out_seeds = 1\n[objective]\nfailed = 1.0\n",
    )
    .unwrap();
}

fn tune_args<'a>(out: &'a str, trials: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "tune",
        "--model",
        "m",
        "--base",
        "base.toml",
        "--config",
        "tiny.toml",
        "--shapes",
        "square:50",
        "--held-out",
        "star:36,4,6",
        "--trials",
        trials,
        "--seed",
        "5",
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    args
}

#[test]
fn a_tiny_tuning_writes_a_config_that_follow_accepts() {
    let t = TempDir::new("tune");
    set_up(&t);
    let r = tactrace(&t.0, &tune_args("tuned", "4", &[]));
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stdout.contains("star-36-4-6") && r.stdout.contains("seed 5"),
        "{}",
        r.stdout
    );
    for f in [
        "tuned.toml",
        "history.csv",
        "convergence.svg",
        "convergence.png",
        "held_out.md",
        "held_out.json",
        "config.toml",
        "base.toml",
    ] {
        assert!(t.join("tuned").join(f).exists(), "missing {f}");
    }
    // The start point + 2 generations of 2, one run each on the one
    // training contour.
    let history = std::fs::read_to_string(t.join("tuned/history.csv")).unwrap();
    assert_eq!(history.lines().count(), 4, "{history}");
    assert!(
        history.lines().last().unwrap().starts_with("2,5,"),
        "{history}"
    );
    let config = std::fs::read_to_string(t.join("tuned/config.toml")).unwrap();
    assert!(config.contains("seed = 5"), "{config}");
    let r = follow(
        &t,
        "square:50",
        &[
            "--config",
            "tuned/tuned.toml",
            "--steps",
            "3",
            "--out",
            "run",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    // An existing output is kept without --force.
    let r = tactrace(&t.0, &tune_args("tuned", "2", &[]));
    assert_eq!(r.code, 2, "{}", r.stderr);
    // Unknown keys in a tuned configuration are refused by name.
    let text = std::fs::read_to_string(t.join("tuned/tuned.toml")).unwrap();
    let bad = text.replace(
        "[controller.policy]\n",
        "[controller.policy]\nstep_boost = 2.0\n",
    );
    std::fs::write(t.join("bad.toml"), bad).unwrap();
    let r = follow(&t, "square:50", &["--config", "bad.toml", "--out", "run2"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("step_boost"), "{}", r.stderr);
    // A policy value that cannot work is refused before anything is written.
    std::fs::write(
        t.join("zero.toml"),
        "[controller.policy]\nmin_step_fraction = 0.0\n",
    )
    .unwrap();
    let r = follow(&t, "square:50", &["--config", "zero.toml", "--out", "run4"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("min_step_fraction"), "{}", r.stderr);
    assert!(!t.join("run4").exists() && !t.join("run4.partial").exists());
    // A held-out contour that is also a training one is refused.
    let mut args = tune_args("t2", "2", &[]);
    let i = args.iter().position(|a| *a == "star:36,4,6").unwrap();
    args[i] = "square:50";
    let r = tactrace(&t.0, &args);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("both a training and a held-out"),
        "{}",
        r.stderr
    );
    // A malformed parametric shape says what is wrong.
    let r = follow(&t, "star:35,7", &["--out", "run3"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("star:R,A,K"), "{}", r.stderr);
}

/// `tactrace follow --model m --shape SHAPE` with `extra` arguments, in `t`.
fn follow(t: &TempDir, shape: &str, extra: &[&str]) -> util::Run {
    let args = [&["follow", "--model", "m", "--shape", shape][..], extra].concat();
    tactrace(&t.0, &args)
}

#[test]
fn an_interrupted_tuning_keeps_its_best_so_far() {
    let t = TempDir::new("tunekill");
    set_up(&t);
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(tune_args("out", "400", &[]))
        .current_dir(&t.0)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("binary starts");
    let history = t.join("out.partial/history.csv");
    let started = Instant::now();
    let generations = || {
        std::fs::read_to_string(&history)
            .map(|h| h.lines().count().saturating_sub(1))
            .unwrap_or(0)
    };
    while generations() < 3 {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no generation written in 120 s"
        );
        assert!(child.try_wait().unwrap().is_none(), "tune ended early");
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    child.wait().unwrap();
    assert!(
        !t.join("out").exists(),
        "an interrupted tuning is not complete"
    );
    let kept = std::fs::read_to_string(t.join("out.partial/tuned.toml")).unwrap();
    // The best so far is refused to be replaced without --force...
    let r = tactrace(&t.0, &tune_args("out", "2", &[]));
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("interrupted tuning"), "{}", r.stderr);
    assert_eq!(
        std::fs::read_to_string(t.join("out.partial/tuned.toml")).unwrap(),
        kept
    );
    // ...is a follow configuration, and the start of a new search.
    let r = follow(
        &t,
        "square:50",
        &[
            "--config",
            "out.partial/tuned.toml",
            "--steps",
            "3",
            "--out",
            "run",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let mut args = tune_args("again", "2", &[]);
    let i = args.iter().position(|a| *a == "base.toml").unwrap();
    args[i] = "out.partial/tuned.toml";
    let r = tactrace(&t.0, &args);
    assert_eq!(r.code, 0, "{}", r.stderr);
}
