//! `train --ensemble K` end to end: the ensemble's folder is read by
//! validate, predict and follow through the one model loader; one member
//! is the single model's folder; out-of-range sizes are bad input.
use crate::util;
use util::{expect_code, expect_refusal, tactrace, Run, TempDir};

fn train(dir: &std::path::Path, out: &str, extra: &[&str]) -> Run {
    let mut args = vec![
        "train", "--model", "pdennn", "--train", "ds", "--epochs", "2", "--out", out,
    ];
    args.extend(extra);
    tactrace(dir, &args)
}

#[test]
fn train_ensemble_saves_a_folder_every_command_loads() {
    let t = TempDir::new("ensemble");
    let dir = &t.0;
    let r = tactrace(
        dir,
        &["collect", "--samples", "60", "--seed", "3", "--out", "ds"],
    );
    expect_code(&r, 0, "collect");
    expect_code(
        &train(dir, "m3", &["--ensemble", "3"]),
        0,
        "train --ensemble 3",
    );
    let json = std::fs::read_to_string(t.join("m3/model.json")).unwrap();
    assert!(json.contains("\"ensemble\": 3"), "{json}");
    let r = tactrace(
        dir,
        &["validate", "--model", "m3", "--data", "ds", "--json"],
    );
    expect_code(&r, 0, "validate");
    let v: serde_json::Value = serde_json::from_str(&r.stdout).expect("json");
    assert!(
        v["position_mae_mm"].as_f64().is_some_and(f64::is_finite),
        "{v}"
    );
    let r = tactrace(dir, &["predict", "--model", "m3", "--data", "ds"]);
    expect_code(&r, 0, "predict");
    // follow loads it (an untrained model may lose contact: 0 or 1).
    let r = tactrace(
        dir,
        &[
            "follow", "--model", "m3", "--shape", "disk", "--steps", "3", "--out", "run",
        ],
    );
    assert!(
        r.code == 0 || r.code == 1,
        "follow: {}\n{}",
        r.code,
        r.stderr
    );

    // One member: the single model's files, byte for byte.
    expect_code(&train(dir, "m", &[]), 0, "train");
    expect_code(
        &train(dir, "m1", &["--ensemble", "1"]),
        0,
        "train --ensemble 1",
    );
    for f in ["model.json", "weights.safetensors"] {
        let a = std::fs::read(t.join("m").join(f)).unwrap();
        assert_eq!(a, std::fs::read(t.join("m1").join(f)).unwrap(), "{f}");
    }

    // Sizes out of range are bad input.
    for k in ["0", "65"] {
        let r = train(dir, "bad", &["--ensemble", k]);
        expect_refusal(&r, 2, "train --ensemble out of range", "ensemble");
    }
    // An image model takes --ensemble as its number of networks.
    let conv = |k: &str, extra: &[&str]| {
        let mut args = vec![
            "train",
            "--model",
            "conv-dennn",
            "--train",
            "ds",
            "--ensemble",
            k,
            "--out",
            "c",
        ];
        args.extend_from_slice(extra);
        tactrace(dir, &args)
    };
    let r = conv("3", &["--print-config"]);
    expect_code(&r, 0, "train conv-dennn --ensemble 3 --print-config");
    assert!(r.stdout.contains("members = 3"), "{}", r.stdout);
    let r = conv("33", &[]);
    expect_refusal(&r, 2, "train conv-dennn --ensemble 33", "members");
}
