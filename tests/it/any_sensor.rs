//! A user's own TacTip from raw frames, end to end through the binary:
//! `sensor inspect` on synthetic sensors of both layouts (331 pins on
//! concentric rings in 128 x 128 frames, 127 pins on a hexagonal lattice
//! in 256 x 256 frames) writes a sensor file that `import` reads with no
//! undeformed frame (the rest layout estimated from the taps), every frame
//! fully tracked and counted in meta.json; a raw colour camera frame with
//! no sensor file fails before anything is read, naming `sensor inspect`;
//! and the shared 331-pin set imports with nothing hand-written.
use crate::util;
use image::{GrayImage, Luma, Rgb, RgbImage};
use std::path::Path;
use tactrace_testdata::layouts::{hex_sensor, ring_sensor, SyntheticSensor};
use util::{tactrace, TempDir};

/// A small deterministic generator (no seed file, no dependency).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

/// Tap `k`'s pins: a smooth push away from a random contact point (tap 0
/// and every fourth tap barely touch), and its labels.
fn tap(s: &SyntheticSensor, rng: &mut Lcg, k: usize) -> (Vec<[f64; 2]>, [f64; 2]) {
    let scale = s.rim[0] / 55.0;
    let (r, t) = (rng.range(0.0, 0.5 * s.rim[0]), rng.range(-3.1, 3.1));
    let at = [s.centre[0] + r * t.cos(), s.centre[1] + r * t.sin()];
    let width = scale * rng.range(10.0, 16.0);
    let push = if k.is_multiple_of(4) { 0.1 } else { 1.0 } * scale * rng.range(0.0, 3.0);
    let pins = s
        .rest
        .iter()
        .map(|p| {
            let (dx, dy) = (p[0] - at[0], p[1] - at[1]);
            let g = (-(dx * dx + dy * dy) / (2.0 * width * width)).exp() / width;
            [p[0] + g * push * dx, p[1] + g * push * dy]
        })
        .collect();
    (pins, [r / scale / 5.0, t.to_degrees()])
}

/// The binary frame of `pins` (white pins and rim arcs on black).
fn render(s: &SyntheticSensor, pins: &[[f64; 2]]) -> GrayImage {
    GrayImage::from_fn(s.size, s.size, |x, y| {
        let (x, y) = (f64::from(x), f64::from(y));
        let on_pin = pins
            .iter()
            .any(|p| (p[0] - x).hypot(p[1] - y) <= s.pin_radius);
        let d = (x - s.centre[0]).hypot(y - s.centre[1]);
        let arc = (y - s.centre[1]).atan2(x - s.centre[0]).rem_euclid(1.0) > 0.15;
        let on_rim = d >= s.rim[0] && d <= s.rim[1] && arc;
        Luma([if on_pin || on_rim { 255 } else { 0 }])
    })
}

/// `n` taps of `s` as frames/image_K.png and targets.csv in `dir`.
fn write_set(s: &SyntheticSensor, dir: &Path, n: usize) {
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let mut csv = String::from("sensor_image,pose_2,pose_6\n");
    let mut rng = Lcg(7);
    for k in 0..n {
        let (pins, [r, theta]) = tap(s, &mut rng, k);
        let name = format!("image_{}.png", k + 1);
        render(s, &pins).save(frames.join(&name)).unwrap();
        csv.push_str(&format!("{name},{r:.4},{theta:.4}\n"));
    }
    std::fs::write(dir.join("targets.csv"), csv).unwrap();
}

fn meta(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("meta.json")).unwrap()).unwrap()
}

/// Inspects the set in `tmp/set` and imports it with no reference;
/// returns the sensor file's text and the dataset's meta.json.
fn inspect_and_import(tmp: &TempDir, n: usize) -> (String, serde_json::Value) {
    let run = tactrace(
        &tmp.0,
        &[
            "sensor",
            "inspect",
            "set/frames",
            "--out",
            "sensor.toml",
            "--picture",
            "found.png",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(tmp.join("found.png").is_file());
    let text = std::fs::read_to_string(tmp.join("sensor.toml")).unwrap();
    // Nothing overwritten without --force.
    let again = tactrace(
        &tmp.0,
        &["sensor", "inspect", "set/frames", "--out", "sensor.toml"],
    );
    assert_eq!(again.code, 2, "{}", again.stderr);
    assert!(again.stderr.contains("--force"), "{}", again.stderr);
    let run = tactrace(
        &tmp.0,
        &[
            "import",
            "--frames",
            "set/frames",
            "--targets",
            "set/targets.csv",
            "--image-column",
            "sensor_image",
            "--sensor",
            "sensor.toml",
            "--out",
            "data",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("no --reference: estimated the rest layout")
            && run.stderr.contains("residual"),
        "{}",
        run.stderr
    );
    assert!(
        run.stderr
            .contains(&format!("fully tracked {n} of {n} (100.00%)")),
        "{}",
        run.stderr
    );
    (text, meta(&tmp.join("data")))
}

fn check_counts(m: &serde_json::Value, n: usize, pins: usize) {
    assert_eq!(m["frames_total"], n, "{m}");
    assert_eq!(m["frames_fully_tracked"], n, "{m}");
    assert_eq!(m["pins_filled"], 0, "{m}");
    let found = m["pins_matched"].as_u64().unwrap() + m["pins_split"].as_u64().unwrap();
    assert_eq!(found as usize, n * pins, "{m}");
    let est = &m["settings"]["import"]["reference"]["estimated"];
    assert_eq!(est["pins"].as_array().unwrap().len(), pins, "{m}");
    assert!(est["residual_px"].as_f64().unwrap() < 0.5, "{est}");
}

#[test]
fn inspect_on_a_ring_sensor_writes_a_sensor_file_import_reads_with_no_reference() {
    let tmp = TempDir::new("rings");
    let s = ring_sensor();
    write_set(&s, &tmp.join("set"), 40);
    let (text, m) = inspect_and_import(&tmp, 40);
    assert!(text.contains("pins = 331"), "{text}");
    assert!(text.contains("layout = \"rings\""), "{text}");
    assert!(text.contains("kind = \"spots\""), "{text}");
    assert!(text.contains("[preprocess.mask]"), "{text}");
    check_counts(&m, 40, 331);
    // The dataset's rest pins are the truth's, to a fraction of a pixel
    // (the nearest estimated pin of every true pin).
    let est: Vec<[f64; 2]> = serde_json::from_value(m["reference_pins"].clone()).unwrap();
    for p in &s.rest {
        let d = est
            .iter()
            .map(|q| (q[0] - p[0]).hypot(q[1] - p[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(d < 0.6, "true pin {p:?} is {d} px from the estimate");
    }
}

#[test]
fn inspect_on_a_lattice_sensor_writes_a_sensor_file_import_reads_with_no_reference() {
    let tmp = TempDir::new("lattice");
    write_set(&hex_sensor(), &tmp.join("set"), 30);
    let (text, m) = inspect_and_import(&tmp, 30);
    assert!(text.contains("pins = 127"), "{text}");
    assert!(text.contains("layout = \"hexagonal\""), "{text}");
    check_counts(&m, 30, 127);
    // Another split read against the same rest pins: --reference DATASET.
    let run = tactrace(
        &tmp.0,
        &[
            "import",
            "--frames",
            "set/frames",
            "--targets",
            "set/targets.csv",
            "--image-column",
            "sensor_image",
            "--reference",
            "data",
            "--out",
            "again",
            "--limit",
            "10",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        !run.stderr.contains("estimated the rest layout"),
        "{}",
        run.stderr
    );
    let again = meta(&tmp.join("again"));
    assert_eq!(again["reference_pins"], m["reference_pins"]);
    assert_eq!(again["frames_fully_tracked"], 10, "{again}");
}

#[test]
fn a_raw_colour_frame_with_no_sensor_file_fails_early_suggesting_sensor_inspect() {
    let tmp = TempDir::new("colour");
    let frames = tmp.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let mut csv = String::from("image_name,pose_2,pose_6\n");
    for k in 0..3 {
        let img = RgbImage::from_fn(640, 480, |x, y| {
            Rgb([(x % 256) as u8, (y % 256) as u8, ((x + y + k) % 256) as u8])
        });
        img.save(frames.join(format!("f{k}.png"))).unwrap();
        csv.push_str(&format!("f{k}.png,0.0,0.0\n"));
    }
    std::fs::write(tmp.join("targets.csv"), csv).unwrap();
    for reference in [None, Some("frames/f0.png")] {
        let mut args = vec![
            "import",
            "--frames",
            "frames",
            "--targets",
            "targets.csv",
            "--out",
            "data",
        ];
        if let Some(r) = reference {
            args.extend(["--reference", r]);
        }
        let run = tactrace(&tmp.0, &args);
        assert_eq!(run.code, 2, "{}", run.stderr);
        assert!(
            run.stderr.contains("colour 640 x 480 camera image")
                && run.stderr.contains("tactrace sensor inspect")
                && run.stderr.contains("--sensor"),
            "{}",
            run.stderr
        );
        assert!(!tmp.join("data").exists());
    }
}

#[test]
fn the_shared_331_pin_set_imports_fully_tracked_with_nothing_hand_written() {
    let Some(set) = tactrace_testdata::shared_set("tactip331-edge2d-shear", "train/targets.csv")
    else {
        return;
    };
    let tmp = TempDir::new("shared331");
    let frames = set.join("train/frames").display().to_string();
    let targets = set.join("train/targets.csv").display().to_string();
    let run = tactrace(&tmp.0, &["sensor", "inspect", &frames, "--out", "s.toml"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let run = tactrace(
        &tmp.0,
        &[
            "import",
            "--frames",
            &frames,
            "--targets",
            &targets,
            "--image-column",
            "sensor_image",
            "--sensor",
            "s.toml",
            "--limit",
            "300",
            "--out",
            "data",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let m = meta(&tmp.join("data"));
    let (total, full) = (
        m["frames_total"].as_u64().unwrap(),
        m["frames_fully_tracked"].as_u64().unwrap(),
    );
    assert_eq!((total, m["pins"].as_u64().unwrap()), (300, 331), "{m}");
    assert!(full * 100 >= total * 99, "{full} of {total} fully tracked");
}
