//! Simulated taps as images (issue 22): `collect --frames-size` and
//! `twin --frames-size` write `frames.npy` and `meta.json`'s
//! `image_frames` as `import --frames-size` does, so an image model trains
//! on simulated data (and, for the twin, validates on the real frames it
//! mirrors). They run the real binary through `tests/it/util.rs`.
use crate::util;
use tactrace_servo::ImageInput;
use util::{
    frames_of, import_real, json, ok, real_data, real_paths, tactrace, train, write_small_conv,
    TempDir,
};

#[test]
fn collect_frames_size_writes_the_rendered_frames_and_trains_an_image_model() {
    let t = TempDir::new("issue22-collect-frames");
    write_small_conv(&t.0);
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
    let r = train(
        &t.0,
        "conv-mlp",
        "ds",
        "1",
        "m",
        &["--config", "small.toml"],
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
fn collect_frames_size_is_refused_where_it_cannot_apply() {
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
fn twin_frames_size_trains_on_simulated_frames_and_validates_on_real_ones() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("issue22-twin-frames");
    write_small_conv(&t.0);
    let [_, targets, init] = real_paths(&data);
    let common = ["--reference", &init, "--limit", "30", "--frames-size", "32"];
    let twin = [
        &["twin", "--targets", &targets][..],
        &common,
        &["--out", "tw"],
    ]
    .concat();
    ok(&tactrace(&t.0, &twin), "twin --frames-size");
    let r = import_real(&t.0, &data, &common, "real");
    ok(&r, "import --frames-size");
    let (rows, sim) = frames_of(&t.join("tw"));
    let (_, real) = frames_of(&t.join("real"));
    assert_eq!(sim.count(), rows);
    assert_eq!(rows, 30);
    // The twin's frames are described as the real ones are: same size,
    // same source size, same preprocessing, so one model takes both.
    assert_eq!(sim.info, real.info);
    assert_ne!(sim.frame(0), sim.frame(29));
    let r = train(
        &t.0,
        "conv-mlp",
        "tw",
        "1",
        "m",
        &["--config", "small.toml"],
    );
    ok(&r, "train on the twin's frames");
    let r = tactrace(
        &t.0,
        &["validate", "--model", "m", "--data", "real", "--json"],
    );
    ok(&r, "validate on the real frames");
    let v = json(&r.stdout);
    assert_eq!(v["samples"], 30);
    assert_eq!(v["rows_seen_in_training"], 0);
}
