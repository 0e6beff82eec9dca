//! `calibrate` and `twin` through the binary on a sensor with no
//! undeformed frame: a synthetic 127-pin TacTip on concentric rings (the
//! simulator, frames on disk, no `init_0.png`) imported with its rest
//! layout estimated from the taps, then twinned against that dataset
//! (`--reference DATASET`) and calibrated without `--reference`; both
//! report both pin layouts' fits. And the shared 331-pin edge set
//! calibrated with nothing hand-written (fails when the data is absent,
//! unless `TACTRACE_SKIP_REAL_DATA=1`).
use crate::util;
use tactrace_sensor::{TacTipConfig, TacTipModel};
use util::{
    calibrate_taps, follows_three_steps, import_taps, ok, reference_pins, tactrace, train,
    write_taps, TapSpread, TempDir,
};

/// `n` labelled taps of a 127-pin ring sensor in `dir` (frames/,
/// targets.csv), r over [-5, 25] mm (the lightest taps barely touch: the
/// rest layout is estimated from them), theta over [-45, 45] deg.
fn ring_taps(dir: &std::path::Path, n: usize) {
    let model = TacTipModel::new(util::ring_sensor()).unwrap();
    write_taps(dir, &model, n, &TapSpread::edge(5));
}

/// `tactrace twin` of the taps' labels (`targets.csv`, plain edge
/// labels) into `tw`, with `extra` arguments.
fn twin_taps(dir: &std::path::Path, extra: &[&str]) -> util::Run {
    let mut args = vec!["twin", "--targets", "targets.csv", "--out", "tw"];
    args.extend(extra);
    args.extend(["--dz-column", "none", "--shear-columns", "none"]);
    tactrace(dir, &args)
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
fn twin_with_a_dataset_reference_writes_the_datasets_pin_order() {
    let t = TempDir::new("twin-dataset");
    ring_taps(&t.0, 60);
    ok(&import_taps(&t.0, &[], "ds"), "import");
    let pins = reference_pins(&t.join("ds"));
    assert_eq!(pins.as_array().unwrap().len(), 127);
    let run = twin_taps(&t.0, &["--reference", "ds"]);
    ok(&run, "twin --reference DATASET");
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
fn calibrate_without_an_undeformed_frame_then_twin_in_its_pin_order() {
    let t = TempDir::new("calibrate-estimated");
    ring_taps(&t.0, 80);
    let run = calibrate_taps(&t.0, "40", &[]);
    ok(&run, "calibrate");
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
    ok(&twin_taps(&t.0, &["--sensor", "s"]), "twin --sensor");
    ok(&import_taps(&t.0, &[], "ds"), "import");
    assert_eq!(reference_pins(&t.join("tw")), reference_pins(&t.join("ds")));
    a_twin_holds_out_whole_taps(&t.0);
}

/// `train --val-fraction` on the twin `tw` (80 label rows rendered three
/// times each, and the 40 calibration taps) holds out every copy of its
/// taps, says so, and warns of
/// no copies; `validate --val-fraction` scores those rows, none of them
/// seen in training.
fn a_twin_holds_out_whole_taps(dir: &std::path::Path) {
    let split = ["--val-fraction", "0.25", "--split-seed", "2"];
    let run = train(dir, "pdennn", "tw", "2", "m-tw", &split);
    ok(&run, "train --val-fraction on a twin");
    assert!(
        run.stderr.contains("every copy of 30 of the 120 taps"),
        "{}",
        run.stderr
    );
    assert!(
        !run.stderr.contains("show a tap that training"),
        "{}",
        run.stderr
    );
    let rec = util::json(&std::fs::read_to_string(dir.join("m-tw/training.json")).unwrap());
    assert_eq!(rec["split"]["unit"], "tap", "{rec}");
    assert_eq!(rec["split"]["rows"].as_array().unwrap().len(), 70);
    let args = [
        &["validate", "--model", "m-tw", "--data", "tw", "--json"],
        &split[..],
    ];
    let run = tactrace(dir, &args.concat());
    ok(&run, "validate --val-fraction on a twin");
    let v = util::json(&run.stdout);
    assert_eq!(v["rows_seen_in_training"], 0, "{}", run.stdout);
    assert_eq!(v["samples"], 70, "{}", run.stdout);
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
fn the_shared_331_pin_set_calibrates_with_nothing_hand_written() {
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
    ok(&run, "sensor inspect");
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
    ok(&run, "calibrate");
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
fn a_sensor_calibrated_without_an_undeformed_frame_collects_and_follows() {
    let t = TempDir::new("sensor-estimated-runs");
    ring_taps(&t.0, 60);
    ok(&calibrate_taps(&t.0, "30", &[]), "calibrate");
    let sensor = tactrace_store::SensorFolder::read(&t.join("s")).unwrap();
    // Its taps are read against its own (estimated) rest pins, in their
    // order, not against the pins a detector finds in reference.png (the
    // simulator's rest frame).
    let run = tactrace(
        &t.0,
        &["collect", "--sensor", "s", "--samples", "40", "--out", "c"],
    );
    ok(&run, "collect");
    let pins: Vec<[f64; 2]> = serde_json::from_value(reference_pins(&t.join("c"))).unwrap();
    assert_eq!(pins, sensor.spec.reference_pins);
    ok(&train(&t.0, "pdennn", "c", "1", "m", &[]), "train");
    follows_three_steps(&t.0, "s", "m", "run");
}

/// A 127-pin sensor (undeformed frame given) whose labels turn against
/// the simulator's angle, start a quarter turn away and put the object on
/// the other side: `calibrate` finds the convention from the taps, says
/// so and records it in `sensor.toml`.
#[test]
fn calibrate_estimates_and_records_the_label_convention() {
    let t = TempDir::new("calibrate-convention");
    let own = TacTipConfig::default();
    let mut truth = own.clone();
    truth.calibration.angle_scale = -1.0;
    truth.calibration.angle_offset_deg += 90.0;
    truth.calibration.object_side = -own.calibration.object_side;
    let model = TacTipModel::new(truth).unwrap();
    std::fs::create_dir_all(t.join("frames")).unwrap();
    model
        .render(model.rest_pins(), None)
        .save(t.join("frames/init_0.png"))
        .unwrap();
    let spread = TapSpread {
        r_mm: -3.0..3.0,
        theta_deg: -180.0..180.0,
        noise: false,
        seed: 3,
    };
    write_taps(&t.0, &model, 50, &spread);
    let run = calibrate_taps(&t.0, "30", &["--reference", "frames/init_0.png"]);
    ok(&run, "calibrate");
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
