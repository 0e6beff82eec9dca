//! A sensor whose pins are a few pixels wide, read by the small-pin
//! ("spots") detector, in the servo loop through the binary: a synthetic
//! 127-pin TacTip on concentric rings in 128 x 128 frames (the simulator,
//! frames on disk, no undeformed frame), calibrated with a sensor file
//! naming the small-pin detector, then `collect`, `follow` and `bench`
//! with `--sensor`, for a pin model and for an image model (whose contact
//! check reads the pins with the same detector).
use crate::util;
use std::path::Path;
use tactrace_sensor::{TacTipConfig, TacTipModel};
use tactrace_store::{SensorSummary, SightFile};
use tactrace_vision::{DetectorParams, LayoutKind, PreprocessParams, SpotParams};
use util::{
    calibrate_taps, follows_three_steps, import_taps, ok, tactrace, train, write_small_conv,
    write_taps, TapSpread, TempDir,
};

/// 127 pins on 6 rings, about 3 px wide and 7 px apart in 128 x 128
/// binarised frames.
fn small_pin_sensor() -> TacTipConfig {
    let mut cfg = util::ring_sensor();
    cfg.geometry.pin_radius_mm = 0.7;
    cfg.camera.width = 128;
    cfg.camera.height = 128;
    cfg.camera.centre_px = [63.4, 64.5];
    cfg.camera.focal_px = 39.0;
    cfg
}

/// `n` labelled taps of the small-pin sensor in `dir` (frames/,
/// targets.csv), r over [-5, 25] mm (the lightest barely touch), theta
/// over [-45, 45] deg, and the sensor file reading them (`sensor.toml`:
/// no preprocessing, the small-pin detector).
fn small_pin_taps(dir: &Path, n: usize) {
    let model = TacTipModel::new(small_pin_sensor()).unwrap();
    write_taps(dir, &model, n, &TapSpread::edge(7));
    let file = SightFile {
        sensor: SensorSummary {
            pins: 127,
            layout: LayoutKind::Rings,
            spacing_px: 7.0,
            pin_pixels: 4.0,
            frame_size: [128, 128],
        },
        preprocess: PreprocessParams::default(),
        detect: DetectorParams::Spots(SpotParams {
            level: 127,
            min_pixels: 1,
            max_pixels: 16,
            max_cluster_pixels: 48,
            connectivity: Default::default(),
        }),
    };
    std::fs::write(dir.join("sensor.toml"), file.to_toml()).unwrap();
}

/// Calibrated from the taps (no undeformed frame) with the sensor file:
/// the sensor folder records the small-pin detector.
fn calibrated(t: &TempDir) {
    small_pin_taps(&t.0, 60);
    let run = calibrate_taps(&t.0, "30", &["--sensor", "sensor.toml"]);
    ok(&run, "calibrate");
    let folder = tactrace_store::SensorFolder::read(&t.join("s")).unwrap();
    let sight = folder.spec.sight.expect("the sensor settings recorded");
    assert!(matches!(sight.detect, DetectorParams::Spots(_)));
}

#[test]
fn a_small_pin_sensor_follows_a_disk_and_benches_with_a_pin_model() {
    let t = TempDir::new("small-pins-follow");
    calibrated(&t);
    let run = tactrace(
        &t.0,
        &["collect", "--sensor", "s", "--samples", "40", "--out", "c"],
    );
    ok(&run, "collect");
    ok(&train(&t.0, "pdennn", "c", "1", "m", &[]), "train");
    follows_three_steps(&t.0, "s", "m", "run");
    let run = tactrace(
        &t.0,
        &["bench", "--sensor", "s", "--model", "m", "--taps", "5"],
    );
    ok(&run, "bench");
    assert!(run.stdout.contains("frame -> command"), "{}", run.stdout);
}

/// An image model on the small-pin sensor: its contact check reads the
/// pins with the sensor's small-pin detector over its own rest pins
/// (the blob detector finds none of these pins).
#[test]
fn a_small_pin_sensor_follows_a_disk_with_an_image_model() {
    let t = TempDir::new("small-pins-image");
    calibrated(&t);
    let run = import_taps(
        &t.0,
        &["--sensor", "sensor.toml", "--frames-size", "16"],
        "d",
    );
    ok(&run, "import");
    write_small_conv(&t.0);
    let run = train(&t.0, "conv-mlp", "d", "1", "m", &["--config", "small.toml"]);
    ok(&run, "train");
    follows_three_steps(&t.0, "s", "m", "run");
    let metrics = std::fs::read_to_string(t.join("run/trajectory.csv")).unwrap();
    let header = metrics.lines().next().unwrap();
    let col = header
        .split(',')
        .position(|c| c == "contact")
        .expect(header);
    let touched = metrics
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(col) == Some("true"))
        .count();
    assert!(touched > 0, "no tap made contact:\n{metrics}");
}
