//! Simulated taps as images (issue 22): `collect --frames-size` and
//! `twin --frames-size` write `frames.npy` and `meta.json`'s
//! `image_frames` as `import --frames-size` does, so an image model trains
//! on simulated data (and, for the twin, validates on the real frames it
//! mirrors). They run the real binary through `tests/util.rs`.
mod util;
use std::path::Path;
use tactrace_servo::ImageInput;
use tactrace_store::{read_dataset, read_dataset_frames, ImageFrames};
use util::{real_data, tactrace, Run, TempDir};

fn ok(r: &Run, what: &str) {
    assert_eq!(
        r.code, 0,
        "{what}\nstdout: {}\nstderr: {}",
        r.stdout, r.stderr
    );
}

/// The dataset in `dir` and its frames (which it must have).
fn frames_of(dir: &Path) -> (usize, ImageFrames) {
    let data = read_dataset(dir).unwrap();
    let frames = read_dataset_frames(dir, &data)
        .unwrap()
        .unwrap_or_else(|| panic!("{} has no frames.npy", dir.display()));
    (data.len(), frames)
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text.trim()).unwrap_or_else(|e| panic!("{e}: {text}"))
}

/// A small network for 32 px frames.
const SMALL: &str = "dense = [8]\nbatch_size = 8\n[[conv]]\nchannels = 4\nkernel = 3\nstride = 2\n";

#[test]
fn issue22_collect_frames_size_writes_the_rendered_frames_and_trains_an_image_model() {
    let t = TempDir::new("issue22-collect-frames");
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let r = tactrace(
        &t.0,
        &[
            "collect",
            "--samples",
            "24",
            "--seed",
            "5",
            "--frames-size",
            "32",
            "--save-frames",
            "--out",
            "ds",
        ],
    );
    ok(&r, "collect --frames-size");
    let (rows, frames) = frames_of(&t.join("ds"));
    assert_eq!(rows, 24);
    assert_eq!(frames.count(), 24);
    assert_eq!((frames.info.height, frames.info.width), (32, 32));
    // Simulated frames reach the follow perception as rendered: none.
    assert_eq!(frames.info.preprocess, None);
    // Each row is its saved rendered frame through the one ImageInput,
    // bit for bit (what the follow perception feeds a model).
    let input = ImageInput::new(None, (32, 32)).unwrap();
    for i in [0, 7, 23] {
        let png = t.join(&format!("ds/frames/frame_{i:05}.png"));
        let grey = image::open(&png).unwrap().to_luma8();
        let source = [grey.height() as usize, grey.width() as usize];
        assert_eq!(frames.info.source_size, source);
        let made = input.of_frame(&grey).unwrap();
        assert_eq!(made, frames.frame(i), "row {i}");
    }
    // Rows differ: the frames are the taps', not one frame repeated.
    assert_ne!(frames.frame(0), frames.frame(23));
    // An image model trains on them for one epoch, then validates.
    let r = tactrace(
        &t.0,
        &[
            "train",
            "--model",
            "conv-mlp",
            "--train",
            "ds",
            "--epochs",
            "1",
            "--config",
            "small.toml",
            "--out",
            "m",
        ],
    );
    ok(&r, "train conv-mlp on a collection's frames");
    let r = tactrace(
        &t.0,
        &["validate", "--model", "m", "--data", "ds", "--json"],
    );
    ok(&r, "validate");
    let v = json(&r.stdout);
    assert_eq!(v["samples"], 24);
    assert_eq!(v["rows_seen_in_training"], 24);
}

#[test]
fn issue22_collect_frames_size_is_refused_where_it_cannot_apply() {
    let t = TempDir::new("issue22-collect-frames-bad");
    for args in [
        &["--frames-size", "2"][..],
        &["--frames-size", "32", "--task", "surface_3d"][..],
    ] {
        let mut all = vec!["collect", "--samples", "4", "--out", "ds"];
        all.extend(args);
        let r = tactrace(&t.0, &all);
        assert_eq!(r.code, 2, "{args:?}\n{}", r.stderr);
        assert!(r.stderr.contains("frames-size"), "{}", r.stderr);
        assert!(!t.join("ds").exists());
    }
}

#[test]
fn issue22_twin_frames_size_trains_on_simulated_frames_and_validates_on_real_ones() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("issue22-twin-frames");
    std::fs::write(t.join("small.toml"), SMALL).unwrap();
    let (targets, frames) = (data.join("targets.csv"), data.join("frames"));
    let init = frames.join("init_0.png");
    let (targets, frames, init) = (
        targets.to_str().unwrap(),
        frames.to_str().unwrap(),
        init.to_str().unwrap(),
    );
    let common = ["--targets", targets, "--limit", "30", "--frames-size", "32"];
    let twin = [
        &["twin", "--reference", init][..],
        &common,
        &["--out", "tw"],
    ]
    .concat();
    ok(&tactrace(&t.0, &twin), "twin --frames-size");
    let real = [
        &["import", "--frames", frames, "--reference", init][..],
        &common,
        &["--out", "real"],
    ]
    .concat();
    ok(&tactrace(&t.0, &real), "import --frames-size");
    let (rows, sim) = frames_of(&t.join("tw"));
    let (_, real) = frames_of(&t.join("real"));
    assert_eq!(sim.count(), rows);
    assert_eq!(rows, 30);
    // The twin's frames are described as the real ones are: same size,
    // same source size, same preprocessing, so one model takes both.
    assert_eq!(sim.info, real.info);
    assert_ne!(sim.frame(0), sim.frame(29));
    let train = [
        "train",
        "--model",
        "conv-mlp",
        "--train",
        "tw",
        "--epochs",
        "1",
        "--config",
        "small.toml",
        "--out",
        "m",
    ];
    ok(&tactrace(&t.0, &train), "train on the twin's frames");
    let r = tactrace(
        &t.0,
        &["validate", "--model", "m", "--data", "real", "--json"],
    );
    ok(&r, "validate on the real frames");
    let v = json(&r.stdout);
    assert_eq!(v["samples"], 30);
    assert_eq!(v["rows_seen_in_training"], 0);
}
