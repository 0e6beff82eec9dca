//! An image model of several networks through the command line (issue
//! 22, accuracy): `train --model conv-mlp --config` with `members = 2`
//! writes one model folder holding both networks, each the one-network
//! model of its seed, and `validate` and `follow` use it like any image
//! model. They run the real binary through `tests/it/util.rs`.
use crate::util;
use tactrace_store::StoredImageModel;
use util::{tactrace, Run, TempDir};

fn ok(r: &Run, what: &str) {
    assert_eq!(
        r.code, 0,
        "{what}: exit code {}\nstdout: {}\nstderr: {}",
        r.code, r.stdout, r.stderr
    );
}

/// A small network for 32 px frames, with `members` networks.
fn config(members: usize) -> String {
    format!(
        "members = {members}\ndense = [16]\nbatch_size = 8\nlearning_rate = 0.003\n\
         [[conv]]\nchannels = 4\nkernel = 3\nstride = 2\n\
         [[conv]]\nchannels = 8\nkernel = 3\nstride = 2\n"
    )
}

#[test]
fn an_ensemble_trains_validates_and_follows_from_the_cli() {
    let t = TempDir::new("conv4-ensemble");
    let d = t.0.as_path();
    let r = tactrace(
        d,
        &[
            "collect",
            "--shape",
            "disk",
            "--samples",
            "120",
            "--seed",
            "3",
            "--frames-size",
            "32",
            "--out",
            "ds",
        ],
    );
    ok(&r, "collect");
    std::fs::write(d.join("two.toml"), config(2)).unwrap();
    std::fs::write(d.join("one.toml"), config(1)).unwrap();
    let train = |cfg: &str, seed: &str, out: &str| {
        let args = [
            "train", "--model", "conv-mlp", "--train", "ds", "--config", cfg, "--epochs", "2",
            "--seed", seed, "--out", out,
        ];
        ok(&tactrace(d, &args), out);
        StoredImageModel::load(&d.join(out)).unwrap()
    };
    let two = train("two.toml", "4", "two");
    let first = train("one.toml", "4", "first");
    let second = train("one.toml", "5", "second");
    let nets = two.model().network().networks();
    assert_eq!(nets.len(), 2);
    assert_eq!(&nets[0], first.model().network().network());
    assert_eq!(&nets[1], second.model().network().network());
    assert_ne!(nets[0], nets[1]);
    let json = std::fs::read_to_string(d.join("two").join("model.json")).unwrap();
    assert!(json.contains("\"members\": 2"), "{json}");

    let r = tactrace(d, &["validate", "--model", "two", "--data", "ds", "--json"]);
    ok(&r, "validate");
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert!(v["position_mae_mm"].as_f64().unwrap().is_finite(), "{v}");
    let r = tactrace(
        d,
        &[
            "follow", "--model", "two", "--shape", "disk", "--steps", "6", "--seed", "1", "--out",
            "run",
        ],
    );
    ok(&r, "follow");
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("run/metrics.json")).unwrap())
            .unwrap();
    assert_eq!(m["steps"], 6, "{m}");
}
