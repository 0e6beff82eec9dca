//! `calibrate` and `twin` through the binary on a sensor with no
//! undeformed frame: a synthetic 127-pin TacTip on concentric rings (the
//! simulator, frames on disk, no `init_0.png`) imported with its rest
//! layout estimated from the taps, then twinned against that dataset
//! (`--reference DATASET`) and calibrated without `--reference`; both
//! report both pin layouts' fits. And the shared 331-pin edge set
//! calibrated with nothing hand-written (fails when the data is absent,
//! unless `TACTRACE_SKIP_REAL_DATA=1`).
mod util;
use rand::{Rng, SeedableRng};
use std::path::Path;
use tactrace_sensor::{EdgeTap, PinLayout, TacTipConfig, TacTipModel};
use util::{tactrace, TempDir};

/// `n` labelled taps of a 127-pin ring sensor in `dir` (frames/,
/// targets.csv), r over [-5, 25] mm (the lightest taps barely touch: the
/// rest layout is estimated from them), theta over [-45, 45] deg.
fn ring_taps(dir: &Path, n: usize) {
    let mut cfg = TacTipConfig::default();
    cfg.geometry.layout = PinLayout::Rings;
    cfg.geometry.ring_phase_deg = (1..=6).map(|k| 2.0 / k as f64).collect();
    let model = TacTipModel::new(cfg).unwrap();
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut csv = String::from("image_name,pose_2,pose_6\n");
    for k in 0..n {
        let tap = EdgeTap {
            r_mm: rng.random_range(-5.0..25.0),
            theta_deg: rng.random_range(-45.0..45.0),
            ..EdgeTap::default()
        };
        let name = format!("frame_{k}_0.png");
        let pins = model.edge_tap_pins(&tap);
        model
            .render(&pins, Some(&mut rng))
            .save(frames.join(&name))
            .unwrap();
        csv.push_str(&format!("{name},{},{}\n", tap.r_mm, tap.theta_deg));
    }
    std::fs::write(dir.join("targets.csv"), csv).unwrap();
}

fn reference_pins(dataset: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dataset.join("meta.json")).unwrap();
    let meta: serde_json::Value = serde_json::from_str(&text).unwrap();
    meta["reference_pins"].clone()
}

/// Both layouts named, the rings kept.
fn names_both_layouts(stderr: &str) {
    assert!(
        stderr.contains("concentric rings kept") && stderr.contains("hexagonal lattice"),
        "{stderr}"
    );
    assert!(!stderr.contains("lattice kept"), "{stderr}");
}

#[test]
fn issue21_twin_with_a_dataset_reference_writes_the_datasets_pin_order() {
    let t = TempDir::new("twin-dataset");
    ring_taps(&t.0, 60);
    let plain = ["--dz-column", "none", "--shear-columns", "none"];
    let run = tactrace(
        &t.0,
        &[
            "import",
            "--frames",
            "frames",
            "--targets",
            "targets.csv",
            "--out",
            "ds",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let pins = reference_pins(&t.join("ds"));
    assert_eq!(pins.as_array().unwrap().len(), 127);
    let mut args = vec![
        "twin",
        "--reference",
        "ds",
        "--targets",
        "targets.csv",
        "--out",
        "tw",
    ];
    args.extend(plain);
    let run = tactrace(&t.0, &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    names_both_layouts(&run.stderr);
    assert_eq!(reference_pins(&t.join("tw")), pins);
    // Neither a reference nor a calibrated sensor: bad input, saying what to give.
    let run = tactrace(
        &t.0,
        &["twin", "--targets", "targets.csv", "--out", "tw-none"],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(run.stderr.contains("--reference DATASET"), "{}", run.stderr);
}

#[test]
fn issue21_calibrate_without_an_undeformed_frame_then_twin_in_its_pin_order() {
    let t = TempDir::new("calibrate-estimated");
    ring_taps(&t.0, 80);
    let plain = ["--dz-column", "none", "--shear-columns", "none"];
    let mut args = vec![
        "calibrate",
        "--frames",
        "frames",
        "--targets",
        "targets.csv",
        "--samples",
        "40",
        "--out",
        "s",
    ];
    args.extend(plain);
    let run = tactrace(&t.0, &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("no --reference: estimated the rest layout (127 pins)"),
        "{}",
        run.stderr
    );
    names_both_layouts(&run.stderr);
    let toml = std::fs::read_to_string(t.join("s/sensor.toml")).unwrap();
    assert!(toml.contains("layout = \"rings\""), "{toml}");
    // The calibrated sensor's twin, no --reference: its own rest pins,
    // which an import of the same taps estimates alike.
    let mut args = vec![
        "twin",
        "--sensor",
        "s",
        "--targets",
        "targets.csv",
        "--out",
        "tw",
    ];
    args.extend(plain);
    let run = tactrace(&t.0, &args);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let run = tactrace(
        &t.0,
        &[
            "import",
            "--frames",
            "frames",
            "--targets",
            "targets.csv",
            "--out",
            "ds",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert_eq!(reference_pins(&t.join("tw")), reference_pins(&t.join("ds")));
}

/// The field RMS before and after on the held-out taps, from calibrate's
/// report line `held-out taps (N): field RMS a -> b px, ...`.
fn held_out_rms(output: &str) -> (f64, f64) {
    let line = output
        .lines()
        .find(|l| l.contains("field RMS"))
        .unwrap_or_else(|| panic!("no field RMS line: {output}"));
    let rest = line.split("field RMS ").nth(1).unwrap();
    let mut words = rest.split_whitespace();
    let before: f64 = words.next().unwrap().parse().unwrap();
    words.next();
    let after: f64 = words.next().unwrap().parse().unwrap();
    (before, after)
}

#[test]
fn issue21_the_shared_331_pin_set_calibrates_with_nothing_hand_written() {
    let Some(set) = tactrace_testdata::shared_set("tactip331-edge2d-shear", "train/targets.csv")
    else {
        return;
    };
    let t = TempDir::new("calibrate-331");
    let frames = set.join("train/frames");
    let frames = frames.to_str().unwrap();
    // Every 12th row (417 taps over the whole circle; the file is sorted
    // by angle).
    let text = std::fs::read_to_string(set.join("train/targets.csv")).unwrap();
    let mut lines = text.lines();
    let mut part = format!("{}\n", lines.next().unwrap());
    for line in lines.step_by(12) {
        part.push_str(line);
        part.push('\n');
    }
    let targets = t.join("part.csv");
    std::fs::write(&targets, part).unwrap();
    let run = tactrace(&t.0, &["sensor", "inspect", frames, "--out", "s331.toml"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let run = tactrace(
        &t.0,
        &[
            "calibrate",
            "--frames",
            frames,
            "--targets",
            targets.to_str().unwrap(),
            "--image-column",
            "sensor_image",
            "--target",
            "pose_2:mm",
            "--target",
            "pose_6:deg:circular",
            "--dz-column",
            "none",
            "--sensor",
            "s331.toml",
            "--samples",
            "100",
            "--out",
            "s",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr.contains("estimated the rest layout (331 pins)"),
        "{}",
        run.stderr
    );
    names_both_layouts(&run.stderr);
    // Its label convention is not the simulator's: the angle turns the
    // other way (docs/results.md, "The 331-pin simulator").
    assert!(
        run.stderr
            .contains("label convention (estimated from the taps, 100 taps): angle sign -1"),
        "{}",
        run.stderr
    );
    let (before, after) = held_out_rms(&format!("{}{}", run.stdout, run.stderr));
    assert!(
        after < 0.6 * before && before < 1.3,
        "{before} -> {after} px"
    );
}

#[test]
fn issue21_a_sensor_calibrated_without_an_undeformed_frame_collects_and_follows() {
    let t = TempDir::new("sensor-estimated-runs");
    ring_taps(&t.0, 60);
    let run = tactrace(
        &t.0,
        &[
            "calibrate",
            "--frames",
            "frames",
            "--targets",
            "targets.csv",
            "--samples",
            "30",
            "--out",
            "s",
            "--dz-column",
            "none",
            "--shear-columns",
            "none",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let sensor = tactrace_store::SensorFolder::read(&t.join("s")).unwrap();
    // Its taps are read against its own (estimated) rest pins, in their
    // order, not against the pins a detector finds in reference.png (the
    // simulator's rest frame).
    let run = tactrace(
        &t.0,
        &["collect", "--sensor", "s", "--samples", "40", "--out", "c"],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let pins: Vec<[f64; 2]> = serde_json::from_value(reference_pins(&t.join("c"))).unwrap();
    assert_eq!(pins, sensor.spec.reference_pins);
    let run = tactrace(
        &t.0,
        &[
            "train", "--model", "pdennn", "--train", "c", "--epochs", "1", "--out", "m",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let run = tactrace(
        &t.0,
        &[
            "follow", "--sensor", "s", "--model", "m", "--shape", "disk", "--steps", "3", "--out",
            "run",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    let trajectory = std::fs::read_to_string(t.join("run/trajectory.csv")).unwrap();
    assert_eq!(trajectory.lines().count(), 4, "{trajectory}");
}

/// A 127-pin sensor (undeformed frame given) whose labels turn against
/// the simulator's angle, start a quarter turn away and put the object on
/// the other side: `calibrate` finds the convention from the taps, says
/// so and records it in `sensor.toml`.
#[test]
fn issue21_calibrate_estimates_and_records_the_label_convention() {
    let t = TempDir::new("calibrate-convention");
    let own = TacTipConfig::default();
    let mut truth = own.clone();
    truth.calibration.angle_scale = -1.0;
    truth.calibration.angle_offset_deg += 90.0;
    truth.calibration.object_side = -own.calibration.object_side;
    let model = TacTipModel::new(truth).unwrap();
    let frames = t.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    model
        .render(model.rest_pins(), None)
        .save(frames.join("init_0.png"))
        .unwrap();
    let mut csv = String::from("image_name,pose_2,pose_6\n");
    for k in 0..50 {
        let tap = EdgeTap {
            r_mm: rng.random_range(-3.0..3.0),
            theta_deg: rng.random_range(-180.0..180.0),
            ..EdgeTap::default()
        };
        let name = format!("frame_{k}_0.png");
        let pins = model.edge_tap_pins(&tap);
        model.render(&pins, None).save(frames.join(&name)).unwrap();
        csv.push_str(&format!("{name},{},{}\n", tap.r_mm, tap.theta_deg));
    }
    std::fs::write(t.join("targets.csv"), csv).unwrap();
    let run = tactrace(
        &t.0,
        &[
            "calibrate",
            "--frames",
            "frames",
            "--targets",
            "targets.csv",
            "--reference",
            "frames/init_0.png",
            "--dz-column",
            "none",
            "--shear-columns",
            "none",
            "--samples",
            "30",
            "--out",
            "s",
        ],
    );
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr.contains(
            "label convention (estimated from the taps, 30 taps): angle sign -1, position sign -1"
        ),
        "{}",
        run.stderr
    );
    let text = std::fs::read_to_string(t.join("s/sensor.toml")).unwrap();
    let spec: toml::Value = toml::from_str(&text).unwrap();
    let conv = &spec["convention"];
    assert_eq!(conv["kept_own"].as_bool(), Some(false), "{text}");
    let chosen = &conv["chosen"];
    assert_eq!(chosen["angle_sign"].as_float(), Some(-1.0), "{text}");
    let want = tactrace_sensor::wrap_deg(own.calibration.angle_offset_deg + 270.0);
    let got = chosen["angle_offset_deg"].as_float().unwrap();
    assert!(
        tactrace_sensor::wrap_deg(got - want).abs() < 5.0,
        "{got} for {want}"
    );
    // The simulator it writes is set to the convention found.
    let cal = &spec["sensor"]["calibration"];
    assert!(cal["angle_scale"].as_float().unwrap() < 0.0, "{text}");
    assert!((cal["angle_offset_deg"].as_float().unwrap() - got).abs() < 1e-9);
}
