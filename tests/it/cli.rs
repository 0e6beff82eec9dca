//! End-to-end tests of the `tactrace` binary.
use crate::util;
use util::{expect_refusal, real_data, real_paths, tactrace, TempDir};

#[test]
fn collect_writes_a_python_readable_dataset() {
    let t = TempDir::new("collect");
    let r = tactrace(
        &t.0,
        &[
            "collect",
            "--shape",
            "disk",
            "--samples",
            "30",
            "--seed",
            "7",
            "--out",
            "ds",
            "--save-frames",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    for f in [
        "inputs.npy",
        "targets.npy",
        "meta.json",
        "frames/frame_00000.png",
        "frames/reference.png",
    ] {
        assert!(t.join("ds").join(f).exists(), "missing {f}");
    }
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.join("ds/meta.json")).unwrap()).unwrap();
    assert_eq!(meta["seed"], 7);
    assert_eq!(meta["samples"], 30);
    assert_eq!(meta["pins"], 127);
    // The same seed gives the same bytes.
    let r = tactrace(
        &t.0,
        &["collect", "--samples", "30", "--seed", "7", "--out", "ds2"],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(
        std::fs::read(t.join("ds/inputs.npy")).unwrap(),
        std::fs::read(t.join("ds2/inputs.npy")).unwrap()
    );
    // An existing output is not overwritten without --force.
    let r = tactrace(&t.0, &["collect", "--samples", "5", "--out", "ds"]);
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("already exists"), "{}", r.stderr);
}

/// A model refuses data whose pins follow another reference order.
#[test]
fn data_ordered_against_another_reference_is_refused() {
    let t = TempDir::new("pinorder");
    let r = tactrace(
        &t.0,
        // 36 samples at least for the 35 components (issue 20).
        &["collect", "--samples", "40", "--seed", "3", "--out", "ds"],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let args = [
        "--model", "pdennn", "--train", "ds", "--epochs", "1", "--out", "m",
    ];
    let r = tactrace(&t.0, &[&["train"], &args[..]].concat());
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(t.join("m/pins.json").exists());
    let r = tactrace(
        &t.0,
        &["validate", "--model", "m", "--data", "ds", "--json"],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    // The same data with two reference pins listed the other way round.
    std::fs::create_dir_all(t.join("swapped")).unwrap();
    for f in ["inputs.npy", "targets.npy"] {
        std::fs::copy(t.join("ds").join(f), t.join("swapped").join(f)).unwrap();
    }
    let text = std::fs::read_to_string(t.join("ds/meta.json")).unwrap();
    let mut meta: serde_json::Value = serde_json::from_str(&text).unwrap();
    meta["reference_pins"].as_array_mut().unwrap().swap(0, 1);
    std::fs::write(t.join("swapped/meta.json"), meta.to_string()).unwrap();
    for cmd in [
        &["validate", "--model", "m", "--data", "swapped"][..],
        &["predict", "--model", "m", "--data", "swapped"][..],
    ] {
        let r = tactrace(&t.0, cmd);
        assert_eq!(r.code, 2, "{cmd:?}: {}", r.stderr);
        assert!(r.stderr.contains("another order"), "{}", r.stderr);
    }
    let r = tactrace(
        &t.0,
        &[&["train"], &args[..], &["--val", "swapped", "--force"]].concat(),
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
}

#[test]
fn unknown_shape_is_a_clear_error() {
    let t = TempDir::new("badshape");
    let r = tactrace(
        &t.0,
        &[
            "collect",
            "--shape",
            "hexagon",
            "--samples",
            "5",
            "--out",
            "x",
        ],
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("unknown shape `hexagon`"), "{}", r.stderr);
    assert!(!t.join("x").exists());
}

#[test]
fn open_contour_csv_is_rejected_with_the_file_name() {
    let t = TempDir::new("opencsv");
    std::fs::write(t.join("open.csv"), "x,y\n0,0\n10,0\n20,0\n20,10\n20,20\n").unwrap();
    let r = tactrace(
        &t.0,
        &["sensor", "render", "--shape", "open.csv", "--out", "a.png"],
    );
    expect_refusal(&r, 2, "open.csv", "open.csv");
}

#[test]
fn corrupt_image_is_a_clear_error() {
    let t = TempDir::new("corrupt");
    std::fs::write(t.join("bad.png"), b"not a png").unwrap();
    let r = tactrace(&t.0, &["sensor", "pins", "bad.png"]);
    expect_refusal(&r, 2, "bad.png", "bad.png");
}

#[test]
fn render_then_detect_gives_127_pins() {
    let t = TempDir::new("render");
    let r = tactrace(
        &t.0,
        &[
            "sensor", "render", "--shape", "disk", "--r", "2", "--theta", "10", "--out", "tap.png",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let r = tactrace(&t.0, &["sensor", "pins", "tap.png", "--preset", "sim"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let mut lines = r.stdout.lines();
    assert_eq!(lines.next(), Some("x,y,size"));
    assert_eq!(lines.count(), 127);
}

#[test]
fn real_reference_frame_gives_127_pins() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("realpins");
    let init = data.join("frames/init_0.png");
    let r = tactrace(&t.0, &["sensor", "pins", init.to_str().unwrap()]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(r.stdout.lines().count(), 128);
}

#[test]
fn twin_of_real_frames_writes_a_dataset_and_refuses_bad_input() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("twin");
    let (targets, init) = (data.join("targets.csv"), data.join("frames/init_0.png"));
    let (targets, init) = (targets.to_str().unwrap(), init.to_str().unwrap());
    let args = [
        "twin",
        "--targets",
        targets,
        "--reference",
        init,
        "--limit",
        "30",
    ];
    let r = tactrace(&t.0, &[&args[..], &["--out", "twin"]].concat());
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr.contains("simulated 30 labelled taps"),
        "{}",
        r.stderr
    );
    let meta = std::fs::read_to_string(t.join("twin/meta.json")).unwrap();
    assert!(meta.contains("simulated twin"), "{meta}");
    // Nothing is overwritten without --force; a bad column list is bad input.
    let again = tactrace(&t.0, &[&args[..], &["--out", "twin"]].concat());
    assert_eq!(again.code, 2, "{}", again.stderr);
    let bad = [
        &args[..],
        &["--shear-columns", "move_1,move_2", "--out", "t2"],
    ]
    .concat();
    let r = tactrace(&t.0, &bad);
    expect_refusal(&r, 2, "three columns", "three columns");
}

#[test]
fn follow_rejects_unknown_config_keys_and_unreachable_contours() {
    let t = TempDir::new("followbad");
    let ok = |args: &[&str]| {
        let r = tactrace(&t.0, args);
        assert_eq!(r.code, 0, "{}", r.stderr);
    };
    ok(&["collect", "--samples", "40", "--seed", "3", "--out", "ds"]);
    ok(&[
        "train", "--model", "pdennn", "--train", "ds", "--epochs", "2", "--out", "m",
    ]);
    std::fs::write(t.join("bad.toml"), "[follow]\nbogus = 1\n").unwrap();
    let r = tactrace(
        &t.0,
        &[
            "follow", "--model", "m", "--shape", "disk", "--config", "bad.toml", "--out", "r1",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("bogus") && r.stderr.contains("bad.toml"),
        "{}",
        r.stderr
    );
    std::fs::write(
        t.join("far.csv"),
        "1000,1000\n1100,1000\n1100,1100\n1000,1100\n",
    )
    .unwrap();
    let r = tactrace(
        &t.0,
        &[
            "follow", "--model", "m", "--shape", "far.csv", "--out", "r2",
        ],
    );
    expect_refusal(&r, 2, "cannot reach", "cannot reach");
    // A real-rig file whose start lies outside its workspace is refused
    // before any connection is attempted (the host does not exist).
    std::fs::write(
        t.join("rig.toml"),
        "[arm]\nhost = \"192.0.2.1\"\n[camera.folder]\npath = \"ds\"\n\
         [workspace]\nmin = [10.0, 10.0, -15.0]\nmax = [50.0, 50.0, 20.0]\n\
         [start]\nx_mm = 0.0\ny_mm = 0.0\n",
    )
    .unwrap();
    let r = tactrace(
        &t.0,
        &[
            "follow",
            "--hardware",
            "rig.toml",
            "--model",
            "m",
            "--out",
            "r3",
        ],
    );
    expect_refusal(&r, 2, "outside the workspace", "outside the workspace");
}

#[test]
fn reproduce_writes_the_report_with_every_table_and_figure() {
    let t = TempDir::new("reproduce");
    // A miniature run: few taps, few epochs, short follow runs.
    let config =
        "train_samples = 60\nval_samples = 30\nepochs = 3\n[follow.follow]\nmax_steps = 40\n";
    std::fs::write(t.join("small.toml"), config).unwrap();
    let r = tactrace(
        &t.0,
        &[
            "reproduce",
            "--config",
            "small.toml",
            "--seed",
            "4",
            "--out",
            "rep",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let rep = t.join("rep");
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(rep.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["networks"].as_array().unwrap().len(), 4);
    assert_eq!(metrics["shapes"].as_array().unwrap().len(), 4);
    assert_eq!(metrics["seed"], 4);
    let html = std::fs::read_to_string(rep.join("report.html")).unwrap();
    for fig in ["Fig. 4.1", "Fig. 4.4", "Fig. 4.5", "Fig. 5.3", "Fig. 5.4"] {
        assert!(html.contains(fig), "report.html lacks {fig}");
    }
    // Self-contained: every figure is embedded, none is a broken link.
    assert!(!html.contains("src=\"figures/") && !html.contains("src=\"models/"));
    assert!(html.matches("data:image/svg+xml;base64,").count() >= 14);
    // Each shape's run has its step-by-step page, linked from the report.
    for shape in ["disk", "flower", "trine", "teardrop"] {
        let page = format!("follow/{shape}/replay.html");
        assert!(
            html.contains(&format!("href=\"{page}\"")),
            "no link to {page}"
        );
        let text = std::fs::read_to_string(rep.join(&page)).unwrap();
        assert!(text.contains("\"steps\":[["), "{page} holds no steps");
    }
    let config = std::fs::read_to_string(rep.join("config.toml")).unwrap();
    assert!(config.contains("seed = 4") && config.contains("train_samples = 60"));
}

#[test]
fn calibrate_then_render_and_twin_with_the_sensor() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("calibrate");
    let [frames, targets, init] = real_paths(&data);
    let (frames, targets, init) = (frames.as_str(), targets.as_str(), init.as_str());
    let cal = [
        "calibrate",
        "--frames",
        frames,
        "--targets",
        targets,
        "--reference",
        init,
        "--samples",
        "100",
        "--seed",
        "1",
        "--out",
        "sensor",
    ];
    let r = tactrace(&t.0, &cal);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("held-out taps"), "{}", r.stdout);
    for part in [
        "sensor.toml",
        "reference.png",
        "correction.safetensors",
        "figures/field_after.png",
    ] {
        assert!(t.join("sensor").join(part).exists(), "{part}");
    }
    // Nothing overwritten without --force; too few taps is bad input.
    assert_eq!(tactrace(&t.0, &cal).code, 2);
    let few = [&cal[..7], &["--samples", "5", "--out", "s2"]].concat();
    let r = tactrace(&t.0, &few);
    expect_refusal(&r, 2, "10", "10");
    // Taps that do not span theta are refused, the message printed once.
    let narrow = [&cal[..7], &["--limit", "600", "--out", "s3"]].concat();
    let r = tactrace(&t.0, &narrow);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert_eq!(r.stderr.matches("do not span").count(), 1, "{}", r.stderr);
    // The calibrated sensor renders taps whose pins are all found...
    let r = tactrace(
        &t.0,
        &[
            "sensor", "render", "--sensor", "sensor", "--r", "2", "--theta", "10", "--out",
            "tap.png",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let pins = tactrace(&t.0, &["sensor", "pins", "tap.png", "--strict"]);
    assert_eq!(pins.code, 0, "{}", pins.stderr);
    let bad = [
        "sensor", "render", "--sensor", "sensor", "--depth", "50", "--out", "b.png",
    ];
    assert_eq!(tactrace(&t.0, &bad).code, 2);
    // ...and makes training sets in the real reference's pin order.
    let twin = [
        "twin",
        "--sensor",
        "sensor",
        "--targets",
        targets,
        "--reference",
        init,
        "--limit",
        "800",
        "--out",
        "tw",
    ];
    let r = tactrace(&t.0, &twin);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let meta = std::fs::read_to_string(t.join("tw/meta.json")).unwrap();
    assert!(meta.contains("calibrated sensor"), "{meta}");
    let train_twin = [
        "train", "--model", "pdennn", "--train", "tw", "--epochs", "60", "--out", "mt",
    ];
    assert_eq!(tactrace(&t.0, &train_twin).code, 0);
    // Its simulated world: collect in its labels, train, follow, bench.
    let r = tactrace(
        &t.0,
        &[
            "collect",
            "--sensor",
            "sensor",
            "--samples",
            "400",
            "--out",
            "cs",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let meta = std::fs::read_to_string(t.join("cs/meta.json")).unwrap();
    assert!(meta.contains("pose_6"), "{meta}");
    let train = [
        "train", "--model", "pdennn", "--train", "cs", "--epochs", "60", "--out", "m",
    ];
    assert_eq!(tactrace(&t.0, &train).code, 0);
    let follow = |extra: &[&str], out: &str| {
        let model = if extra.contains(&"--model") {
            &[][..]
        } else {
            &["--model", "m"][..]
        };
        let args = [
            &["follow", "--shape", "disk", "--out", out][..],
            model,
            extra,
        ]
        .concat();
        tactrace(&t.0, &args)
    };
    let r = follow(&["--sensor", "sensor"], "run");
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("closed"), "{}", r.stdout);
    let config = std::fs::read_to_string(t.join("run/config.toml")).unwrap();
    assert!(config.contains("calibrated_sensor"), "{config}");
    // The default world lists its pins otherwise: refused before moving.
    let r = follow(&[], "run2");
    expect_refusal(&r, 2, "order", "order");
    assert_eq!(follow(&["--sensor", "no-such-sensor"], "run3").code, 2);
    // The real-frame world reads the sensor's label convention too; its
    // taps are real frames, so the model is the one trained on the twin
    // (the `collect` taps carry no shear, the real frames do).
    let data_dir = data.to_str().unwrap();
    let replay = [
        "--model",
        "mt",
        "--sensor",
        "sensor",
        "--replay",
        data_dir,
        "--replay-keep",
        "N%5==0",
        "--steps",
        "5",
    ];
    let r = follow(&replay, "run4");
    assert_eq!(r.code, 0, "{}", r.stderr);
    let config = std::fs::read_to_string(t.join("run4/config.toml")).unwrap();
    assert!(config.contains("calibrated_sensor"), "{config}");
    let bench = ["bench", "--taps", "20", "--sensor", "sensor"];
    assert_eq!(tactrace(&t.0, &bench).code, 0);
}
