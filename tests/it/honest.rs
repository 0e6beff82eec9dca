//! Issue 20, "honest with the user": useless results are not called
//! success, one kind of bad input has one exit code, and the messages say
//! what to do. Each test names the item it pins down; they run the real
//! binary through `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{
    collect, expect_code, expect_refusal, expect_refusal_saying, import_labelled, real_data,
    real_paths, stderr_says, tactrace, twin, TempDir,
};

/// A temporary folder `name` holding a dataset `ds` of 40 simulated taps
/// and a model `m` trained on it (2 epochs).
fn with_model(name: &str) -> TempDir {
    let t = TempDir::new(name);
    util::dataset_and_model(&t.0, "40", &[], &[]);
    t
}

/// The Bristol labels header (16 columns) and `rows` rows of labels.
fn bristol_targets(path: &Path, extra_column: Option<&str>, rows: usize) {
    let mut header = String::from(
        "image_name,data_name,obj_id,pose_id,pose_1,pose_2,pose_3,pose_4,pose_5,pose_6,\
         move_1,move_2,move_3,move_4,move_5,move_6",
    );
    if let Some(c) = extra_column {
        header.push(',');
        header.push_str(c);
    }
    let mut text = header + "\n";
    for k in 0..rows {
        text.push_str(&format!(
            "frame_{k}_0.png,frame_{k},1,{k},0,{},-0.5,0,0,{},0,0,0,0,0,0",
            (k % 7) as f64 - 3.0,
            (k % 11) as f64 * 5.0 - 25.0
        ));
        if extra_column.is_some() {
            text.push_str(",0");
        }
        text.push('\n');
    }
    std::fs::write(path, text).unwrap();
}

/// Item "useless results": `collect --samples 1` then `train` exited 0.
#[test]
fn training_refuses_too_few_samples_before_any_work() {
    let t = TempDir::new("fewsamples");
    let r = collect(&t.0, "1", &[], "one");
    expect_code(&r, 0, "collect");
    let r = tactrace(&t.0, &["train", "--train", "one", "--out", "m"]);
    expect_refusal(
        &r,
        2,
        "train on 1 sample",
        "too few training samples (1): at least 36",
    );
    stderr_says(&r, &["n_components = 35"]);
    assert!(!t.join("m").exists());
    // 40 taps are enough, but not once a fifth is held out.
    let r = collect(&t.0, "40", &[], "ds");
    expect_code(&r, 0, "collect 40");
    let r = tactrace(
        &t.0,
        &[
            "train",
            "--train",
            "ds",
            "--val-fraction",
            "0.2",
            "--epochs",
            "1",
            "--out",
            "m",
        ],
    );
    let says = ["(32)", "8 more were held out"];
    expect_refusal_saying(&r, 2, "train on 32 of 40", &says);
    assert!(!t.join("m").exists());
}

/// `anneal_fraction = nan` trained, exited 0 and saved a model that did not
/// load; the `n_components` error named `hidden`.
#[test]
fn a_setting_out_of_range_is_refused_naming_its_key() {
    let t = TempDir::new("badsetting");
    let cases = [
        ("anneal_fraction = nan\n", "anneal_fraction"),
        ("anneal_fraction = 2.0\n", "anneal_fraction"),
        (
            "[position]\nn_components = 100000\n",
            "[position] n_components",
        ),
        ("[angle]\nlearning_rate = inf\n", "[angle] learning_rate"),
    ];
    for (text, key) in cases {
        std::fs::write(t.join("cfg.toml"), text).unwrap();
        // Refused when the configuration is resolved: no dataset is read.
        for extra in [&["--print-config"][..], &[]] {
            let mut args = vec!["train", "--train", "missing", "--config", "cfg.toml"];
            args.extend(extra);
            args.extend(["--out", "m"]);
            let r = tactrace(&t.0, &args);
            expect_refusal(&r, 2, text, key);
            assert!(!r.stderr.contains("missing"), "{text}: {}", r.stderr);
        }
    }
    assert!(!t.join("m").exists());
}

/// `[position] hidden = []` reached a loss of 7e56 and was saved (only a
/// NaN or infinite loss counted as diverged).
#[test]
fn a_loss_growing_far_beyond_the_means_is_a_divergence() {
    let t = TempDir::new("growingloss");
    let r = collect(&t.0, "40", &[], "ds");
    expect_code(&r, 0, "collect");
    std::fs::write(
        t.join("cfg.toml"),
        "divergence_retries = 0\n[position]\nhidden = []\nlearning_rate = 2.0\n\
         [angle]\nhidden = []\nlearning_rate = 2.0\n",
    )
    .unwrap();
    let r = tactrace(
        &t.0,
        &[
            "train", "--model", "mlp", "--train", "ds", "--epochs", "3", "--config", "cfg.toml",
            "--out", "m",
        ],
    );
    expect_code(&r, 1, "diverged");
    stderr_says(&r, &["training diverged", "exceeds"]);
    assert!(!r.stderr.contains("NaN"), "a finite loss: {}", r.stderr);
    assert!(!t.join("m").exists());
}

/// `validate` printed NaN MAEs with exit 0 on a degenerate model/dataset.
#[test]
fn validate_never_reports_a_nan_error_as_success() {
    let t = with_model("nanmae");
    // A dataset whose first row is finite but far beyond any float the
    // network can carry: its prediction is not a number.
    let bad = t.join("bad");
    std::fs::create_dir_all(&bad).unwrap();
    for f in ["meta.json", "targets.npy", "inputs.npy"] {
        std::fs::copy(t.join("ds").join(f), bad.join(f)).unwrap();
    }
    let npy = bad.join("inputs.npy");
    let mut bytes = std::fs::read(&npy).unwrap();
    let header = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    for k in 0..254 {
        let v: f32 = if k % 2 == 0 { 3.0e38 } else { -3.0e38 };
        let at = 10 + header + 4 * k;
        bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
    }
    std::fs::write(&npy, bytes).unwrap();
    for json in [false, true] {
        let mut args = vec!["validate", "--model", "m", "--data", "bad"];
        if json {
            args.push("--json");
        }
        let r = tactrace(&t.0, &args);
        expect_code(&r, 1, "NaN prediction");
        stderr_says(&r, &["row 0", "not a number"]);
        assert!(
            !r.stdout.contains("NaN") && !r.stdout.contains("null"),
            "{}",
            r.stdout
        );
    }
    let r = tactrace(&t.0, &["validate", "--model", "m", "--data", "ds"]);
    expect_code(&r, 0, "the good dataset");
}

/// A targets.csv with a duplicate column name silently used the first
/// (all r labels 0).
#[test]
fn a_label_column_named_twice_is_refused() {
    let t = TempDir::new("dupcolumn");
    bristol_targets(&t.join("targets.csv"), Some("pose_2"), 5);
    std::fs::create_dir_all(t.join("frames")).unwrap();
    let r = import_labelled(&t.0, ["frames", "targets.csv", "ref.png"], &[], "x");
    expect_refusal(&r, 2, "import", "`pose_2` appears 2 times");
    let r = twin(&t.0, ["targets.csv", "ref.png"], &[], "x");
    expect_refusal(&r, 2, "twin", "`pose_2` appears 2 times");
    assert!(!t.join("x").exists());
}

/// A wrong column name printed a truncated header that hid the right ones.
#[test]
fn a_wrong_column_lists_every_column_and_the_nearest() {
    let t = TempDir::new("wrongcolumn");
    bristol_targets(&t.join("targets.csv"), None, 5);
    std::fs::create_dir_all(t.join("frames")).unwrap();
    let r = import_labelled(
        &t.0,
        ["frames", "targets.csv", "ref.png"],
        &["--r-column", "pose2"],
        "x",
    );
    expect_refusal(&r, 2, "wrong column", "(did you mean `pose_2`?)");
    for k in 1..=6 {
        for c in [format!("`pose_{k}`"), format!("`move_{k}`")] {
            assert!(r.stderr.contains(&c), "{c}: {}", r.stderr);
        }
    }
}

/// `--frames` pointing one level above the frames folder gave no hint.
#[test]
fn frames_one_level_too_high_names_the_subfolder() {
    let t = TempDir::new("framesup");
    std::fs::create_dir_all(t.join("set/frames")).unwrap();
    bristol_targets(&t.join("set/targets.csv"), None, 3);
    std::fs::write(t.join("set/frames/frame_0_0.png"), b"a frame").unwrap();
    let r = import_labelled(
        &t.0,
        ["set", "set/targets.csv", "set/frames/frame_0_0.png"],
        &[],
        "x",
    );
    let says = ["subfolder set/frames holds it", "--frames set/frames"];
    expect_refusal_saying(&r, 2, "frames one level up", &says);
}

/// A deformed frame given as `--reference` was accepted silently.
#[test]
fn a_pressed_reference_is_warned_about() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("pressedref");
    let [frames, targets, init] = real_paths(&data);
    let pressed = data.join("frames/frame_1432_0.png").display().to_string();
    for (reference, warned) in [(&init, false), (&pressed, true)] {
        let out = if warned { "pressed" } else { "undeformed" };
        let r = import_labelled(
            &t.0,
            [&frames, &targets, reference],
            &["--limit", "200"],
            out,
        );
        expect_code(&r, 0, out);
        assert_eq!(
            r.stderr.contains("the reference looks pressed"),
            warned,
            "{out}: {}",
            r.stderr
        );
    }
}

/// `twin` printed "simulated 13186 labelled taps" from 3762 rows without
/// saying why.
#[test]
fn twin_with_a_sensor_says_where_its_taps_come_from() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("twincount");
    let [frames, targets, init] = real_paths(&data);
    let r = tactrace(
        &t.0,
        &[
            "calibrate",
            "--frames",
            &frames,
            "--targets",
            &targets,
            "--reference",
            &init,
            "--samples",
            "40",
            "--out",
            "sensor",
        ],
    );
    expect_code(&r, 0, "calibrate");
    let r = twin(
        &t.0,
        [&targets, &init],
        &["--sensor", "sensor", "--limit", "30"],
        "twin",
    );
    expect_code(&r, 0, "twin --sensor");
    stderr_says(
        &r,
        &[
            "from 30 labelled rows: 3 render(s) of each (90 taps",
            "its 40 real calibration taps",
        ],
    );
}

/// `[sensor.camera] width = 0` exited 1 from collect and follow but 2 from
/// sensor render; a NaN tap depth stopped a follow run as a fault (1).
#[test]
fn an_invalid_configuration_exits_2_from_every_command() {
    let t = with_model("configcodes");
    let tables = [
        ("[sensor.camera]\nwidth = 0\n", "camera.width"),
        ("[tap]\ndepth_mm = nan\n", "depth_mm"),
        ("[arm]\nrepeatability_mm = -1\n", "repeatability_mm"),
        ("[workspace]\nmax_step_mm = 0\n", "max_step_mm"),
        ("[blob]\nmin_area = -5\n", "area"),
    ];
    for (table, key) in tables {
        std::fs::write(t.join("rig.toml"), table).unwrap();
        // The follow configuration holds the rig under [rig].
        let follow = table.replacen('[', "[rig.", 1);
        std::fs::write(t.join("follow.toml"), follow).unwrap();
        let runs: [&[&str]; 4] = [
            &[
                "collect",
                "--samples",
                "3",
                "--config",
                "rig.toml",
                "--out",
                "c",
            ],
            &[
                "sensor", "render", "--r", "1", "--theta", "0", "--config", "rig.toml", "--out",
                "r.png",
            ],
            &[
                "follow",
                "--model",
                "m",
                "--shape",
                "disk",
                "--steps",
                "2",
                "--config",
                "follow.toml",
                "--out",
                "f",
            ],
            &[
                "evaluate",
                "--model",
                "m",
                "--shapes",
                "disk",
                "--config",
                "follow.toml",
            ],
        ];
        for args in runs {
            let r = tactrace(&t.0, args);
            expect_refusal(&r, 2, &format!("{table} {args:?}"), key);
        }
    }
    for out in ["c", "r.png", "f", "f.partial"] {
        assert!(!t.join(out).exists(), "{out}");
    }
}

/// Causes were printed twice: `(os error 28): No space left ... (os error
/// 28)`. A file-size limit makes writing the dataset fail with an I/O
/// error wrapped by the npy writer, which repeats its cause.
#[test]
fn an_io_cause_is_printed_once() {
    let t = TempDir::new("causeonce");
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f 1; exec '{}' collect --samples 50 --out ds",
            env!("CARGO_BIN_EXE_tactrace")
        ))
        .current_dir(&t.0)
        .output()
        .expect("sh runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cannot write"), "{stderr}");
    assert_eq!(stderr.matches("os error").count(), 1, "{stderr}");
    assert_eq!(stderr.matches("File too large").count(), 1, "{stderr}");
}

/// Rust debug values reached messages (`Pose { x: ... }`, `[Double, ...]`,
/// `StepsDone`): no `{:?}` formats a message outside tests. (The Python
/// package's crate, crates/py, is not scanned here.)
#[test]
fn no_debug_formatting_in_messages() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut dirs = vec![root.join("src")];
    for entry in std::fs::read_dir(root.join("crates")).unwrap() {
        let crate_dir = entry.unwrap().path();
        if crate_dir.file_name().is_some_and(|n| n != "py") {
            dirs.push(crate_dir.join("src"));
        }
    }
    let mut found = Vec::new();
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if path.is_dir() {
                if name != "tests" {
                    dirs.push(path);
                }
                continue;
            }
            if !name.ends_with(".rs") || name == "tests.rs" {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            for (k, line) in text.lines().enumerate() {
                if line.trim_start().starts_with("#[cfg(test)]") {
                    break;
                }
                let debug = line.contains(":?}") || line.contains(":#?}");
                let in_check = ["assert", "panic!", "expect(", "unreachable!"]
                    .iter()
                    .any(|w| line.contains(w));
                if debug && !in_check {
                    found.push(format!("{}:{}: {}", path.display(), k + 1, line.trim()));
                }
            }
        }
    }
    assert!(found.is_empty(), "debug formatting:\n{}", found.join("\n"));
    // And what a follow run prints: its ending in words.
    let t = with_model("ending");
    let r = tactrace(
        &t.0,
        &[
            "follow", "--model", "m", "--shape", "disk", "--steps", "1", "--out", "f",
        ],
    );
    expect_code(&r, 0, "one step");
    assert!(r.stdout.contains("1 steps, steps done"), "{}", r.stdout);
}

/// The README said a lost-contact follow run stays in `OUT.partial`, but
/// it is committed to `OUT`: a run that ended (however) is complete in
/// `OUT`, and the README and ARCHITECTURE say so.
#[test]
fn a_failed_follow_run_is_in_out_as_the_docs_say() {
    let t = with_model("failedrunout");
    // A contour in metres: the sensor loses contact at once.
    let circle: String = (0..100)
        .map(|k| {
            let a = k as f64 / 100.0 * std::f64::consts::TAU;
            format!("{},{}\n", 0.05 * a.cos(), 0.05 * a.sin())
        })
        .collect();
    std::fs::write(t.join("metres.csv"), circle).unwrap();
    let r = tactrace(
        &t.0,
        &[
            "follow",
            "--model",
            "m",
            "--shape",
            "metres.csv",
            "--out",
            "run",
        ],
    );
    expect_refusal(&r, 1, "lost contact", "(lost contact)");
    assert!(t.join("run/metrics.json").is_file() && t.join("run/trajectory.csv").is_file());
    assert!(!t.join("run.partial").exists());
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let readme = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        readme.contains("a run that stops early (lost contact, a refused move, a fault, the step cap) is complete in `OUT`"),
        "README's output folders paragraph"
    );
    let arch = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let arch = arch.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        arch.contains("however it ended"),
        "ARCHITECTURE invariant 6"
    );
}
