//! `tactrace ensemble --member M1 --member M2 --out E`: pin models trained
//! apart on the same rows joined into one model folder whose prediction
//! is the members' mean; `predict` and `validate` take it as any model and
//! it keeps the members' record of their training rows. One member alone
//! predicts what it does; members of other rows or other nets, and an
//! --out that is a member, are refused as bad input. The real binary
//! through `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{expect_code, expect_refusal, tactrace, train, TempDir};

/// A small PCADenNN; `seed` picks its initialisation and shuffles.
fn small(seed: u64, hidden: usize) -> String {
    format!(
        "seed = {seed}\n[pose]\nn_components = 5\nhidden = [{hidden}]\nlearning_rate = 18.0\n\
         output_learning_rate = 2.5\n"
    )
}

/// `predict` of `model` on ds: each row's numbers.
fn predicted(dir: &Path, model: &str) -> Vec<Vec<f64>> {
    let r = tactrace(dir, &["predict", "--model", model, "--data", "ds"]);
    expect_code(&r, 0, "predict");
    let rows = r.stdout.lines().skip(1);
    let numbers = |l: &str| l.split(',').map(|v| v.parse().expect("number")).collect();
    rows.map(numbers).collect()
}

/// Two small models of seeds 0 and 5 on the dataset `ds` (40 taps).
fn two_seeds(t: &TempDir) {
    expect_code(&util::collect(&t.0, "40", &["--seed", "3"], "ds"), 0, "ds");
    for (seed, name) in [(0, "m0"), (5, "m5")] {
        let config = format!("{name}.toml");
        std::fs::write(t.join(&config), small(seed, 8)).unwrap();
        let r = train(&t.0, "pcadennn", "ds", "2", name, &["--config", &config]);
        expect_code(&r, 0, name);
    }
}

#[test]
fn two_seeds_joined_predict_their_mean_and_one_predicts_itself() {
    let t = TempDir::new("ensemble-cmd");
    two_seeds(&t);
    let args = ["ensemble", "--member", "m0", "--member", "m5", "--out", "e"];
    expect_code(&tactrace(&t.0, &args), 0, "ensemble");
    let (a, b, e) = (
        predicted(&t.0, "m0"),
        predicted(&t.0, "m5"),
        predicted(&t.0, "e"),
    );
    assert_ne!(a, b);
    for ((p, q), m) in a.iter().zip(&b).zip(&e) {
        // r and theta (the edge task's, not circular): the mean, to the
        // printed digits; the truth columns unchanged.
        for c in 0..2 {
            assert!(
                (m[c] - (p[c] + q[c]) / 2.0).abs() < 2e-4,
                "{m:?} {p:?} {q:?}"
            );
        }
        assert_eq!(m[2..], p[2..]);
    }
    let members = std::fs::read_to_string(t.join("e").join("members.toml")).unwrap();
    assert!(members.contains("model = \"m0\"") && members.contains("seed = 5"));
    // Its record of the training rows is the members': all 40 seen.
    let r = tactrace(
        &t.0,
        &["validate", "--model", "e", "--data", "ds", "--json"],
    );
    expect_code(&r, 0, "validate");
    assert_eq!(util::json(&r.stdout)["rows_seen_in_training"], 40);
    let one = ["ensemble", "--member", "m5", "--out", "e5"];
    expect_code(&tactrace(&t.0, &one), 0, "one member");
    assert_eq!(predicted(&t.0, "e5"), b);
}

#[test]
fn members_of_other_rows_or_nets_and_out_a_member_are_refused() {
    let t = TempDir::new("ensemble-refused");
    two_seeds(&t);
    expect_code(
        &util::collect(&t.0, "40", &["--seed", "4"], "ds2"),
        0,
        "ds2",
    );
    std::fs::write(t.join("wide.toml"), small(0, 9)).unwrap();
    let r = train(
        &t.0,
        "pcadennn",
        "ds",
        "2",
        "wide",
        &["--config", "wide.toml"],
    );
    expect_code(&r, 0, "wide");
    let r = train(
        &t.0,
        "pcadennn",
        "ds2",
        "2",
        "other",
        &["--config", "m0.toml"],
    );
    expect_code(&r, 0, "other");
    let join = |b: &str, out: &str| {
        let args = [
            "ensemble", "--member", "m0", "--member", b, "--out", out, "--force",
        ];
        tactrace(&t.0, &args)
    };
    expect_refusal(&join("other", "x"), 2, "other rows", "other rows");
    expect_refusal(&join("wide", "y"), 2, "other nets", "pose.hidden");
    expect_refusal(&join("m5", "m5"), 2, "--out a member", "--member");
    for out in ["x", "y"] {
        assert!(!t.join(out).exists(), "{out}");
    }
    predicted(&t.0, "m5");
}

/// A joined model follows as any model: two PDenNNs of other seeds on
/// 400 simulated taps, joined, close the disk in the simulated world (the
/// controller sees the joined model's predictions, never the true pose).
#[test]
fn follow_with_a_joined_model_closes_the_disk() {
    let t = TempDir::new("ensemble-follow");
    expect_code(
        &util::collect(&t.0, "400", &["--seed", "11"], "ds"),
        0,
        "ds",
    );
    for seed in [1, 2] {
        let (config, out) = (format!("s{seed}.toml"), format!("p{seed}"));
        std::fs::write(t.join(&config), format!("seed = {seed}\n")).unwrap();
        let r = train(&t.0, "pdennn", "ds", "60", &out, &["--config", &config]);
        expect_code(&r, 0, &out);
    }
    let args = ["ensemble", "--member", "p1", "--member", "p2", "--out", "e"];
    expect_code(&tactrace(&t.0, &args), 0, "ensemble");
    let args = ["follow", "--model", "e", "--shape", "disk", "--out", "run"];
    let r = tactrace(&t.0, &args);
    expect_code(&r, 0, "follow with the joined model");
    assert!(r.stdout.contains("closed"), "{}", r.stdout);
    let metrics = std::fs::read_to_string(t.join("run").join("metrics.json")).unwrap();
    assert!(metrics.contains("\"closed\": true"), "{metrics}");
}
