//! A collection of plain taps: the sensor pressed flat into a surface at
//! a labelled depth and slid by a labelled shear, with no edge and no
//! tilt. `import --target` takes any labels (here a depth and a slide,
//! both in mm, or the depth alone), `train` and `validate` score them by
//! name, `predict --image` prints every target, and an import that reads
//! the edge task's default columns, constant in such a set, says so.
mod util;
use std::path::Path;
use util::{json, ok, stderr_says, tactrace, TempDir};

/// `n` plain taps of the simulated TacTip in `dir`, numbered from
/// `first`: `frames/frame_K_0.png` and `labels.csv` with the edge
/// columns `pose_2`, `pose_6` (zero: no edge), the depth offset `pose_3`
/// and the slide `move_1` (mm), each uniform in [-1, 1] from `seed`.
fn write_plain_taps(dir: &Path, (first, n): (usize, usize), seed: u64) {
    use rand::{Rng, SeedableRng};
    let model = tactrace_sensor::TacTipModel::new(Default::default()).unwrap();
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut csv = String::from("image_name,pose_2,pose_6,pose_3,move_1\n");
    for k in first..first + n {
        let (dz, dx) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let tap = tactrace_sensor::EdgeTap {
            // The dome's centre 30 mm from the edge on the object's side
            // (r = -30 leaves it in the air): all of it on the surface.
            r_mm: 30.0,
            theta_deg: 0.0,
            dz_mm: dz,
            shear: Some(tactrace_sensor::Shear {
                dx_mm: dx,
                dy_mm: 0.0,
                drz_deg: 0.0,
            }),
        };
        let name = format!("frame_{k}_0.png");
        let pins = model.edge_tap_pins(&tap);
        model
            .render(&pins, Some(&mut rng))
            .save(frames.join(&name))
            .unwrap();
        csv.push_str(&format!("{name},0,0,{dz},{dx}\n"));
    }
    let labels = if first == 0 { "fit.csv" } else { "score.csv" };
    std::fs::write(dir.join(labels), csv).unwrap();
}

fn import(dir: &Path, labels: &str, extra: &[&str], out: &str) -> util::Run {
    let mut args = vec!["import", "--frames", "frames", "--targets", labels];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(dir, &args)
}

/// `validate --json`'s mean absolute error of each target.
fn maes(dir: &Path, model: &str, data: &str) -> serde_json::Value {
    let r = tactrace(
        dir,
        &["validate", "--model", model, "--data", data, "--json"],
    );
    ok(&r, "validate --json");
    json(&r.stdout)["per_target"].clone()
}

#[test]
fn plain_taps_import_train_validate_and_predict_by_name() {
    let t = TempDir::new("plain-taps");
    write_plain_taps(&t.0, (0, 120), 1);
    write_plain_taps(&t.0, (120, 40), 2);
    let r = tactrace(
        &t.0,
        &["sensor", "inspect", "frames", "--out", "sensor.toml"],
    );
    ok(&r, "sensor inspect");
    let sensor = ["--sensor", "sensor.toml"];
    // The edge task's default columns are zero in every row: said.
    let r = import(&t.0, "fit.csv", &sensor, "edge-guess");
    ok(&r, "import with the edge columns");
    stderr_says(
        &r,
        &["pose_2 is 0 in every one of the 120 rows", "--target"],
    );
    let two = ["--target", "pose_3:mm", "--target", "move_1:mm"];
    let r = import(&t.0, "fit.csv", &[&sensor[..], &two].concat(), "fit");
    ok(&r, "import --target pose_3:mm --target move_1:mm");
    assert!(!r.stderr.contains("in every one of"), "{}", r.stderr);
    ok(
        &import(&t.0, "score.csv", &["--like", "fit"], "score"),
        "import --like",
    );
    ok(&util::train(&t.0, "pdennn", "fit", "30", "m", &[]), "train");
    let per = maes(&t.0, "m", "score");
    // Labels uniform in [-1, 1] mm: guessing their mean is off by 0.5 mm.
    for name in ["pose_3", "move_1"] {
        let mae = per[name]["mae"].as_f64().unwrap();
        assert!(mae < 0.25, "{name}: {mae} mm, {per}");
    }
    // The depth alone: one target, predicted from one frame by name.
    let depth = ["--reference", "fit", "--target", "pose_3:mm"];
    ok(
        &import(&t.0, "fit.csv", &depth, "depth"),
        "import --target pose_3:mm",
    );
    ok(
        &util::train(&t.0, "pdennn", "depth", "30", "md", &[]),
        "train on one target",
    );
    let frame = "frames/frame_130_0.png";
    let r = tactrace(
        &t.0,
        &[
            "predict", "--model", "md", "--image", frame, sensor[0], sensor[1],
        ],
    );
    ok(&r, "predict --image");
    let mut lines = r.stdout.lines();
    assert_eq!(lines.next(), Some("pose_3_mm"), "{}", r.stdout);
    let got: f64 = lines.next().unwrap().parse().unwrap();
    let score = std::fs::read_to_string(t.join("score.csv")).unwrap();
    let row = score
        .lines()
        .find(|l| l.starts_with("frame_130_0.png"))
        .unwrap();
    let want: f64 = row.split(',').nth(3).unwrap().parse().unwrap();
    assert!(
        (got - want).abs() < 0.5,
        "predicted {got} mm, labelled {want} mm"
    );
}
