//! An image model is fed frames made exactly as its training dataset's
//! `frames.npy` was (issue 22): `import --sensor --frames-size` records the
//! sensor preprocessing beside the frames, `train` copies it into the
//! model folder, and the one function that makes an image model's input
//! (`tactrace_servo::ImageInput`, used by `follow` in every world and by
//! `predict --image`) gives each row's frame bit for bit. A model folder
//! written before the record keeps loading, with no preprocessing.
use crate::util;
use image::{GrayImage, Luma};
use std::path::Path;
use tactrace_lab::{follow::image_input_for, import_reader};
use tactrace_store::{read_dataset, read_dataset_frames, SightFile, StoredImageModel};
use util::{import_labelled, ok, tactrace, train, write_small_conv, Run, TempDir};

/// `tactrace import` of the synthetic set `set/` (its first image the
/// reference) into `d`, with `extra` arguments.
fn import_set(dir: &Path, extra: &[&str]) -> Run {
    let set = ["set/frames", "set/targets.csv", "set/frames/image_1.png"];
    import_labelled(dir, set, extra, "d")
}

/// A 96 x 96 px synthetic TacTip: 61 pins on a hexagonal lattice of
/// spacing 9 px, with a bright frame border outside the dome that the
/// sensor file's crop and mask remove. Tap `k` pushes the pins
/// away from a point that moves with `k`.
fn frame(k: usize) -> GrayImage {
    let c = [47.6, 48.3];
    let at = [
        c[0] + 12.0 * (k as f64 * 0.9).cos(),
        c[1] + 12.0 * (k as f64 * 1.3).sin(),
    ];
    let push = 2.5 * (k % 5) as f64 / 4.0;
    let mut pins = Vec::new();
    for q in -4i32..=4 {
        for r in -4i32..=4 {
            if (q + r).abs() <= 4 {
                let x = c[0] + 9.0 * (f64::from(q) + 0.5 * f64::from(r));
                let y = c[1] + 9.0 * 0.75f64.sqrt() * f64::from(r);
                let (dx, dy) = (x - at[0], y - at[1]);
                let g = push * (-(dx * dx + dy * dy) / 200.0).exp() / 10.0;
                pins.push([x + g * dx, y + g * dy]);
            }
        }
    }
    GrayImage::from_fn(96, 96, |x, y| {
        let (xf, yf) = (f64::from(x), f64::from(y));
        let on_pin = pins.iter().any(|p| (p[0] - xf).hypot(p[1] - yf) <= 2.2);
        let border = x < 6 || y < 6 || x > 89 || y > 89;
        let ground = ((x * 7 + y * 3 + k as u32) % 40) as u8;
        Luma([if on_pin || border { 250 } else { ground }])
    })
}

/// `n` taps as `dir/frames/image_K.png` and `dir/targets.csv`.
fn write_set(dir: &Path, n: usize) {
    std::fs::create_dir_all(dir.join("frames")).unwrap();
    let mut csv = String::from("sensor_image,pose_2,pose_6\n");
    for k in 0..n {
        let name = format!("image_{}.png", k + 1);
        frame(k).save(dir.join("frames").join(&name)).unwrap();
        csv.push_str(&format!(
            "{name},{:.3},{:.3}\n",
            (k % 7) as f64 * 0.5,
            k as f64 * 3.0
        ));
    }
    std::fs::write(dir.join("targets.csv"), csv).unwrap();
}

#[test]
fn an_image_model_is_fed_frames_made_as_its_frames_npy_rows() {
    let t = TempDir::new("issue22-sight");
    write_set(&t.join("set"), 24);
    let r = tactrace(
        &t.0,
        &["sensor", "inspect", "set/frames", "--out", "sensor.toml"],
    );
    ok(&r, "sensor inspect");
    // The proposal (dome mask, threshold) with a crop of the border.
    let text = std::fs::read_to_string(t.join("sensor.toml")).unwrap();
    assert!(text.contains("[preprocess.mask]"), "{text}");
    std::fs::write(t.join("uncropped.toml"), &text).unwrap();
    let text = text.replace(
        "[preprocess.mask]",
        "[preprocess]\ncrop = [3, 3, 93, 93]\n\n[preprocess.mask]",
    );
    std::fs::write(t.join("sensor.toml"), text).unwrap();
    let sensor = SightFile::read(&t.join("sensor.toml")).unwrap().sight();
    write_small_conv(&t.0);
    let r = import_set(
        &t.0,
        &[
            "--image-column",
            "sensor_image",
            "--sensor",
            "sensor.toml",
            "--frames-size",
            "16",
        ],
    );
    ok(&r, "import --sensor --frames-size");
    let r = train(&t.0, "conv-mlp", "d", "2", "m", &["--config", "small.toml"]);
    ok(&r, "train conv-mlp");
    let data = read_dataset(&t.join("d")).unwrap();
    let rows = read_dataset_frames(&t.join("d"), &data)
        .unwrap()
        .expect("frames.npy");
    let model = StoredImageModel::load(&t.join("m")).unwrap();
    let recorded = model
        .frames()
        .preprocess
        .as_ref()
        .expect("the model records it");
    assert_eq!(*recorded, sensor.preprocess);
    assert!(recorded.crop.is_some() && recorded.mask.is_some());
    assert_eq!(rows.info.preprocess.as_ref(), Some(recorded));
    assert_eq!(rows.info.source_size, [90, 90]);
    let input = image_input_for(&model).unwrap();
    let plain = tactrace_servo::ImageInput::new(None, (16, 16)).unwrap();
    let mut differs = false;
    for (i, name) in data.meta.images.iter().enumerate() {
        let path = t.join("set/frames").join(name);
        // What the real-frame world hands the perception: the grey frame.
        let grey = tactrace_sensor::read_frame(&path).unwrap();
        assert_eq!(
            input.of_frame(&grey).unwrap(),
            rows.frame(i),
            "follow, row {i}"
        );
        // What `predict --image` reads.
        let file = import_reader::image_input(&input, &path).unwrap();
        assert_eq!(file, rows.frame(i), "predict --image, row {i}");
        differs |= plain.of_frame(&grey).unwrap() != rows.frame(i);
    }
    assert!(
        differs,
        "the preprocessing changed no frame: the test proves nothing"
    );
    // predict --image prints the prediction of the row's frame.
    let first = format!("set/frames/{}", data.meta.images[0]);
    let r = tactrace(&t.0, &["predict", "--model", "m", "--image", &first]);
    ok(&r, "predict --image");
    let values = model.model().predict_targets(rows.frame(0)).unwrap();
    let cells: Vec<String> = values.iter().map(|v| format!("{v:.4}")).collect();
    assert!(
        r.stdout.contains(&cells.join(",")),
        "{}\n{cells:?}",
        r.stdout
    );
    // A --sensor that preprocesses otherwise than the record: refused.
    let r = tactrace(
        &t.0,
        &[
            "predict",
            "--model",
            "m",
            "--image",
            &first,
            "--sensor",
            "uncropped.toml",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("leave out --sensor"), "{}", r.stderr);
}

/// A model folder written before `frames.json` recorded the preprocessing
/// loads, and its frames are made as before: grey as they are, averaged.
#[test]
fn an_image_model_folder_without_the_record_still_loads() {
    let t = TempDir::new("issue22-old");
    write_set(&t.join("set"), 16);
    write_small_conv(&t.0);
    let r = import_set(
        &t.0,
        &["--image-column", "sensor_image", "--frames-size", "16"],
    );
    ok(&r, "import without a sensor file");
    let meta = std::fs::read_to_string(t.join("d/meta.json")).unwrap();
    let meta: serde_json::Value = serde_json::from_str(&meta).unwrap();
    assert!(meta["image_frames"]["height"] == 16, "{meta}");
    assert!(meta["image_frames"].get("preprocess").is_none(), "{meta}");
    let r = train(&t.0, "conv-mlp", "d", "1", "m", &["--config", "small.toml"]);
    ok(&r, "train conv-mlp");
    // frames.json as folders wrote it before the record existed.
    let old = r#"{"file": "frames.npy", "height": 16, "width": 16, "source_size": [96, 96],
                  "layout": "N x H x W uint8 grey"}"#;
    std::fs::write(t.join("m/frames.json"), old).unwrap();
    let model = StoredImageModel::load(&t.join("m")).unwrap();
    assert!(model.frames().preprocess.is_none());
    let input = image_input_for(&model).unwrap();
    assert!(input.preprocess().is_none());
    let data = read_dataset(&t.join("d")).unwrap();
    let rows = read_dataset_frames(&t.join("d"), &data).unwrap().unwrap();
    let grey =
        tactrace_sensor::read_frame(&t.join("set/frames").join(&data.meta.images[2])).unwrap();
    let raw = tactrace_convnet::area_resample(grey.as_raw(), (96, 96), (16, 16));
    assert_eq!(input.of_frame(&grey).unwrap(), raw);
    assert_eq!(raw, rows.frame(2));
    let first = format!("set/frames/{}", data.meta.images[0]);
    let r = tactrace(&t.0, &["predict", "--model", "m", "--image", &first]);
    ok(&r, "predict --image with an old folder");
}
