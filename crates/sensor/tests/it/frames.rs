//! Rendering, the simulated and replay sensors, and frame reading.
use crate::common;
use common::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::PathBuf;
use tactrace_geometry::Pose;
use tactrace_sensor::{
    read_frame, ReplaySensor, SensorError, SimTacTip, TacTipConfig, TacTipModel, TactileSensor,
};

fn nearest(points: &[[f64; 2]], p: [f64; 2]) -> f64 {
    points
        .iter()
        .map(|q| (q[0] - p[0]).hypot(q[1] - p[1]))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn rendered_pins_are_found_again_by_centroids() {
    // The anti-aliased grey frame (before the camera's binarisation).
    let mut cfg = plain_model().config().clone();
    cfg.camera.binarise_above = None;
    let model = TacTipModel::new(cfg).expect("valid config");
    let object = square([0.0, -30.0], 30.0);
    for pins in [
        model.rest_pins().to_vec(),
        model.pins(&object, tap(0.0, 1.0, 3.0, 20.0), None),
    ] {
        let frame = model.render(&pins, None);
        assert_eq!(frame.dimensions(), model.image_size());
        let found = centroids(&frame);
        assert_eq!(found.len(), pins.len(), "one blob per pin");
        for (weighted, thresholded) in &found {
            assert!(
                nearest(&pins, *weighted) < 0.1,
                "weighted centroid {weighted:?}"
            );
            // Thresholding a ~2 px disc quantises its centroid: up to
            // ~1/3 px off depending on the sub-pixel position.
            assert!(
                nearest(&pins, *thresholded) < 0.35,
                "thresholded centroid {thresholded:?} weighted {weighted:?} d {}",
                nearest(&pins, *thresholded)
            );
        }
    }
}

#[test]
fn pin_areas_match_the_real_frames() {
    // Real 256 x 256 frames: pins cover about 15-60 px^2, growing outwards.
    let model = TacTipModel::new(TacTipConfig::default()).expect("default model");
    let radii = model.pin_radii();
    let area = |r: f64| std::f64::consts::PI * r * r;
    assert!(
        (10.0..25.0).contains(&area(radii[0])),
        "centre pin area {}",
        area(radii[0])
    );
    let outer = area(*radii.last().expect("pins"));
    assert!((35.0..75.0).contains(&outer), "outer pin area {outer}");
}

#[test]
fn nuisance_is_seeded_and_bounded() {
    let mut cfg = TacTipConfig::default();
    cfg.nuisance.pin_jitter_px = 0.3;
    cfg.nuisance.image_noise_std = 5.0;
    let model = TacTipModel::new(cfg).expect("valid");
    let pins = model.rest_pins().to_vec();
    let a = model.render(&pins, Some(&mut ChaCha8Rng::seed_from_u64(7)));
    let b = model.render(&pins, Some(&mut ChaCha8Rng::seed_from_u64(7)));
    let c = model.render(&pins, Some(&mut ChaCha8Rng::seed_from_u64(8)));
    assert_eq!(a, b);
    assert_ne!(a, c);
    let clean = model.render(&pins, None);
    let diff: f64 = a
        .iter()
        .zip(clean.iter())
        .map(|(x, y)| (*x as f64 - *y as f64).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    assert!(
        diff.sqrt() > 3.0 && diff.sqrt() < 40.0,
        "rms grey difference {}",
        diff.sqrt()
    );
}

#[test]
fn sim_tactip_without_contact_captures_the_reference_frame() {
    let mut cfg = TacTipConfig::default();
    cfg.nuisance.pin_jitter_px = 0.0;
    let model = TacTipModel::new(cfg).expect("valid");
    let mut sim = SimTacTip::new(
        model,
        square([0.0, 0.0], 20.0),
        Box::new(|| Pose::planar(0.0, 0.0, 5.0, 0.0)),
        3,
    );
    let frame = sim.capture().expect("capture");
    assert_eq!(frame, sim.reference_frame());
}

#[test]
fn sim_tactip_in_contact_differs_from_reference() {
    let model = TacTipModel::new(TacTipConfig::default()).expect("valid");
    let mut sim = SimTacTip::new(
        model,
        square([0.0, -20.0], 20.0),
        Box::new(|| Pose::planar(0.0, 0.0, -3.0, 0.0)),
        3,
    );
    let frame = sim.capture().expect("capture");
    assert_ne!(frame, sim.reference_frame());
}

fn temp_dir(name: &str) -> PathBuf {
    tempfile::Builder::new()
        .prefix(&format!("tactrace-sensor-{name}-"))
        .tempdir()
        .expect("temp dir")
        .keep()
}

#[test]
fn replay_returns_saved_frames_in_order_then_errors() {
    let dir = temp_dir("replay");
    let model = plain_model();
    let object = square([0.0, -30.0], 30.0);
    let frames = [
        model.render(model.rest_pins(), None),
        model.render(&model.pins(&object, tap(0.0, 0.0, 3.0, 0.0), None), None),
    ];
    let paths: Vec<PathBuf> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let p = dir.join(format!("f{i}.png"));
            f.save(&p).expect("save");
            p
        })
        .collect();
    let mut replay = ReplaySensor::new(paths);
    assert_eq!(replay.capture().expect("first"), frames[0]);
    assert_eq!(replay.capture().expect("second"), frames[1]);
    assert!(matches!(
        replay.capture(),
        Err(SensorError::ReplayExhausted { count: 2 })
    ));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn read_frame_converts_colour_and_names_bad_files() {
    let dir = temp_dir("read");
    let colour = image::RgbImage::from_pixel(4, 3, image::Rgb([255, 255, 255]));
    let colour_path = dir.join("colour.png");
    colour.save(&colour_path).expect("save");
    let grey = read_frame(&colour_path).expect("colour frame reads");
    assert_eq!((grey.dimensions(), grey.get_pixel(0, 0)[0]), ((4, 3), 255));

    let missing = dir.join("missing.png");
    let err = read_frame(&missing).expect_err("missing");
    assert!(
        matches!(err, SensorError::FrameMissing { .. }) && err.to_string().contains("missing.png")
    );

    let text = dir.join("notes.png");
    std::fs::write(&text, "not an image at all").expect("write");
    let err = read_frame(&text).expect_err("text");
    assert!(
        matches!(err, SensorError::NotAnImage { .. }) && err.to_string().contains("notes.png"),
        "{err}"
    );

    let mut bytes = Vec::new();
    std::fs::File::open(&colour_path)
        .and_then(|mut f| std::io::Read::read_to_end(&mut f, &mut bytes))
        .expect("read back");
    bytes.truncate(bytes.len() / 2);
    let corrupt = dir.join("corrupt.png");
    std::fs::write(&corrupt, &bytes).expect("write");
    let err = read_frame(&corrupt).expect_err("corrupt");
    assert!(
        matches!(
            err,
            SensorError::CorruptFrame { .. } | SensorError::FrameUnreadable { .. }
        ),
        "{err}"
    );
    assert!(err.to_string().contains("corrupt.png"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Per-tap cost of pins + render (run with --ignored --nocapture).
#[test]
#[ignore]
fn timing_of_pins_and_render() {
    let model = TacTipModel::new(TacTipConfig::default()).expect("valid");
    let object = square([0.0, -30.0], 30.0);
    let n = 2000;
    let start = std::time::Instant::now();
    let mut pins = Vec::new();
    for k in 0..n {
        pins = model.pins(
            &object,
            tap(0.0, (k % 10) as f64 * 0.3, 3.0, k as f64 % 45.0),
            None,
        );
    }
    let t_pins = start.elapsed().as_secs_f64() / n as f64;
    let start = std::time::Instant::now();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..n {
        let _ = model.render(&pins, Some(&mut rng));
    }
    let t_render = start.elapsed().as_secs_f64() / n as f64;
    println!(
        "pins {:.1} us/tap, render {:.1} us/frame",
        t_pins * 1e6,
        t_render * 1e6
    );
}
