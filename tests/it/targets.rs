//! Named targets end to end (issue 21, item 4): `import --target` of three
//! targets (one circular), `train` and `validate --json` with
//! `per_target`, `import --like` for another split, and a model folder of
//! the edge task written before targets were named (model format 2).
use crate::util;
use std::path::Path;
use util::{json, ok, real_data, tactrace, Run, TempDir};

/// The header and the first `n` rows of the real set's labels whose frame
/// number N has `N % 5` in `parts`, into `out`.
fn part_csv(data: &Path, out: &Path, parts: &[u64], n: usize) {
    let text = std::fs::read_to_string(data.join("targets.csv")).unwrap();
    let mut lines = text.lines();
    let mut rows = vec![lines.next().unwrap().to_string()];
    rows.extend(
        lines
            .filter(|l| {
                let name = l.split(',').next().unwrap_or_default();
                tactrace_store::collection::frame_number(name)
                    .is_some_and(|k| parts.contains(&(k % 5)))
            })
            .take(n)
            .map(str::to_string),
    );
    std::fs::write(out, rows.join("\n") + "\n").unwrap();
}

/// A small, fast model: 3 epochs of small nets.
const SMALL: &str = "[position]\nn_components = 10\nhidden = [32]\nlearning_rate = 18.0\n\
    output_learning_rate = 5.0\nbeta = 1.0\n\n[angle]\nn_components = 10\nhidden = [32]\n\
    learning_rate = 18.0\noutput_learning_rate = 5.0\nbeta = 1.0\n";

#[test]
fn three_targets_import_train_validate_and_import_like() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("targets3");
    part_csv(&data, &t.join("fit.csv"), &[2, 3, 4], 60);
    part_csv(&data, &t.join("score.csv"), &[0], 30);
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let s = |p: &Path| p.display().to_string();
    let init = s(&data.join("frames/init_0.png"));
    let r = import_fit(
        &t,
        &data,
        &[
            "--target",
            "pose_2:mm",
            "--target",
            "pose_6:deg:circular",
            "--target",
            "pose_3:mm",
        ],
    );
    ok(&r, "import --target");
    let meta = json(&std::fs::read_to_string(t.join("fit/meta.json")).unwrap());
    assert_eq!(
        meta["target_names"],
        json(r#"["pose_2", "pose_6", "pose_3"]"#)
    );
    assert_eq!(meta["target_units"], json(r#"["mm", "deg", "mm"]"#));
    assert_eq!(meta["target_circular"], json("[false, true, false]"));
    // No role marked: no roles written.
    assert!(meta.get("target_roles").is_none(), "{meta}");
    let fit = tactrace_store::read_dataset(&t.join("fit")).unwrap();
    assert_eq!(fit.n_targets(), 3);
    assert_eq!(fit.len(), 60);

    // Another split with the same reference, detector and targets.
    let r = import_labels(&t, &data, "score.csv", &["--like", "fit"], "score");
    ok(&r, "import --like");
    let score = tactrace_store::read_dataset(&t.join("score")).unwrap();
    assert_eq!(score.meta.target_columns, fit.meta.target_columns);
    assert_eq!(score.meta.reference_pins, fit.meta.reference_pins);
    assert_eq!(
        score.meta.settings["import"]["spec"],
        fit.meta.settings["import"]["spec"]
    );
    assert_eq!(
        score.meta.settings["import"]["blob"],
        fit.meta.settings["import"]["blob"]
    );
    assert_eq!(score.len(), 30);
    // --like takes the reference and targets from the dataset: not both.
    let r = import_labels(
        &t,
        &data,
        "score.csv",
        &["--like", "fit", "--target", "pose_2:mm"],
        "x",
    );
    assert_eq!(r.code, 2, "{}", r.stderr);

    for kind in ["pdennn", "mlp"] {
        let out = format!("m-{kind}");
        ok(&train_small(&t, kind, &out), "train");
        let r = tactrace(
            &t.0,
            &["validate", "--model", &out, "--data", "score", "--json"],
        );
        ok(&r, "validate --json");
        let v = json(&r.stdout);
        let per = &v["per_target"];
        for (name, unit, circular) in [
            ("pose_2", "mm", false),
            ("pose_6", "deg", true),
            ("pose_3", "mm", false),
        ] {
            assert_eq!(per[name]["unit"], unit, "{v}");
            assert_eq!(per[name]["circular"], circular, "{v}");
            let mae = per[name]["mae"].as_f64().unwrap();
            assert!(mae.is_finite() && mae >= 0.0, "{v}");
        }
        // A wrapped angle error is at most 180 deg.
        assert!(per["pose_6"]["mae"].as_f64().unwrap() <= 180.0);
        // Today's keys stay: the mm targets' mean, the deg target's.
        let mm =
            (per["pose_2"]["mae"].as_f64().unwrap() + per["pose_3"]["mae"].as_f64().unwrap()) / 2.0;
        assert!(
            (v["position_mae_mm"].as_f64().unwrap() - mm).abs() < 1e-9,
            "{v}"
        );
        assert_eq!(v["angle_mae_deg"], per["pose_6"]["mae"]);
        assert_eq!(v["samples"], 30);
        // The printed report names every target; the figure has a panel each.
        let plots = format!("plots-{kind}");
        let r = tactrace(
            &t.0,
            &[
                "validate", "--model", &out, "--data", "score", "--plots", &plots,
            ],
        );
        ok(&r, "validate --plots");
        let svg = std::fs::read_to_string(t.join(&plots).join("predicted_vs_true.svg")).unwrap();
        for name in ["true pose_2 (mm)", "true pose_6 (deg)", "true pose_3 (mm)"] {
            assert!(svg.contains(name), "{name} not in the figure");
        }
        for name in ["pose_2: ", "pose_6: ", "pose_3: ", "(circular, wrapped)"] {
            assert!(r.stdout.contains(name), "{}", r.stdout);
        }
        // predict --data: every target, predicted then true.
        let r = tactrace(&t.0, &["predict", "--model", &out, "--data", "score"]);
        ok(&r, "predict --data");
        assert!(r.stdout.starts_with(
            "pose_2_mm,pose_6_deg,pose_3_mm,true_pose_2_mm,true_pose_6_deg,true_pose_3_mm\n"
        ));
    }
    // The servo loop takes an edge pose: a model of other targets is refused.
    let r = tactrace(
        &t.0,
        &[
            "follow",
            "--model",
            "m-pdennn",
            "--shape",
            "disk",
            "--replay",
            &s(&data),
            "--steps",
            "3",
            "--out",
            "run",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("not an edge pose"), "{}", r.stderr);
    assert!(!t.join("run").exists());
    // A model of other targets is scored on a dataset of the same targets only.
    let r = import_labels(&t, &data, "score.csv", &["--reference", &init], "edge");
    ok(&r, "import (edge)");
    let r = tactrace(&t.0, &["validate", "--model", "m-pdennn", "--data", "edge"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("pose_3 (mm)"), "{}", r.stderr);
}

/// Roles marked at import (`:position`, `:angle`) let a model that also
/// learns the tap's depth serve the servo loop, which reads the edge pose
/// from the marked targets; a role on a target of the wrong unit is
/// refused at import.
#[test]
fn marked_roles_let_a_model_of_three_targets_follow() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("roles3");
    part_csv(&data, &t.join("fit.csv"), &[2, 3, 4], 60);
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let r = import_fit(&t, &data, &["--target", "pose_3:deg:position"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("position but is in deg"), "{}", r.stderr);
    assert!(!t.join("fit").exists());
    let targets = [
        "--target",
        "pose_2:mm:position",
        "--target",
        "pose_3:mm",
        "--target",
        "pose_6:deg:circular:angle",
    ];
    ok(
        &import_fit(&t, &data, &targets),
        "import --target with roles",
    );
    let meta = json(&std::fs::read_to_string(t.join("fit/meta.json")).unwrap());
    assert_eq!(meta["target_roles"], json(r#"["position", null, "angle"]"#));
    ok(&train_small(&t, "pdennn", "m"), "train");
    let model = json(&std::fs::read_to_string(t.join("m/model.json")).unwrap());
    let roles: Vec<_> = model["outputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["role"].clone())
        .collect();
    assert_eq!(
        roles,
        [json(r#""position""#), json("null"), json(r#""angle""#)]
    );
    let replay = data.display().to_string();
    let r = tactrace(
        &t.0,
        &[
            "follow", "--model", "m", "--shape", "disk", "--replay", &replay, "--steps", "3",
            "--out", "run",
        ],
    );
    ok(&r, "follow with a model of three targets, two marked");
    assert!(t.join("run").is_dir());
}

#[test]
fn an_edge_model_folder_of_format_2_loads_and_scores_the_same() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("format2");
    part_csv(&data, &t.join("fit.csv"), &[2, 3, 4], 50);
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let r = import_fit(&t, &data, &[]);
    ok(&r, "import");
    let r = tactrace(
        &t.0,
        &[
            "train",
            "--train",
            "fit",
            "--config",
            "small.toml",
            "--epochs",
            "2",
            "--out",
            "m",
        ],
    );
    ok(&r, "train");
    let validate = || {
        let r = tactrace(
            &t.0,
            &["validate", "--model", "m", "--data", "fit", "--json"],
        );
        ok(&r, "validate");
        json(&r.stdout)
    };
    let now = validate();
    assert!(now["per_target"]["pose_2"]["mae"].is_number(), "{now}");
    // The model as format 2 wrote it: no targets named.
    let path = t.join("m/model.json");
    let mut model = json(&std::fs::read_to_string(&path).unwrap());
    let obj = model.as_object_mut().unwrap();
    assert_eq!(obj["version"], 3);
    assert!(obj.remove("outputs").is_some());
    obj.insert("version".into(), 2.into());
    std::fs::write(&path, serde_json::to_string_pretty(&model).unwrap()).unwrap();
    let old = validate();
    assert_eq!(old["position_mae_mm"], now["position_mae_mm"]);
    assert_eq!(old["angle_mae_deg"], now["angle_mae_deg"]);
    assert_eq!(old["per_target"], now["per_target"]);
}

/// `import` of `fit.csv` in `t` (frames and reference frame of the real
/// set `data`) into `fit`, with `extra` arguments.
fn import_fit(t: &TempDir, data: &Path, extra: &[&str]) -> Run {
    let init = data.join("frames/init_0.png").display().to_string();
    let extra = [&["--reference", &init], extra].concat();
    import_labels(t, data, "fit.csv", &extra, "fit")
}

/// `train` of a `kind` model on the dataset `fit` in `t` for 3 epochs of
/// the small nets (`small.toml`), into `out`.
fn train_small(t: &TempDir, kind: &str, out: &str) -> Run {
    let args = [
        "train",
        "--train",
        "fit",
        "--model",
        kind,
        "--config",
        "small.toml",
    ];
    tactrace(
        &t.0,
        &[&args[..], &["--epochs", "3", "--out", out]].concat(),
    )
}

/// `import` of the real set's frames labelled in `labels` (a CSV in `t`)
/// into `out`, with `extra` arguments (a reference, targets or `--like`).
fn import_labels(t: &TempDir, data: &Path, labels: &str, extra: &[&str], out: &str) -> Run {
    let frames = data.join("frames").display().to_string();
    let mut args = vec!["import", "--frames", &frames, "--targets", labels];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(&t.0, &args)
}

/// `train --search` on a three-target set (one circular) scores every
/// target: `search.csv` has an error column a target and the score is the
/// sum of the three errors over their goals (`goals` in the search file).
#[test]
fn train_search_scores_every_target() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("search3");
    part_csv(&data, &t.join("fit.csv"), &[2, 3, 4], 80);
    let targets = [
        "--target",
        "pose_2:mm",
        "--target",
        "pose_6:deg:circular",
        "--target",
        "pose_3:mm",
    ];
    ok(&import_fit(&t, &data, &targets), "import --target");
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    std::fs::write(
        t.join("grid.toml"),
        "learning_rates = [18.0]\noutput_learning_rates = [1.0, 5.0]\nbetas = [1.0]\n\
         hidden = [16]\nn_components = [8]\ntrials = 2\ngoals = [0.25, 3.0, 0.1]\n",
    )
    .unwrap();
    let args = [
        "train",
        "--train",
        "fit",
        "--model",
        "pdennn",
        "--config",
        "small.toml",
        "--epochs",
        "3",
        "--search",
        "--search-space",
        "grid.toml",
        "--out",
        "m",
    ];
    let r = tactrace(&t.0, &args);
    ok(&r, "train --search");
    assert!(r.stderr.contains("pose_3"), "{}", r.stderr);
    let csv = std::fs::read_to_string(t.join("m/search.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let tail = &header[header.len() - 4..];
    assert_eq!(
        tail,
        ["mae_pose_2_mm", "mae_pose_6_deg", "mae_pose_3_mm", "score"]
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .rev()
                .take(4)
                .map(|v| v.parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 2);
    for row in &rows {
        let (score, pose_3, pose_6, pose_2) = (row[0], row[1], row[2], row[3]);
        assert!(pose_6 <= 180.0, "{row:?}");
        let expected = pose_2 / 0.25 + pose_6 / 3.0 + pose_3 / 0.1;
        assert!(
            (score - expected).abs() < 1e-9 * expected.max(1.0),
            "{row:?}"
        );
    }
    assert!(rows[0][0] <= rows[1][0], "best first: {rows:?}");
    // A goal list that does not give one goal a target is refused.
    std::fs::write(t.join("bad.toml"), "goals = [0.25, 3.0]\ntrials = 1\n").unwrap();
    let mut bad = args.to_vec();
    bad[11] = "bad.toml";
    bad[13] = "m2";
    let r = tactrace(&t.0, &bad);
    assert_eq!(r.code, 2, "{}", r.stderr);
}
