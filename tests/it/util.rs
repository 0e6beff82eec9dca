//! Helpers for end-to-end tests: run the real binary in a temp dir.
#![allow(dead_code)]
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The outcome of one `tactrace` invocation.
pub struct Run {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

/// A fresh temporary directory for one test (`tempfile`), removed on drop;
/// `.0` is its path.
pub struct TempDir(pub PathBuf, tempfile::TempDir);

impl TempDir {
    pub fn new(name: &str) -> Self {
        let dir = tempfile::Builder::new()
            .prefix(&format!("tactrace-test-{name}-"))
            .tempdir()
            .expect("a temporary directory");
        Self(dir.path().to_path_buf(), dir)
    }
    pub fn join(&self, s: &str) -> PathBuf {
        self.0.join(s)
    }
}

/// Run `tactrace args...` with `dir` as the working directory.
pub fn tactrace(dir: &Path, args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("binary runs");
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// The real TacTip data folder; see `tactrace_testdata` for what happens
/// when it is absent.
pub fn real_data() -> Option<PathBuf> {
    tactrace_testdata::real_edge_set()
}

/// The real set's frames folder, labels file and reference frame, as
/// arguments.
pub fn real_paths(data: &Path) -> [String; 3] {
    let frames = data.join("frames");
    [
        frames.display().to_string(),
        data.join("targets.csv").display().to_string(),
        frames.join("init_0.png").display().to_string(),
    ]
}

/// Run `tactrace args...` in `dir`, read the first `lines` lines of its
/// standard output, then close the pipe (`tactrace ... | head -n LINES`).
pub fn tactrace_head(dir: &Path, args: &[&str], lines: usize) -> Run {
    use std::io::{BufRead, BufReader, Read};
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    let mut stdout = String::new();
    {
        let mut out = BufReader::new(child.stdout.take().expect("piped stdout"));
        for _ in 0..lines {
            if out.read_line(&mut stdout).expect("stdout readable") == 0 {
                break;
            }
        }
        // Dropping the reader closes the pipe.
    }
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("piped stderr")
        .read_to_string(&mut stderr)
        .expect("stderr readable");
    let status = child.wait().expect("binary ends");
    Run {
        code: status.code().unwrap_or(-1),
        stdout,
        stderr,
    }
}

/// Asserts that `run` exited with `code`, showing both outputs otherwise.
pub fn expect_code(run: &Run, code: i32, what: &str) {
    assert_eq!(
        run.code, code,
        "{what}: exit code {} (expected {code})\nstdout: {}\nstderr: {}",
        run.code, run.stdout, run.stderr
    );
}

/// Asserts that `run` ended with exit `code` and that its stderr says
/// `says` (a refusal that names its reason).
pub fn expect_refusal(run: &Run, code: i32, what: &str, says: &str) {
    expect_code(run, code, what);
    assert!(
        run.stderr.contains(says),
        "{what}: stderr does not say {says:?}:\n{}",
        run.stderr
    );
}

/// Asserts that `run` ended with exit `code` and that its stderr says
/// every one of `says` (a refusal whose message names several things).
pub fn expect_refusal_saying(run: &Run, code: i32, what: &str, says: &[&str]) {
    expect_code(run, code, what);
    stderr_says(run, says);
}

/// Asserts that `run`'s stderr says every one of `says`.
pub fn stderr_says(run: &Run, says: &[&str]) {
    for s in says {
        assert!(
            run.stderr.contains(s),
            "stderr does not say {s:?}:\n{}",
            run.stderr
        );
    }
}

/// Asserts that `run` succeeded (exit 0).
pub fn ok(run: &Run, what: &str) {
    expect_code(run, 0, what);
}

/// `text` (a command's `--json` output or a JSON file) parsed.
pub fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text.trim()).unwrap_or_else(|e| panic!("{e}: {text}"))
}

/// `validate --json` of `model` on the dataset `data` (run in `dir`):
/// the per-target figures.
pub fn per_target(dir: &Path, model: &str, data: &str) -> serde_json::Value {
    let r = tactrace(
        dir,
        &["validate", "--model", model, "--data", data, "--json"],
    );
    expect_code(&r, 0, "validate");
    json(&r.stdout)["per_target"].clone()
}

/// The reference pins a dataset's `meta.json` records.
pub fn reference_pins(dataset: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dataset.join("meta.json")).unwrap();
    json(&text)["reference_pins"].clone()
}

/// A small convolutional network (one conv layer, 8 dense units) for
/// frames of 16 to 32 px; written by [`write_small_conv`].
pub const SMALL_CONV: &str =
    "dense = [8]\nbatch_size = 8\n[[conv]]\nchannels = 4\nkernel = 3\nstride = 2\n";

/// Writes [`SMALL_CONV`] as `dir/small.toml`.
pub fn write_small_conv(dir: &Path) {
    std::fs::write(dir.join("small.toml"), SMALL_CONV).unwrap();
}

/// The simulator's 127-pin TacTip on 6 concentric rings (each ring turned
/// a little), otherwise its defaults.
pub fn ring_sensor() -> tactrace_sensor::TacTipConfig {
    let mut cfg = tactrace_sensor::TacTipConfig::default();
    cfg.geometry.layout = tactrace_sensor::PinLayout::Rings;
    cfg.geometry.ring_phase_deg = (1..=6).map(|k| 2.0 / k as f64).collect();
    cfg
}

/// How [`write_taps`] spreads its taps: uniform `r_mm` and `theta_deg`
/// drawn from a generator seeded by `seed`, which also renders each frame's
/// noise when `noise` is set.
pub struct TapSpread {
    pub r_mm: std::ops::Range<f64>,
    pub theta_deg: std::ops::Range<f64>,
    pub noise: bool,
    pub seed: u64,
}

impl TapSpread {
    /// r over [-5, 25] mm (the lightest taps barely touch), theta over
    /// [-45, 45] deg, noisy frames.
    pub fn edge(seed: u64) -> Self {
        Self {
            r_mm: -5.0..25.0,
            theta_deg: -45.0..45.0,
            noise: true,
            seed,
        }
    }
}

/// `n` labelled edge taps of the simulated sensor `model` in `dir`:
/// `frames/frame_K_0.png` and `targets.csv` (`image_name,pose_2,pose_6`,
/// r in mm and theta in deg), no undeformed frame.
pub fn write_taps(dir: &Path, model: &tactrace_sensor::TacTipModel, n: usize, spread: &TapSpread) {
    use rand::{Rng, SeedableRng};
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(spread.seed);
    let mut csv = String::from("image_name,pose_2,pose_6\n");
    for k in 0..n {
        let tap = tactrace_sensor::EdgeTap {
            r_mm: rng.random_range(spread.r_mm.clone()),
            theta_deg: rng.random_range(spread.theta_deg.clone()),
            ..tactrace_sensor::EdgeTap::default()
        };
        let name = format!("frame_{k}_0.png");
        let pins = model.edge_tap_pins(&tap);
        let noise = if spread.noise { Some(&mut rng) } else { None };
        model.render(&pins, noise).save(frames.join(&name)).unwrap();
        csv.push_str(&format!("{name},{},{}\n", tap.r_mm, tap.theta_deg));
    }
    std::fs::write(dir.join("targets.csv"), csv).unwrap();
}

/// `tactrace calibrate` of the taps in `dir` (`frames/`, `targets.csv`)
/// from `samples` of them into `s`, plain edge labels (no depth or shear
/// columns), with `extra` arguments.
pub fn calibrate_taps(dir: &Path, samples: &str, extra: &[&str]) -> Run {
    let mut args = vec![
        "calibrate",
        "--frames",
        "frames",
        "--targets",
        "targets.csv",
        "--samples",
        samples,
        "--out",
        "s",
        "--dz-column",
        "none",
        "--shear-columns",
        "none",
    ];
    args.extend(extra);
    tactrace(dir, &args)
}

/// `tactrace import` of the taps in `dir` (`frames/`, `targets.csv`) into
/// `out`, with `extra` arguments.
pub fn import_taps(dir: &Path, extra: &[&str], out: &str) -> Run {
    let mut args = vec!["import", "--frames", "frames", "--targets", "targets.csv"];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(dir, &args)
}

/// `tactrace train --model KIND --train DATA --epochs N --out OUT`, with
/// `extra` arguments (e.g. `--config small.toml`).
pub fn train(dir: &Path, kind: &str, data: &str, epochs: &str, out: &str, extra: &[&str]) -> Run {
    let mut args = vec![
        "train", "--model", kind, "--train", data, "--epochs", epochs,
    ];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(dir, &args)
}

/// A follow run of 3 steps on the disk with `--sensor SENSOR --model
/// MODEL` into `out`: it succeeds and its trajectory has a header and
/// 3 rows.
pub fn follows_three_steps(dir: &Path, sensor: &str, model: &str, out: &str) {
    let run = tactrace(
        dir,
        &[
            "follow", "--sensor", sensor, "--model", model, "--shape", "disk", "--steps", "3",
            "--out", out,
        ],
    );
    ok(&run, "follow");
    let trajectory = std::fs::read_to_string(dir.join(out).join("trajectory.csv")).unwrap();
    assert_eq!(trajectory.lines().count(), 4, "{trajectory}");
}

/// The dataset in `dir`: its row count and its frames (which it must have).
pub fn frames_of(dir: &Path) -> (usize, tactrace_store::ImageFrames) {
    let data = tactrace_store::read_dataset(dir).unwrap();
    let frames = tactrace_store::read_dataset_frames(dir, &data)
        .unwrap()
        .unwrap_or_else(|| panic!("{} has no frames.npy", dir.display()));
    (data.len(), frames)
}

/// `tactrace import` of the real set in `data` (its frames and labels,
/// see [`real_paths`]) into `out`, with `extra` arguments.
pub fn import_real(dir: &Path, data: &Path, extra: &[&str], out: &str) -> Run {
    let [frames, targets, _] = real_paths(data);
    let mut args = vec!["import", "--frames", &frames, "--targets", &targets];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(dir, &args)
}

/// A dataset of `n` synthetic 16 px frames in `dir` (a bright spot a
/// frame), targets `x` (mm, 0.25 mm a px) and `angle` (deg, circular):
/// the spot's offset and direction from the centre; a dummy pin vector a
/// row; `origin` names the test that made it.
pub fn spot_frames_dataset(dir: &Path, origin: &str, n: usize) {
    const SIDE: usize = 16;
    let (mut inputs, mut targets, mut pixels) = (Vec::new(), Vec::new(), Vec::new());
    let c = (SIDE as f64 - 1.0) / 2.0;
    for k in 0..n {
        let cx = 3.5 + 9.0 * (k as f64 * 0.618_034).fract();
        let cy = 3.5 + 9.0 * (k as f64 * 0.414_214 + 0.3).fract();
        pixels.extend((0..SIDE * SIDE).map(|i| {
            let (y, x) = ((i / SIDE) as f64, (i % SIDE) as f64);
            let d2 = (x - cx).powi(2) + (y - cy).powi(2);
            (20.0 + 220.0 * (-d2 / 4.0).exp()).round() as u8
        }));
        let angle = (cy - c).atan2(cx - c).to_degrees();
        targets.extend([((cx - c) * 0.25) as f32, angle as f32]);
        inputs.extend([cx as f32, cy as f32, 0.0, 0.0, 0.0, 0.0]);
    }
    write_spot_frames(dir, origin, SIDE, inputs, targets, pixels);
}

/// Writes a synthetic image dataset to `dir`: `side` x `side` frames
/// `pixels`, 6 pin inputs and two targets a row, x (mm) and a circular
/// angle (deg); `origin` names the test that made it.
pub fn write_spot_frames(
    dir: &Path,
    origin: &str,
    side: usize,
    inputs: Vec<f32>,
    targets: Vec<f32>,
    pixels: Vec<u8>,
) {
    use tactrace_store::{DatasetMeta, FramesInfo, ImageFrames, TapData};
    let meta: DatasetMeta = serde_json::from_value(serde_json::json!({
        "source": "synthetic", "origin": origin, "seed": null,
        "samples": targets.len() / 2, "pins": 3, "targets": ["x (mm)", "angle (deg)"],
        "target_names": ["x", "angle"], "target_units": ["mm", "deg"],
        "target_circular": [false, true], "frames_with_missing_pins": 0,
        "reference_pins": [[1.0, 1.0], [8.0, 8.0], [14.0, 2.0]],
        "settings": {}, "tactrace_version": "test",
    }))
    .unwrap();
    let data = TapData {
        inputs,
        targets,
        meta,
    };
    let frames = ImageFrames {
        info: FramesInfo::new(side, side, [side, side]),
        pixels,
    };
    tactrace_store::write_dataset_with(dir, &data, &[], Some(&frames), false).unwrap();
}

/// `tactrace collect --samples SAMPLES` with `extra` arguments into `out`
/// (simulated taps).
pub fn collect(dir: &Path, samples: &str, extra: &[&str], out: &str) -> Run {
    let mut args = vec!["collect", "--samples", samples];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(dir, &args)
}

/// A dataset `ds` of `samples` simulated taps (`collect_extra` given to
/// `collect`) and a model `m` trained on it for 2 epochs (`train_extra`
/// given to `train`), both succeeding; returns train's run.
pub fn dataset_and_model(
    dir: &Path,
    samples: &str,
    collect_extra: &[&str],
    train_extra: &[&str],
) -> Run {
    expect_code(&collect(dir, samples, collect_extra, "ds"), 0, "collect");
    let mut args = vec!["train", "--train", "ds", "--epochs", "2"];
    args.extend(train_extra);
    args.extend(["--out", "m"]);
    let r = tactrace(dir, &args);
    expect_code(&r, 0, "train");
    r
}

/// `tactrace import --frames FRAMES --targets TARGETS --reference
/// REFERENCE` with `extra` arguments into `out`.
pub fn import_labelled(
    dir: &Path,
    [frames, targets, reference]: [&str; 3],
    extra: &[&str],
    out: &str,
) -> Run {
    let mut args = vec![
        "import",
        "--frames",
        frames,
        "--targets",
        targets,
        "--reference",
        reference,
    ];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(dir, &args)
}

/// `tactrace twin --targets TARGETS --reference REFERENCE` with `extra`
/// arguments into `out`.
pub fn twin(dir: &Path, [targets, reference]: [&str; 2], extra: &[&str], out: &str) -> Run {
    let mut args = vec!["twin", "--targets", targets, "--reference", reference];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(dir, &args)
}

/// `tactrace follow --model MODEL --shape disk --replay DATA --steps STEPS`
/// (the real-frame world of the collection `data`) with `extra` arguments
/// into `out`.
pub fn follow_disk_replay(
    dir: &Path,
    model: &str,
    data: &Path,
    steps: &str,
    extra: &[&str],
    out: &str,
) -> Run {
    let data = data.display().to_string();
    let mut args = vec![
        "follow", "--model", model, "--shape", "disk", "--replay", &data, "--steps", steps,
    ];
    args.extend(extra);
    args.extend(["--out", out]);
    tactrace(dir, &args)
}
