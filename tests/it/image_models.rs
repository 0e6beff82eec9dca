//! The image models end to end (issue 22): `import --frames-size` keeps
//! the frames as `frames.npy`, `train --model conv-dennn|conv-mlp` fits
//! them, `validate` and `predict` read the model folder, and a dataset of
//! pin vectors only is refused. They run the real binary through
//! `tests/it/util.rs`.
use crate::util;
use std::path::Path;
use util::{
    collect, expect_code, expect_refusal, follow_disk_replay, import_real, json, real_paths,
    tactrace, train, TempDir,
};

/// Side of the synthetic frames, px.
const SIDE: usize = 16;

/// One synthetic frame: a bright spot at `(cx, cy)` px on a dark ground.
fn spot(cx: f64, cy: f64) -> Vec<u8> {
    (0..SIDE * SIDE)
        .map(|i| {
            let (y, x) = ((i / SIDE) as f64, (i % SIDE) as f64);
            let d2 = (x - cx).powi(2) + (y - cy).powi(2);
            (20.0 + 220.0 * (-d2 / 4.0).exp()).round() as u8
        })
        .collect()
}

/// The spot of row `k` (a fixed spread over the frame) and its targets:
/// `x` (mm, 0.25 mm a px from the centre) and `angle` (deg, circular,
/// the spot's direction from the centre).
fn row(k: usize) -> ((f64, f64), [f32; 2]) {
    let u = (k as f64 * 0.618_034).fract();
    let v = (k as f64 * 0.414_214 + 0.3).fract();
    let (cx, cy) = (3.5 + 9.0 * u, 3.5 + 9.0 * v);
    let c = (SIDE as f64 - 1.0) / 2.0;
    let x_mm = (cx - c) * 0.25;
    let angle = (cy - c).atan2(cx - c).to_degrees();
    ((cx, cy), [x_mm as f32, angle as f32])
}

/// A dataset of `n` synthetic frames in `dir`: the frames as images, a
/// dummy pin vector a row (3 pins), targets `x` (mm) and `angle` (deg,
/// circular).
fn synthetic_dataset(dir: &Path, n: usize) {
    let (mut inputs, mut targets, mut pixels) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..n {
        let ((cx, cy), t) = row(k);
        pixels.extend(spot(cx, cy));
        targets.extend(t);
        inputs.extend([cx as f32, cy as f32, 0.0, 0.0, 0.0, 0.0]);
    }
    util::write_spot_frames(
        dir,
        "tests/it/image_models.rs",
        SIDE,
        inputs,
        targets,
        pixels,
    );
}

/// A small network for the 16 px frames.
const SMALL: &str = "dense = [16]\nlearning_rate = 0.003\nbatch_size = 8\n\
                     [[conv]]\nchannels = 6\nkernel = 3\nstride = 2\n\
                     [[conv]]\nchannels = 8\nkernel = 3\nstride = 2\n";

#[test]
fn conv_models_train_on_frames_then_validate_and_predict() {
    let t = TempDir::new("issue22-train");
    synthetic_dataset(&t.join("ds"), 240);
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    // Predicting every target's mean: the error to beat.
    let (xs, angles): (Vec<f64>, Vec<f64>) = (0..240)
        .map(|k| (row(k).1[0] as f64, row(k).1[1] as f64))
        .unzip();
    let mean = xs.iter().sum::<f64>() / 240.0;
    let x_baseline = xs.iter().map(|x| (x - mean).abs()).sum::<f64>() / 240.0;
    assert!(x_baseline > 0.5 && angles.iter().any(|a| a.abs() > 150.0));
    for kind in ["conv-mlp", "conv-dennn"] {
        let out = format!("m-{kind}");
        let settings = [
            "--val-fraction",
            "0.25",
            "--seed",
            "3",
            "--config",
            "small.toml",
        ];
        let r = train(&t.0, kind, "ds", "30", &out, &settings);
        expect_code(&r, 0, kind);
        assert!(r.stdout.contains("validation: x "), "{}", r.stdout);
        for file in [
            "model.json",
            "weights.safetensors",
            "frames.json",
            "training.json",
        ] {
            assert!(t.join(&out).join(file).is_file(), "{kind}: no {file}");
        }
        let config = std::fs::read_to_string(t.join(&out).join("config.toml")).unwrap();
        assert!(
            config.contains("seed 3") && config.contains("channels = 6"),
            "{config}"
        );
        // Again into the same folder: refused without --force.
        let again = train(&t.0, kind, "ds", "1", &out, &[]);
        expect_code(&again, 2, "train into an existing model folder");
        let r = tactrace(
            &t.0,
            &[
                "validate",
                "--model",
                &out,
                "--data",
                "ds",
                "--val-fraction",
                "0.25",
                "--json",
            ],
        );
        expect_code(&r, 0, "validate");
        let v = json(&r.stdout);
        assert_eq!(v["samples"], 60);
        assert_eq!(v["rows_seen_in_training"], 0);
        assert_eq!(v["per_target"]["angle"]["circular"], true);
        let x_mae = v["per_target"]["x"]["mae"].as_f64().unwrap();
        let angle_mae = v["per_target"]["angle"]["mae"].as_f64().unwrap();
        assert!(
            x_mae < 0.5 * x_baseline,
            "{kind}: x MAE {x_mae} against {x_baseline} predicting the mean"
        );
        assert!(angle_mae < 45.0, "{kind}: angle MAE {angle_mae} deg");
        // One frame as a PNG: the model's N targets.
        let ((cx, cy), truth) = row(7);
        let png = t.join("frame.png");
        image::GrayImage::from_raw(SIDE as u32, SIDE as u32, spot(cx, cy))
            .unwrap()
            .save(&png)
            .unwrap();
        let r = tactrace(&t.0, &["predict", "--model", &out, "--image", "frame.png"]);
        expect_code(&r, 0, "predict --image");
        let mut lines = r.stdout.lines();
        assert_eq!(lines.next(), Some("x_mm,angle_deg"));
        let values: Vec<f64> = lines
            .next()
            .unwrap()
            .split(',')
            .map(|v| v.parse().unwrap())
            .collect();
        assert!(
            (values[0] - truth[0] as f64).abs() < 1.0,
            "{values:?} {truth:?}"
        );
        let r = tactrace(&t.0, &["predict", "--model", &out, "--data", "ds"]);
        expect_code(&r, 0, "predict --data");
        assert_eq!(r.stdout.lines().count(), 241);
    }
}

#[test]
fn an_image_model_refuses_a_dataset_of_pins_only() {
    let t = TempDir::new("issue22-pins-only");
    let r = collect(&t.0, "20", &["--seed", "1"], "pins");
    expect_code(&r, 0, "collect");
    let r = train(&t.0, "conv-dennn", "pins", "1", "m", &[]);
    expect_code(&r, 2, "train conv-dennn on pins only");
    assert!(
        r.stderr.contains("pin displacements only") && r.stderr.contains("--frames-size"),
        "{}",
        r.stderr
    );
    assert!(!t.join("m").exists());
}

#[test]
fn import_keeps_the_frames_as_images_of_the_size_asked() {
    let Some(set) = tactrace_testdata::real_edge_set() else {
        return;
    };
    let t = TempDir::new("issue22-import");
    let [_, _, reference] = real_paths(&set);
    let with_reference = ["--reference", &reference];
    let r = import_real(
        &t.0,
        &set,
        &[
            &with_reference[..],
            &["--limit", "12", "--frames-size", "32"],
        ]
        .concat(),
        "d",
    );
    expect_code(&r, 0, "import --frames-size");
    let data = tactrace_store::read_dataset(&t.join("d")).unwrap();
    let images = tactrace_store::read_dataset_frames(&t.join("d"), &data)
        .unwrap()
        .expect("frames.npy");
    assert_eq!(
        (images.count(), images.info.height, images.info.width),
        (12, 32, 32)
    );
    assert_eq!(images.info.source_size, [256, 256]);
    // The frame as the detector reads it, area-averaged: 8 x 8 blocks.
    let first =
        tactrace_sensor::read_frame(&set.join("frames").join(&data.meta.images[0])).unwrap();
    let block: u32 = (0..8)
        .flat_map(|y| (0..8).map(move |x| (x, y)))
        .map(|(x, y)| first.get_pixel(x, y).0[0] as u32)
        .sum();
    assert_eq!(images.frame(0)[0] as u32, (block + 32) / 64);
    let meta = json(&std::fs::read_to_string(t.join("d/meta.json")).unwrap());
    assert_eq!(meta["image_frames"]["height"], 32);
    assert_eq!(meta["image_frames"]["file"], "frames.npy");
    // Another split `--like` it keeps its frames at its size.
    let r = import_real(&t.0, &set, &["--like", "d", "--limit", "5"], "e");
    expect_code(&r, 0, "import --like");
    let e = tactrace_store::read_dataset(&t.join("e")).unwrap();
    let images = tactrace_store::read_dataset_frames(&t.join("e"), &e)
        .unwrap()
        .unwrap();
    assert_eq!((images.count(), images.info.height), (5, 32));
    // Without --frames-size: no frames.npy, no image_frames.
    let r = import_real(
        &t.0,
        &set,
        &[&with_reference[..], &["--limit", "3"]].concat(),
        "p",
    );
    expect_code(&r, 0, "import");
    assert!(!t.join("p/frames.npy").exists());
    let meta = json(&std::fs::read_to_string(t.join("p/meta.json")).unwrap());
    assert!(meta.get("image_frames").is_none());
}

/// `follow --replay` with an image model: the perception reads the answered
/// real frames' pixels; the run goes its steps and writes its folder. A
/// world whose frames are of another size than the model's training
/// frames is refused before anything moves.
#[test]
fn follow_in_the_real_frame_world_with_an_image_model() {
    let Some(set) = tactrace_testdata::real_edge_set() else {
        return;
    };
    let t = TempDir::new("issue22-follow");
    let [_, _, reference] = real_paths(&set);
    let settings = [
        "--reference",
        &reference,
        "--limit",
        "200",
        "--frames-size",
        "16",
    ];
    let r = import_real(&t.0, &set, &settings, "d");
    expect_code(&r, 0, "import");
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let r = train(&t.0, "conv-mlp", "d", "3", "m", &["--config", "small.toml"]);
    expect_code(&r, 0, "train");
    let r = follow_disk_replay(&t.0, "m", &set, "6", &[], "run");
    // A barely trained model may lose the edge (exit 1): the run is whole either way.
    assert!(r.code == 0 || r.code == 1, "{}", r.stderr);
    let metrics = json(&std::fs::read_to_string(t.join("run/metrics.json")).unwrap());
    assert!(metrics["steps"].as_u64().unwrap_or(0) >= 1, "{metrics}");
    let trajectory = std::fs::read_to_string(t.join("run/trajectory.csv")).unwrap();
    assert!(trajectory.lines().count() >= 2, "{trajectory}");
    // The simulated world renders 256 px frames too, but the synthetic
    // model was trained on 16 px ones: refused, exit 2.
    synthetic_dataset(&t.join("syn"), 40);
    let r = train(
        &t.0,
        "conv-mlp",
        "syn",
        "1",
        "syn-m",
        &["--config", "small.toml"],
    );
    expect_code(&r, 0, "train synthetic");
    let r = tactrace(
        &t.0,
        &[
            "follow", "--model", "syn-m", "--shape", "disk", "--steps", "3", "--out", "sim",
        ],
    );
    expect_refusal(
        &r,
        2,
        "follow with a model of other frames",
        "trained on frames of 16 x 16 px",
    );
}

/// `reproduce --image-model` trains and follows on real frames: without
/// `--real` it is refused before any work.
#[test]
fn reproduce_image_model_needs_real_frames() {
    let t = TempDir::new("issue22-reproduce");
    let r = tactrace(&t.0, &["reproduce", "--image-model", "--out", "rep"]);
    expect_refusal(
        &r,
        2,
        "reproduce --image-model without --real",
        "give --real DIR",
    );
    assert!(!t.join("rep").exists());
}
