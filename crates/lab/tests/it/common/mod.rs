//! Test fixtures shared by the lab's integration tests: a synthetic "real"
//! TacTip (the simulator with a known field distortion) and its labelled
//! taps on a straight edge, in the Bristol layout.
#![allow(dead_code)]
pub mod fake_rig;

use rand::{Rng, SeedableRng};
use std::path::Path;
use tactrace_sensor::{EdgeTap, FieldCorrection, TacTipConfig, TacTipModel};
use tactrace_store::collection::TapColumns;
use tactrace_store::LabelledCollection;

pub const PINS: usize = 127;

/// A known distortion: every displacement 30 % larger, x and y mixed a
/// little, a constant 0.4 px shift in x.
pub fn distortion() -> FieldCorrection {
    distortion_of(PINS)
}

/// [`distortion`] for a sensor of `pins` pins.
pub fn distortion_of(pins: usize) -> FieldCorrection {
    let d = 2 * pins;
    let mut w = vec![0.0f32; d * d];
    for k in 0..d {
        w[k * d + k] = 0.3;
        w[k * d + (k + pins) % d] = 0.1;
    }
    let b = (0..d).map(|k| if k < pins { 0.4 } else { 0.0 }).collect();
    FieldCorrection::new(pins, w, b).unwrap()
}

/// `n` labelled taps of the distorted sensor in `dir` (frames/, targets.csv,
/// frames/init_0.png), labels spread over r in [-5, 5] mm and theta in
/// [-45, 45] deg, as a collection without depth or shear columns.
pub fn distorted_sensor_set(dir: &Path, n: usize) -> LabelledCollection {
    sensor_set(dir, n, TacTipConfig::default())
}

/// As [`distorted_sensor_set`] for the sensor `sensor` (any layout).
pub fn sensor_set(dir: &Path, n: usize, sensor: TacTipConfig) -> LabelledCollection {
    sensor_set_over(dir, n, sensor, 5.0)
}

/// As [`sensor_set`] with r spread over [-5, `r_max`] mm (a larger
/// `r_max` adds light taps, from which a rest layout can be estimated).
pub fn sensor_set_over(
    dir: &Path,
    n: usize,
    sensor: TacTipConfig,
    r_max: f64,
) -> LabelledCollection {
    let plain = TacTipModel::new(sensor.clone()).unwrap();
    let pins = plain.rest_pins().len();
    let real = TacTipModel::with_rest_pins(sensor, plain.rest_pins().to_vec())
        .unwrap()
        .with_correction(distortion_of(pins))
        .unwrap();
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let reference = frames.join("init_0.png");
    real.render(real.rest_pins(), None)
        .save(&reference)
        .unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut csv = String::from("image_name,pose_2,pose_6\n");
    for k in 0..n {
        let tap = EdgeTap {
            r_mm: rng.random_range(-5.0..r_max),
            theta_deg: rng.random_range(-45.0..45.0),
            dz_mm: 0.0,
            shear: None,
        };
        let pins = real.seen_pins(real.edge_tap_pins(&tap));
        let name = format!("frame_{k}_0.png");
        real.render(&pins, Some(&mut rng))
            .save(frames.join(&name))
            .unwrap();
        csv.push_str(&format!("{name},{},{}\n", tap.r_mm, tap.theta_deg));
    }
    let targets = dir.join("targets.csv");
    std::fs::write(&targets, csv).unwrap();
    LabelledCollection::new(frames, targets, reference).with_tap(TapColumns::default())
}

/// A calibration of `collection` on `samples` taps, seed 1 (replayed taps
/// rendered with seed 1), nothing else asked.
pub fn calibration(
    collection: LabelledCollection,
    samples: usize,
) -> tactrace_lab::calibrate::CalibrateConfig {
    tactrace_lab::calibrate::CalibrateConfig {
        collection,
        render_seed: 1,
        samples: Some(samples),
        seed: 1,
        allowed_rows: None,
        score_rows: None,
        fit_physics: false,
        labelled_depth: false,
        pin_jitter: Default::default(),
    }
}
