//! The 3D tasks through the real binary (issue 23 items 4-5): `collect
//! --task surface_3d`, `train`, `validate`, `follow --task surface_3d`,
//! the exit codes of bad objects, and the planar task unchanged by the
//! new flags.
use crate::util;
use util::{tactrace, Run, TempDir};

fn ok(r: &Run, what: &str) {
    assert_eq!(r.code, 0, "{what}: {}", r.stderr);
}

/// A small, fast model: a few epochs of small nets.
const SMALL: &str =
    "[position]\nn_components = 10\nhidden = [16]\n\n[angle]\nn_components = 10\nhidden = [16]\n";

#[test]
fn collect_train_validate_follow_surface_3d_end_to_end() {
    let t = TempDir::new("surface3d");
    let collect = |seed: &str, n: &str, out: &str| {
        tactrace(
            &t.0,
            &[
                "collect",
                "--task",
                "surface_3d",
                "--object",
                "plane",
                "--samples",
                n,
                "--seed",
                seed,
                "--out",
                out,
            ],
        )
    };
    ok(&collect("1", "150", "train"), "collect train");
    ok(&collect("2", "60", "val"), "collect val");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.join("train/meta.json")).unwrap()).unwrap();
    assert_eq!(meta["target_names"], serde_json::json!(["z", "rx", "ry"]));
    assert_eq!(
        meta["target_units"],
        serde_json::json!(["mm", "deg", "deg"])
    );
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let r = tactrace(
        &t.0,
        &[
            "train",
            "--train",
            "train",
            "--config",
            "small.toml",
            "--epochs",
            "3",
            "--out",
            "m",
        ],
    );
    ok(&r, "train");
    let r = tactrace(
        &t.0,
        &["validate", "--model", "m", "--data", "val", "--json"],
    );
    ok(&r, "validate");
    for name in ["\"z\"", "\"rx\"", "\"ry\""] {
        assert!(r.stdout.contains(name), "{name}: {}", r.stdout);
    }
    let r = tactrace(
        &t.0,
        &[
            "follow",
            "--task",
            "surface_3d",
            "--object",
            "ramp",
            "--model",
            "m",
            "--length",
            "5",
            "--out",
            "run",
        ],
    );
    // A 3-epoch model may lose the surface; the run is written either way.
    assert!(r.code == 0 || r.code == 1, "{}", r.stderr);
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.join("run/metrics.json")).unwrap())
            .unwrap();
    for key in [
        "mean_distance_mm",
        "max_distance_mm",
        "mean_normal_error_deg",
        "coverage",
        "closed",
    ] {
        assert!(m.get(key).is_some(), "{key}: {m}");
    }
    assert!(t.join("run/replay.html").is_file() && t.join("run/trajectory_3d.png").is_file());
    // An object that is neither built in nor a mesh file is bad input.
    let r = tactrace(
        &t.0,
        &[
            "follow",
            "--task",
            "surface_3d",
            "--object",
            "teapot",
            "--model",
            "m",
            "--out",
            "run2",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("teapot"), "{}", r.stderr);
    // The edge model cannot drive the surface task: its targets name no
    // surface component (bad input, before any step).
    ok(
        &tactrace(&t.0, &["collect", "--samples", "40", "--out", "edge"]),
        "collect edge",
    );
    ok(
        &tactrace(
            &t.0,
            &[
                "train",
                "--train",
                "edge",
                "--config",
                "small.toml",
                "--epochs",
                "1",
                "--out",
                "me",
            ],
        ),
        "train edge",
    );
    let r = tactrace(
        &t.0,
        &[
            "follow",
            "--task",
            "surface_3d",
            "--object",
            "plane",
            "--model",
            "me",
            "--out",
            "run3",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(!t.join("run3").exists());
}

/// `--task edge_2d` is the planar task as before: the same trajectory,
/// byte for byte, as a run without the flag.
#[test]
fn planar_task_flag_gives_the_identical_run() {
    let t = TempDir::new("planar");
    ok(
        &tactrace(&t.0, &["collect", "--samples", "60", "--out", "d"]),
        "collect",
    );
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    ok(
        &tactrace(
            &t.0,
            &[
                "train",
                "--train",
                "d",
                "--config",
                "small.toml",
                "--epochs",
                "1",
                "--out",
                "m",
            ],
        ),
        "train",
    );
    let follow = |extra: &[&str], out: &str| {
        let mut args = vec![
            "follow", "--shape", "disk", "--model", "m", "--steps", "12", "--out", out,
        ];
        args.extend_from_slice(extra);
        tactrace(&t.0, &args)
    };
    let a = follow(&[], "a");
    let b = follow(&["--task", "edge_2d"], "b");
    assert_eq!(a.code, b.code, "{} / {}", a.stderr, b.stderr);
    let read = |d: &str| std::fs::read(t.join(d).join("trajectory.csv")).unwrap();
    assert_eq!(read("a"), read("b"));
}

/// `collect --task edge_5d` with its range flags and `--at X,Y` (negative
/// numbers too); `follow --task edge_5d` refuses an object without an
/// edge and the surface task's path flags before anything runs (exit 2).
#[test]
fn edge_5d_collect_flags_and_follow_refusals() {
    let t = TempDir::new("edge5d");
    let r = tactrace(
        &t.0,
        &[
            "collect",
            "--task",
            "edge_5d",
            "--object",
            "foil",
            "--at",
            "-3,-40",
            "--x-range",
            "2",
            "--tilt-range",
            "10",
            "--rz-range",
            "30",
            "--samples",
            "40",
            "--out",
            "e",
        ],
    );
    ok(&r, "collect edge_5d");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.join("e/meta.json")).unwrap()).unwrap();
    assert_eq!(
        meta["target_names"],
        serde_json::json!(["x", "z", "rx", "ry", "rz"])
    );
    let targets = std::fs::read(t.join("e/targets.npy")).unwrap();
    assert!(targets.len() > 40 * 5 * 4);
    let bad_at = tactrace(
        &t.0,
        &[
            "collect", "--task", "edge_5d", "--object", "foil", "--at", "1,2,3", "--out", "x",
        ],
    );
    assert_eq!(bad_at.code, 2, "{}", bad_at.stderr);
    assert!(
        bad_at.stderr.contains("--at takes two numbers"),
        "{}",
        bad_at.stderr
    );
    let follow = |extra: &[&str], out: &str| {
        let mut args = vec!["follow", "--task", "edge_5d", "--model", "m", "--out", out];
        args.extend_from_slice(extra);
        tactrace(&t.0, &args)
    };
    let no_edge = follow(&["--object", "saddle"], "r1");
    assert_eq!(no_edge.code, 2, "{}", no_edge.stderr);
    assert!(no_edge.stderr.contains("no edge"), "{}", no_edge.stderr);
    let heading = follow(&["--object", "foil", "--heading", "10"], "r2");
    assert_eq!(heading.code, 2, "{}", heading.stderr);
    assert!(!t.join("r1").exists() && !t.join("r2").exists());
}
