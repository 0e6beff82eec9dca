//! `follow --replay`: the real-frame world on the shared real edge set, a
//! model trained on one part of it following a contour answered by another
//! part, and the bad inputs it refuses (exit code 2).
use crate::util;
use std::path::Path;
use util::{
    dataset_and_model, follow_disk_replay, import_labelled, real_data, real_paths, tactrace,
    TempDir,
};

/// `part.csv`: the header and the rows of `targets.csv` among the first
/// `rows` whose frame number N has N % 5 in `keep`.
fn write_part(data: &Path, out: &Path, rows: usize, keep: &[u64]) {
    let text = std::fs::read_to_string(data.join("targets.csv")).unwrap();
    let mut lines = text.lines();
    let mut part = vec![lines.next().unwrap().to_string()];
    for line in lines.take(rows) {
        let name = line.split(',').next().unwrap();
        let n: u64 = name
            .trim_start_matches("frame_")
            .split('_')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        if keep.contains(&(n % 5)) {
            part.push(line.to_string());
        }
    }
    std::fs::write(out, part.join("\n") + "\n").unwrap();
}

#[test]
fn a_model_trained_on_real_frames_follows_a_disk_answered_by_held_out_frames() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("replay");
    write_part(&data, &t.join("fit.csv"), 1500, &[2, 3, 4]);
    let [frames, _, init] = real_paths(&data);
    let fit = t.join("fit.csv").display().to_string();
    let r = import_labelled(&t.0, [&frames, &fit, &init], &[], "fit");
    assert_eq!(r.code, 0, "{}", r.stderr);
    let r = tactrace(
        &t.0,
        &[
            "train",
            "--train",
            "fit",
            "--val-fraction",
            "0.15",
            "--out",
            "m",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let follow = |extra: &[&str], out: &str| follow_disk_replay(&t.0, "m", &data, "60", extra, out);
    let r = follow(&["--replay-keep", "N%5==0"], "run");
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stdout
            .contains("label distance of the answered real frames"),
        "{}",
        r.stdout
    );
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(t.join("run/metrics.json")).unwrap())
            .unwrap();
    let replay = &metrics["replay"];
    assert_eq!(replay["taps"], 60, "{metrics}");
    assert!(
        replay["bank_frames"].as_u64().unwrap() >= 700,
        "the whole N%5==0 part: {metrics}"
    );
    let (mean, p95, max) = (
        replay["distance_mean"].as_f64().unwrap(),
        replay["distance_p95"].as_f64().unwrap(),
        replay["distance_max"].as_f64().unwrap(),
    );
    assert!(0.0 < mean && mean <= p95 && p95 <= max, "{metrics}");
    // Sixty taps of a disk answered by the labels of a straight edge: the
    // loop stays on the edge (the first steps are a quarter of the disk).
    let track = metrics["mean_track_error_mm"].as_f64().unwrap();
    assert!(track < 1.5, "{metrics}");
    let answers = std::fs::read_to_string(t.join("run/answers.csv")).unwrap();
    assert_eq!(answers.lines().count(), 61, "a header and a line a tap");
    let page = std::fs::read_to_string(t.join("run/replay.html")).unwrap();
    assert!(page.contains("real-frame world") && !page.contains("https:"));
    let config = std::fs::read_to_string(t.join("run/config.toml")).unwrap();
    assert!(
        config.contains("[replay]") && config.contains("remainder = 0"),
        "{config}"
    );
    // The run's config.toml runs the same again, in the same world.
    let r = tactrace(
        &t.0,
        &[
            "follow",
            "--model",
            "m",
            "--shape",
            "disk",
            "--config",
            "run/config.toml",
            "--out",
            "again",
        ],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let trajectory =
        |run: &str| std::fs::read_to_string(t.join(run).join("trajectory.csv")).unwrap();
    assert_eq!(trajectory("run"), trajectory("again"));

    // Bad input, each exit code 2 with a message saying what is wrong.
    let r = follow(&["--r-column", "nope"], "bad1");
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("no column `nope`"), "{}", r.stderr);
    std::fs::create_dir(t.join("empty")).unwrap();
    let r = tactrace(
        &t.0,
        &[
            "follow", "--model", "m", "--shape", "disk", "--replay", "empty", "--out", "bad2",
        ],
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("not a labelled collection"),
        "{}",
        r.stderr
    );
    std::fs::write(
        t.join("ghost.csv"),
        "image_name,pose_2,pose_3,pose_6\nframe_99999_0.png,1,0,5\nframe_99998_0.png,2,0,6\n",
    )
    .unwrap();
    let r = follow(&["--targets", "ghost.csv"], "bad3");
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("labelled frames are missing"),
        "{}",
        r.stderr
    );
    let r = follow(&["--replay-keep", "N%5"], "bad4");
    assert_eq!(r.code, 2, "{}", r.stderr);
}

/// A model in the simulator's pin order cannot read the real frames: the
/// guard refuses it before anything moves.
#[test]
fn a_model_in_another_pin_order_is_refused() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("replay-pins");
    dataset_and_model(&t.0, "40", &[], &[]);
    let r = follow_disk_replay(&t.0, "m", &data, "3", &[], "run");
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("not ordered like the model's training data"),
        "{}",
        r.stderr
    );
    assert!(!t.join("run").exists());
}
