//! A collection of plain taps: the sensor pressed flat into a surface at
//! a labelled depth and slid by a labelled shear, with no edge and no
//! tilt. `import --target` takes any labels (here a depth and a slide,
//! both in mm, or the depth alone), `train` and `validate` score them by
//! name, `predict --image` prints every target, and an import that reads
//! the edge task's default columns, constant in such a set, says so.
use crate::util;
use std::path::Path;
use util::{json, ok, stderr_says, tactrace, TempDir};

/// `n` plain taps of the simulated TacTip in `dir`, numbered from
/// `first`: `frames/frame_K_0.png` and `labels.csv` with the edge
/// columns `pose_2`, `pose_6` (zero: no edge), the depth offset `pose_3`
/// and the slide `move_1` (mm), each uniform in [-1, 1] from `seed`, and
/// the twist `move_6` (deg): uniform in [-5, 5] when `twist`, else 0.
fn write_plain_taps(dir: &Path, (first, n): (usize, usize), seed: u64, twist: bool) {
    use rand::{Rng, SeedableRng};
    let model = tactrace_sensor::TacTipModel::new(Default::default()).unwrap();
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut csv = String::from("image_name,pose_2,pose_6,pose_3,move_1,move_6\n");
    for k in first..first + n {
        let (dz, dx) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let drz = if twist {
            rng.random_range(-5.0..5.0)
        } else {
            0.0
        };
        let tap = tactrace_sensor::EdgeTap {
            // The dome's centre 30 mm from the edge on the object's side
            // (r = -30 leaves it in the air): all of it on the surface.
            r_mm: 30.0,
            theta_deg: 0.0,
            dz_mm: dz,
            shear: Some(tactrace_sensor::Shear {
                dx_mm: dx,
                dy_mm: 0.0,
                drz_deg: drz,
            }),
        };
        let name = format!("frame_{k}_0.png");
        let pins = model.edge_tap_pins(&tap);
        model
            .render(&pins, Some(&mut rng))
            .save(frames.join(&name))
            .unwrap();
        csv.push_str(&format!("{name},0,0,{dz},{dx},{drz}\n"));
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
    write_plain_taps(&t.0, (0, 120), 1, false);
    write_plain_taps(&t.0, (120, 40), 2, false);
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

/// Session 13's new user: a model of one mm and one deg target that are
/// not an edge's (here a depth and a twist; the 127-pin surface set's
/// depth and angle alike) was called "position" and "angle" by `train`,
/// `validate` and its plots, and `predict` printed `r_mm,theta_deg`.
/// Every one of them now names the targets by their columns.
#[test]
fn a_depth_and_a_twist_are_shown_by_their_names() {
    let t = TempDir::new("depth-twist");
    write_plain_taps(&t.0, (0, 40), 3, true);
    write_plain_taps(&t.0, (120, 12), 4, true);
    let r = tactrace(&t.0, &["sensor", "inspect", "frames", "--out", "s.toml"]);
    ok(&r, "sensor inspect");
    let targets = ["--target", "pose_3:mm", "--target", "move_6:deg"];
    let fit = [&["--sensor", "s.toml"][..], &targets].concat();
    ok(&import(&t.0, "fit.csv", &fit, "fit"), "import");
    ok(
        &import(&t.0, "score.csv", &["--like", "fit"], "score"),
        "--like",
    );
    let r = util::train(&t.0, "pdennn", "fit", "2", "m", &["--val", "score"]);
    ok(&r, "train");
    let said = |what: &str, text: &str, names: &[&str]| {
        for name in names {
            assert!(text.contains(name), "{what} does not say {name}: {text}");
        }
        for edge in ["position", "angle", "r_mm", "theta"] {
            assert!(!text.contains(edge), "{what} says {edge}: {text}");
        }
    };
    said("train", &r.stdout, &["validation: pose_3 ", ", move_6 "]);
    let validate = ["validate", "--model", "m", "--data", "score"];
    let r = tactrace(&t.0, &[&validate[..], &["--plots", "plots"]].concat());
    ok(&r, "validate --plots");
    said("validate", &r.stdout, &["  pose_3: ", "  move_6: "]);
    let svg = std::fs::read_to_string(t.join("plots/predicted_vs_true.svg")).unwrap();
    said("the plot", &svg, &["pose_3, MAE", "move_6, MAE"]);
    let r = tactrace(&t.0, &["predict", "--model", "m", "--data", "score"]);
    ok(&r, "predict --data");
    let header = r.stdout.lines().next().unwrap_or_default();
    assert_eq!(
        header,
        "pose_3_mm,move_6_deg,true_pose_3_mm,true_move_6_deg"
    );
    let frame = ["--image", "frames/frame_120_0.png", "--sensor", "s.toml"];
    let r = tactrace(&t.0, &[&["predict", "--model", "m"][..], &frame].concat());
    ok(&r, "predict --image");
    assert_eq!(r.stdout.lines().next(), Some("pose_3_mm,move_6_deg"));
}

/// Session 14's new user: frames that are all the same, read against a
/// reference that is one of them, gave a dataset of zero displacements
/// without a word, and `train` fitted it. `import` now warns, and
/// `train` refuses it (exit 2), naming the dataset and why.
#[test]
fn frames_that_never_move_are_warned_about_and_not_trained_on() {
    let t = TempDir::new("still-frames");
    write_plain_taps(&t.0, (0, 12), 5, false);
    let frames = t.join("frames");
    for k in 1..12 {
        let to = frames.join(format!("frame_{k}_0.png"));
        std::fs::copy(frames.join("frame_0_0.png"), to).unwrap();
    }
    let reference = ["--reference", "frames/frame_0_0.png"];
    let targets = ["--target", "pose_3:mm"];
    let r = import(
        &t.0,
        "fit.csv",
        &[&reference[..], &targets].concat(),
        "still",
    );
    ok(&r, "import of still frames");
    stderr_says(&r, &["every pin displacement is 0", "all 12 rows"]);
    let r = util::train(&t.0, "pdennn", "still", "2", "m", &[]);
    util::expect_refusal_saying(
        &r,
        2,
        "train on still pins",
        &["still", "no model can learn"],
    );
    assert!(!t.join("m").exists(), "a model folder was written");
}
