//! Regression tests, each named after the item of issue 10 ("Found") whose
//! bug it pins down. They run the real binary through `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{
    expect_code, expect_refusal, expect_refusal_saying, import_labelled, stderr_says, tactrace,
    tactrace_head, twin, TempDir,
};

/// A temporary folder `name` holding a small dataset `ds` and a model `m`
/// trained on it.
fn with_model(name: &str) -> TempDir {
    let t = TempDir::new(name);
    util::dataset_and_model(&t.0, "40", &["--seed", "3"], &["--model", "pdennn"]);
    t
}

/// A closed contour CSV: a circle of `radius` about (`cx`, `cy`).
fn circle_csv(path: &Path, cx: f64, cy: f64, radius: f64) {
    let text: String = (0..100)
        .map(|k| {
            let t = k as f64 / 100.0 * std::f64::consts::TAU;
            format!("{},{}\n", cx + radius * t.cos(), cy + radius * t.sin())
        })
        .collect();
    std::fs::write(path, text).unwrap();
}

/// A grey-level PNG of uniform noise (no TacTip frame).
fn noise_png(path: &Path, width: u32, height: u32, seed: u64) {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let img = image::GrayImage::from_fn(width, height, |_, _| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        image::Luma([(state >> 56) as u8])
    });
    img.save(path).unwrap();
}

fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// Item 1: a rig file naming only `[tap] depth_mm` (at its default) was
/// read without the defaults ("the reference needs at least 3 pins").
#[test]
fn rig_file_with_only_the_tap_depth_keeps_the_defaults() {
    let t = TempDir::new("rigdefaults");
    std::fs::write(t.join("rig.toml"), "[tap]\ndepth_mm = 8.25\n").unwrap();
    let r = util::collect(&t.0, "10", &["--config", "rig.toml"], "ds");
    expect_code(&r, 0, "collect --config rig.toml");
    assert_eq!(read_json(&t.join("ds/meta.json"))["pins"], 127);
}

/// Item 2: `tactrace predict ... | head -2` panicked on the broken pipe.
#[test]
fn a_closed_stdout_ends_quietly_with_0() {
    let t = TempDir::new("brokenpipe");
    // Enough rows (over 100 kB) that the pipe fills before the reader quits.
    let r = util::collect(&t.0, "4000", &["--seed", "2"], "big");
    expect_code(&r, 0, "collect");
    let r = tactrace(
        &t.0,
        &["train", "--train", "big", "--epochs", "1", "--out", "m"],
    );
    expect_code(&r, 0, "train");
    noise_png(&t.join("noise.png"), 640, 480, 1);
    let cases: [(&[&str], usize); 3] = [
        (&["predict", "--model", "m", "--data", "big"], 2),
        // One short line: the pipe is closed before it is written.
        (&["validate", "--model", "m", "--data", "big", "--json"], 0),
        (&["sensor", "pins", "noise.png", "--expect", "0"], 0),
    ];
    for (args, lines) in cases {
        let r = tactrace_head(&t.0, args, lines);
        assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
        assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
        assert!(!r.stderr.contains("error"), "{args:?}: {}", r.stderr);
        assert_eq!(r.stdout.lines().count(), lines, "{args:?}");
    }
}

/// Item 3: `follow` overwrote an existing `--out` and left partial folders.
#[test]
fn follow_refuses_an_existing_out_without_force() {
    let t = with_model("followforce");
    let follow = ["follow", "--model", "m", "--shape", "disk", "--out", "run"];
    let r = tactrace(&t.0, &[&follow[..], &["--steps", "3"]].concat());
    expect_code(&r, 0, "first follow");
    assert!(!t.join("run.partial").exists(), "the staging folder stays");
    std::fs::write(t.join("run/mine.txt"), "keep me").unwrap();
    let before = std::fs::read(t.join("run/trajectory.csv")).unwrap();
    let r = tactrace(&t.0, &[&follow[..], &["--steps", "5"]].concat());
    expect_refusal(&r, 2, "follow into an existing --out", "--force");
    assert_eq!(std::fs::read(t.join("run/trajectory.csv")).unwrap(), before);
    assert!(t.join("run/mine.txt").exists());
    assert!(!t.join("run.partial").exists());
    let r = tactrace(&t.0, &[&follow[..], &["--steps", "5", "--force"]].concat());
    expect_code(&r, 0, "follow --force");
    assert!(
        !t.join("run/mine.txt").exists(),
        "--force replaces the folder"
    );
    let rows = std::fs::read_to_string(t.join("run/trajectory.csv")).unwrap();
    assert_eq!(rows.lines().count(), 1 + 5);
    assert!(!t.join("run.partial").exists());
}

/// Item 3: `reproduce` overwrote an existing `--out`.
#[test]
fn reproduce_refuses_an_existing_out_without_force() {
    let t = TempDir::new("reproforce");
    let config = "train_samples = 40\nval_samples = 20\nepochs = 1\nreport_steps = false\n\
                  [follow.follow]\nmax_steps = 5\n";
    std::fs::write(t.join("tiny.toml"), config).unwrap();
    std::fs::create_dir_all(t.join("rep")).unwrap();
    std::fs::write(t.join("rep/mine.txt"), "keep me").unwrap();
    let args = ["reproduce", "--config", "tiny.toml", "--out", "rep"];
    let r = tactrace(&t.0, &args);
    expect_refusal(&r, 2, "reproduce into an existing --out", "--force");
    assert_eq!(
        std::fs::read_to_string(t.join("rep/mine.txt")).unwrap(),
        "keep me"
    );
    assert_eq!(std::fs::read_dir(t.join("rep")).unwrap().count(), 1);
    let r = tactrace(&t.0, &[&args[..], &["--force"]].concat());
    expect_code(&r, 0, "reproduce --force");
    assert!(
        !t.join("rep/mine.txt").exists(),
        "--force replaces the folder"
    );
    assert!(t.join("rep/metrics.json").exists());
    // Nothing staged is left beside it.
    let siblings: Vec<_> = std::fs::read_dir(&t.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("rep") && n != "rep")
        .collect();
    assert!(siblings.is_empty(), "{siblings:?}");
}

/// Item 4: a follow that lost contact after 3 steps on a contour in metres
/// exited 0 with coverage 1.0; a 5 mm disk exited 0.
#[test]
fn a_run_that_does_not_complete_exits_1_with_honest_metrics() {
    let t = with_model("failedrun");
    circle_csv(&t.join("metres.csv"), 0.0, 0.0, 0.05);
    circle_csv(&t.join("small.csv"), 5.5, -51.5, 5.0);
    // A short cap keeps the 5 mm disk's run (which never closes) fast.
    std::fs::write(t.join("cap.toml"), "[follow]\nmax_steps = 60\n").unwrap();
    for shape in ["metres.csv", "small.csv"] {
        let out = format!("run-{shape}");
        let r = tactrace(
            &t.0,
            &[
                "follow", "--model", "m", "--shape", shape, "--config", "cap.toml", "--out", &out,
            ],
        );
        expect_code(&r, 1, shape);
        assert!(r.stderr.contains("the run failed"), "{shape}: {}", r.stderr);
        assert!(
            r.stderr.contains("smaller than the sensor"),
            "{shape}: {}",
            r.stderr
        );
        let m = read_json(&t.join(&out).join("metrics.json"));
        assert_eq!(m["succeeded"], false, "{shape}: {m}");
        assert!(
            m["warning"]
                .as_str()
                .is_some_and(|w| w.contains("smaller than the sensor")),
            "{shape}: {m}"
        );
        assert!(!t.join(&format!("{out}.partial")).exists());
    }
    // The run in metres stood still for 3 taps: it traced nothing.
    let m = read_json(&t.join("run-metres.csv/metrics.json"));
    assert_eq!(m["ending"], "lost_contact", "{m}");
    assert!(m["coverage"].as_f64().unwrap() < 0.01, "{m}");
    // One `steps` key, not two.
    let text = std::fs::read_to_string(t.join("run-metres.csv/metrics.json")).unwrap();
    assert_eq!(text.matches("\"steps\"").count(), 1, "{text}");
}

/// Item 5: a missing contour CSV was reported as an unknown shape name.
#[test]
fn a_missing_contour_csv_is_not_an_unknown_shape() {
    let t = TempDir::new("missingcsv");
    let render = |shape: &str| {
        tactrace(
            &t.0,
            &["sensor", "render", "--shape", shape, "--out", "a.png"],
        )
    };
    let r = render("x.csv");
    expect_code(&r, 2, "missing x.csv");
    assert!(
        r.stderr.contains("cannot read x.csv") && !r.stderr.contains("unknown shape"),
        "{}",
        r.stderr
    );
    let r = render("hexagon");
    expect_refusal(&r, 2, "hexagon", "unknown shape `hexagon`");
    assert!(!t.join("a.png").exists());
}

/// Item 6: the operating system's message was printed twice.
#[test]
fn an_os_error_is_printed_once() {
    let t = with_model("oserror");
    let cases: [&[&str]; 5] = [
        &["validate", "--model", "m", "--data", "missing_dir"],
        &["collect", "--config", "missing.toml", "--out", "x"],
        &[
            "follow",
            "--model",
            "m",
            "--shape",
            "missing.csv",
            "--out",
            "x",
        ],
        &[
            "sensor",
            "pins",
            "ds/inputs.npy",
            "--params",
            "missing.toml",
        ],
        &[
            "import",
            "--frames",
            "ds",
            "--targets",
            "missing.csv",
            "--reference",
            "ds/missing.png",
            "--out",
            "x",
        ],
    ];
    for args in cases {
        let r = tactrace(&t.0, args);
        expect_code(&r, 2, &format!("{args:?}"));
        let error_lines = r.stderr.lines().filter(|l| l.starts_with("error")).count();
        assert_eq!(error_lines, 1, "{args:?}: {}", r.stderr);
        for os in ["No such file or directory", "os error"] {
            assert!(
                r.stderr.matches(os).count() <= 1,
                "{args:?} repeats `{os}`: {}",
                r.stderr
            );
        }
    }
    // A dataset file that is a folder: an OS error inside a format error.
    std::fs::create_dir_all(t.join("bad")).unwrap();
    for f in ["meta.json", "targets.npy"] {
        std::fs::copy(t.join("ds").join(f), t.join("bad").join(f)).unwrap();
    }
    std::fs::create_dir_all(t.join("bad/inputs.npy")).unwrap();
    let r = tactrace(&t.0, &["validate", "--model", "m", "--data", "bad"]);
    expect_code(&r, 2, "inputs.npy is a folder");
    // Issue 20: refused as not a regular file before the OS is asked.
    assert!(r.stderr.matches("os error").count() <= 1, "{}", r.stderr);
    stderr_says(&r, &["inputs.npy: is a folder, not a regular file"]);
}

/// Item 7: a frame with too few pins exited 1 (a failed run), not 2.
#[test]
fn a_frame_with_too_few_pins_is_bad_input() {
    let t = with_model("fewpins");
    let render = |args: &[&str]| {
        let r = tactrace(&t.0, &[&["sensor", "render"], args].concat());
        expect_code(&r, 0, "render");
    };
    render(&["--depth", "0", "--r", "30", "--out", "ref.png"]);
    render(&["--r", "1", "--theta", "5", "--out", "tap.png"]);
    noise_png(&t.join("noise.png"), 640, 480, 7);
    // A rendered frame cut to its left third.
    let tap = image::open(t.join("tap.png")).unwrap().to_luma8();
    let (w, h) = tap.dimensions();
    image::imageops::crop_imm(&tap, 0, 0, w / 3, h)
        .to_image()
        .save(t.join("cut.png"))
        .unwrap();
    let predict = |image: &str| {
        tactrace(
            &t.0,
            &[
                "predict",
                "--model",
                "m",
                "--image",
                image,
                "--reference",
                "ref.png",
            ],
        )
    };
    expect_code(&predict("tap.png"), 0, "a whole rendered frame");
    for image in ["noise.png", "cut.png"] {
        let r = predict(image);
        expect_refusal_saying(&r, 2, image, &[image, "pins matched"]);
    }
}

/// Item 8: `import` with a bad reference read every frame, then blamed them.
#[test]
fn import_with_a_bad_reference_fails_fast_naming_it() {
    let t = TempDir::new("badreference");
    let r = util::collect(&t.0, "30", &["--save-frames"], "sim");
    expect_code(&r, 0, "collect --save-frames");
    let mut csv = String::from("image_name,pose_2,pose_6\n");
    for k in 0..30 {
        csv += &format!("frame_{k:05}.png,{}.5,{}\n", k % 5, k % 7);
    }
    std::fs::write(t.join("targets.csv"), csv).unwrap();
    noise_png(&t.join("noise.png"), 640, 480, 3);
    let import = |reference: &str, out: &str| {
        import_labelled(&t.0, ["sim/frames", "targets.csv", reference], &[], out)
    };
    expect_code(
        &import("sim/frames/reference.png", "good"),
        0,
        "good reference",
    );
    let r = import("noise.png", "bad");
    expect_refusal(
        &r,
        2,
        "noise as the reference",
        "noise.png: not an undeformed frame",
    );
    stderr_says(&r, &["--reference"]);
    assert!(!t.join("bad").exists());
    // `twin` orders its simulated frames against the reference: the same.
    let r = twin(
        &t.0,
        ["targets.csv", "noise.png"],
        &["--dz-column", "none", "--shear-columns", "none"],
        "twin",
    );
    expect_refusal(
        &r,
        2,
        "twin with noise as the reference",
        "noise.png: not an undeformed frame",
    );
    assert!(!t.join("twin").exists());
}

/// Item 9: a JSON file given as `--targets` was dumped as its "columns".
#[test]
fn a_json_targets_file_is_not_dumped_as_columns() {
    let t = TempDir::new("jsontargets");
    let json = serde_json::json!({
        "frames": (0..200).map(|k| format!("frame_{k}.png")).collect::<Vec<_>>(),
        "labels": { "pose_2": [1.0, 2.0], "pose_6": [3.0, 4.0] },
    });
    std::fs::write(
        t.join("targets.json"),
        serde_json::to_string_pretty(&json).unwrap(),
    )
    .unwrap();
    std::fs::write(t.join("ref.png"), b"unused").unwrap();
    let r = import_labelled(&t.0, ["frames", "targets.json", "ref.png"], &[], "x");
    expect_refusal(
        &r,
        2,
        "JSON targets",
        "targets.json: not a CSV with the label columns",
    );
    assert!(
        r.stderr.len() < 600,
        "{} bytes: {}",
        r.stderr.len(),
        r.stderr
    );
    // A wide CSV lists every column, wrapped (issue 20: a truncated header
    // hid the right ones).
    let header: Vec<String> = (0..40).map(|k| format!("c{k}")).collect();
    std::fs::write(t.join("wide.csv"), header.join(",") + "\n").unwrap();
    let r = import_labelled(&t.0, ["frames", "wide.csv", "ref.png"], &[], "x");
    let says = ["its 40 columns", "`c39`"];
    expect_refusal_saying(&r, 2, "wide CSV", &says);
}

/// Item 10: an unreachable contour printed a Rust debug struct (`Pose { x: .. }`).
#[test]
fn an_unreachable_contour_prints_no_debug_struct() {
    let t = with_model("unreachable");
    std::fs::write(
        t.join("far.csv"),
        "1000,1000\n1100,1000\n1100,1100\n1000,1100\n",
    )
    .unwrap();
    let r = tactrace(
        &t.0,
        &["follow", "--model", "m", "--shape", "far.csv", "--out", "r"],
    );
    expect_refusal(&r, 2, "far.csv", "cannot reach");
    assert!(
        !r.stderr.contains('{') && !r.stderr.contains("Pose"),
        "{}",
        r.stderr
    );
    assert!(!t.join("r").exists() && !t.join("r.partial").exists());
}

/// Item 11: a plot that could not be written became a configuration error
/// (exit 2, as for bad input); it is a failed run (exit 1).
#[test]
fn an_output_that_cannot_be_written_exits_1() {
    let t = with_model("cannotwrite");
    // A folder where the figure file should be (--force: replacing an
    // existing output is asked for, issue 20, and cannot be done).
    std::fs::create_dir_all(t.join("plots/predicted_vs_true.svg")).unwrap();
    let r = tactrace(
        &t.0,
        &[
            "validate", "--model", "m", "--data", "ds", "--plots", "plots", "--force",
        ],
    );
    expect_refusal(
        &r,
        1,
        "a figure that cannot be written",
        "predicted_vs_true.svg",
    );
    // A file where a folder should be.
    std::fs::write(t.join("afile"), "x").unwrap();
    let r = tactrace(
        &t.0,
        &[
            "follow",
            "--model",
            "m",
            "--shape",
            "disk",
            "--steps",
            "3",
            "--out",
            "afile/run",
        ],
    );
    expect_code(&r, 1, "a run folder that cannot be made");
    // Bad input stays 2.
    let r = tactrace(
        &t.0,
        &[
            "validate", "--model", "m", "--data", "nothing", "--plots", "p",
        ],
    );
    expect_code(&r, 2, "a missing dataset");
}

/// Item 12: `sensor pins` on noise reported 495 "pins", exit 0, no warning.
#[test]
fn sensor_pins_warns_when_the_count_is_not_the_sensors() {
    let t = TempDir::new("pinscount");
    noise_png(&t.join("noise.png"), 640, 480, 5);
    let r = tactrace(&t.0, &["sensor", "render", "--r", "2", "--out", "tap.png"]);
    expect_code(&r, 0, "render");
    let pins = |args: &[&str]| tactrace(&t.0, &[&["sensor", "pins"], args].concat());
    let r = pins(&["noise.png"]);
    expect_refusal(&r, 0, "noise, warned", "warning: noise.png");
    stderr_says(&r, &["127 pins"]);
    assert!(r.stdout.lines().count() > 1, "the blobs are still printed");
    let r = pins(&["noise.png", "--strict"]);
    expect_code(&r, 2, "noise, --strict");
    let r = pins(&["noise.png", "--expect", "0"]);
    expect_code(&r, 0, "noise, no check");
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
    let r = pins(&["tap.png", "--preset", "sim", "--strict"]);
    expect_code(&r, 0, "a rendered frame");
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
}

/// Item 13: `sensor render --depth 50` silently gave the 8 mm image.
#[test]
fn render_refuses_depths_outside_the_contact_model() {
    let t = TempDir::new("renderdepth");
    let render = |args: &[&str]| {
        tactrace(
            &t.0,
            &[&["sensor", "render", "--out", "a.png"], args].concat(),
        )
    };
    for args in [
        &["--depth", "50"][..],
        &["--depth", "-1"],
        &["--depth", "NaN"],
        &["--r", "nan"],
        &["--theta", "inf"],
    ] {
        let r = render(args);
        expect_code(&r, 2, &format!("{args:?}"));
        assert!(!t.join("a.png").exists(), "{args:?}");
    }
    let r = render(&["--depth", "50"]);
    stderr_says(&r, &["0 to 8 mm", "max_depth_mm"]);
    expect_code(&render(&["--depth", "8"]), 0, "the deepest tap");
}

/// Item 14: `bench --real-frames` without `--model` ignored the folder.
#[test]
fn bench_real_frames_without_model_is_bad_input() {
    let t = TempDir::new("benchreal");
    std::fs::create_dir_all(t.join("frames")).unwrap();
    let r = tactrace(&t.0, &["bench", "--taps", "1", "--real-frames", "frames"]);
    expect_refusal(&r, 2, "bench --real-frames", "--model");
    assert!(r.stdout.is_empty(), "{}", r.stdout);
}

/// Item 15: two unrelated `CameraConfig` types; the rig file's `[camera]`
/// table is now a `FrameSourceConfig`, under the same table name.
#[test]
fn the_rig_files_camera_table_is_a_frame_source() {
    use tactrace_lab::hardware::{FrameSourceConfig, HardwareConfig};
    let text = "[arm]\nhost = \"192.0.2.1\"\n[camera.folder]\npath = \"frames\"\n\
                [workspace]\nmin = [-50.0, -50.0, -15.0]\nmax = [50.0, 50.0, 20.0]\n\
                [start]\nx_mm = 0.0\ny_mm = 0.0\n";
    let cfg = HardwareConfig::from_toml(text, "rig.toml").unwrap();
    assert!(
        matches!(&cfg.camera, FrameSourceConfig::Folder { path, .. } if path == Path::new("frames"))
    );
}
