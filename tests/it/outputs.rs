//! Issue 20 ("Build" items 2 and 3): one writer per output, every output
//! obeys `--force`, no output in or around an input, and bounded inputs
//! (sizes declared in files and configurations, non-regular files). The
//! real binary through `tests/it/util.rs`; concurrency is made deterministic
//! by holding an output's lock from the test, or by a run that is surely
//! still going.
use crate::util;
use std::fs;
use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use util::{expect_code, expect_refusal, tactrace, Run, TempDir};

/// A small dataset `ds` (with its frames) and a model `m` trained on it.
fn dataset_and_model(dir: &Path) {
    let args = ["collect", "--samples", "40", "--seed", "3", "--save-frames"];
    let r = tactrace(dir, &[&args[..], &["--out", "ds"]].concat());
    expect_code(&r, 0, "collect");
    let r = tactrace(
        dir,
        &["train", "--train", "ds", "--epochs", "2", "--out", "m"],
    );
    expect_code(&r, 0, "train");
}

/// Hold the lock of the output `name` in `dir` as another process would
/// (an open `.NAME.lock`, locked, with `pid` in it).
fn hold_lock(dir: &Path, name: &str, pid: u32) -> fs::File {
    let mut f = fs::File::create(dir.join(format!(".{name}.lock"))).unwrap();
    f.try_lock().expect("the lock is free");
    writeln!(f, "{pid}").unwrap();
    f
}

/// Run `tactrace args` in `dir`, killed (and the test failed) if it takes
/// longer than `limit`: for inputs that used to hang.
fn tactrace_within(dir: &Path, args: &[&str], limit: Duration) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > limit {
            let _ = child.kill();
            panic!("tactrace {args:?} still running after {limit:?}: it hangs");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// Two `follow`s into one `--out` could both exit 0, one losing its run;
/// two `collect`s both exit 0, one dataset replacing the other; a second
/// run deleted the first's live `OUT.partial`. Now a run into an output
/// another run holds is refused (exit 2, naming its pid), with or without
/// `--force`, and touches nothing.
#[test]
fn a_run_into_an_output_another_run_writes_is_refused() {
    let t = TempDir::new("locked");
    dataset_and_model(&t.0);
    fs::create_dir(t.join("out.partial")).unwrap();
    fs::write(t.join("out.partial/trajectory.csv"), "live run\n").unwrap();
    let lock = hold_lock(&t.0, "out", 4242);
    let follow = ["follow", "--model", "m", "--shape", "disk", "--steps", "3"];
    let runs: [&[&str]; 5] = [
        &[&follow[..], &["--out", "out"]].concat(),
        &[&follow[..], &["--out", "out", "--force"]].concat(),
        &["collect", "--samples", "5", "--out", "out"],
        &["collect", "--samples", "5", "--out", "out", "--force"],
        &["train", "--train", "ds", "--epochs", "1", "--out", "out"],
    ];
    for args in runs {
        let r = tactrace(&t.0, args);
        expect_code(&r, 2, &format!("{args:?}"));
        assert!(
            r.stderr
                .contains("out is being written by another tactrace run (pid 4242)"),
            "{args:?}: {}",
            r.stderr
        );
    }
    assert_eq!(
        fs::read_to_string(t.join("out.partial/trajectory.csv")).unwrap(),
        "live run\n"
    );
    assert!(!t.join("out").exists());
    // The holder ends (as a killed run's lock ends with it): the leftover
    // partial is replaced and the lock file removed.
    drop(lock);
    let r = tactrace(&t.0, &[&follow[..], &["--out", "out"]].concat());
    expect_code(&r, 0, "follow once the lock is free");
    assert!(t.join("out/trajectory.csv").exists() && !t.join("out.partial").exists());
    assert!(!t.join(".out.lock").exists());
}

/// The same with the binary holding the lock: a second follow while the
/// first is surely running is refused with the first one's pid, and the
/// first's partial run is left alone.
#[test]
fn a_second_follow_is_refused_while_the_first_runs() {
    let t = TempDir::new("twofollows");
    dataset_and_model(&t.0);
    let long = [
        "follow", "--model", "m", "--shape", "disk", "--steps", "100000", "--out", "run",
    ];
    let mut first = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(long)
        .current_dir(&t.0)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("binary starts");
    let csv = t.join("run.partial/trajectory.csv");
    let deadline = Instant::now() + Duration::from_secs(60);
    while fs::read_to_string(&csv).map_or(true, |s| s.lines().count() < 3) {
        assert!(Instant::now() < deadline, "the first run wrote no steps");
        assert!(first.try_wait().unwrap().is_none(), "the first run ended");
        std::thread::sleep(Duration::from_millis(10));
    }
    let second = ["follow", "--model", "m", "--shape", "disk", "--steps", "3"];
    let r = tactrace(&t.0, &[&second[..], &["--out", "run", "--force"]].concat());
    let still_running = first.try_wait().unwrap().is_none();
    let _ = first.kill();
    first.wait().unwrap();
    assert!(
        still_running,
        "the first run ended before the second started"
    );
    expect_code(&r, 2, "a second follow into the same --out");
    let pid = format!("(pid {})", first.id());
    assert!(r.stderr.contains(&pid), "{pid}: {}", r.stderr);
    let rows = fs::read_to_string(&csv).unwrap();
    assert!(rows.lines().count() >= 3, "the first run's steps: {rows}");
}

/// `sensor render --out EXISTING` and `validate --plots DIR` replaced
/// their files without `--force`; every single-file output now refuses an
/// existing one (exit 2, saying to add --force).
#[test]
fn every_file_output_obeys_force() {
    let t = TempDir::new("fileforce");
    dataset_and_model(&t.0);
    let render = |r: &str, force: bool| {
        let mut args = vec!["sensor", "render", "--r", r, "--out", "tap.png"];
        if force {
            args.push("--force");
        }
        tactrace(&t.0, &args)
    };
    expect_code(&render("1", false), 0, "first render");
    let first = fs::read(t.join("tap.png")).unwrap();
    let r = render("-2", false);
    expect_refusal(
        &r,
        2,
        "render over an existing file",
        "tap.png already exists; pass --force",
    );
    assert_eq!(fs::read(t.join("tap.png")).unwrap(), first);
    expect_code(&render("-2", true), 0, "render --force");
    assert_ne!(fs::read(t.join("tap.png")).unwrap(), first);

    let validate = |force: bool| {
        let mut args = vec!["validate", "--model", "m", "--data", "ds", "--plots", "p"];
        if force {
            args.push("--force");
        }
        tactrace(&t.0, &args)
    };
    expect_code(&validate(false), 0, "first validate --plots");
    fs::write(t.join("p/notes.txt"), "mine").unwrap();
    let png = fs::read(t.join("p/predicted_vs_true.png")).unwrap();
    fs::write(t.join("p/predicted_vs_true.svg"), "old").unwrap();
    let r = validate(false);
    expect_refusal(&r, 2, "validate --plots over existing plots", "--force");
    assert_eq!(
        fs::read_to_string(t.join("p/predicted_vs_true.svg")).unwrap(),
        "old"
    );
    expect_code(&validate(true), 0, "validate --plots --force");
    assert!(fs::read_to_string(t.join("p/predicted_vs_true.svg"))
        .unwrap()
        .contains("<svg"));
    assert_eq!(fs::read(t.join("p/predicted_vs_true.png")).unwrap(), png);
    assert_eq!(fs::read_to_string(t.join("p/notes.txt")).unwrap(), "mine");

    // camera grab refuses before it opens any device.
    let args = [
        "camera",
        "grab",
        "--device",
        "/nonexistent",
        "--out",
        "tap.png",
    ];
    let r = tactrace(&t.0, &args);
    expect_refusal(&r, 2, "camera grab over an existing file", "pass --force");
}

/// `import --frames F --out F --force` deleted its input frames. An output
/// equal to or inside an input, or a folder output holding an input that
/// `--force` would delete with it, is refused (exit 2) and nothing is
/// touched.
#[test]
fn an_output_in_or_around_an_input_is_refused() {
    let t = TempDir::new("overlap");
    dataset_and_model(&t.0);
    let mut csv = String::from("image_name,pose_2,pose_6\n");
    for k in 0..10 {
        csv += &format!("frame_{k:05}.png,{}.5,{}\n", k % 5, k % 7);
    }
    fs::write(t.join("targets.csv"), csv).unwrap();
    let frames = fs::read_dir(t.join("ds/frames")).unwrap().count();
    fs::create_dir(t.join("cfg")).unwrap();
    fs::write(t.join("cfg/rig.toml"), "[tap]\ndepth_mm = 6.25\n").unwrap();
    let import = [
        "import",
        "--frames",
        "ds/frames",
        "--targets",
        "targets.csv",
    ];
    let import = [&import[..], &["--reference", "ds/frames/reference.png"]].concat();
    let cases: [(Vec<&str>, &str); 6] = [
        (
            [&import[..], &["--out", "ds/frames", "--force"]].concat(),
            "--out ds/frames is the same as the input --frames ds/frames",
        ),
        (
            [&import[..], &["--out", "./ds/frames/../frames/new"]].concat(),
            "is inside the input --frames ds/frames",
        ),
        (
            vec![
                "collect",
                "--config",
                "cfg/rig.toml",
                "--out",
                "cfg",
                "--force",
            ],
            "the input --config cfg/rig.toml is inside --out cfg, which --force would replace",
        ),
        (
            vec!["train", "--train", "ds", "--out", "ds", "--force"],
            "--out ds is the same as the input --train ds",
        ),
        (
            vec![
                "sensor",
                "render",
                "--config",
                "cfg/rig.toml",
                "--out",
                "cfg/rig.toml",
            ],
            "--out cfg/rig.toml is the same as the input --config",
        ),
        (
            vec![
                "validate", "--model", "m", "--data", "ds", "--plots", "m/plots",
            ],
            "--plots m/plots is inside the input --model m",
        ),
    ];
    for (args, message) in cases {
        let r = tactrace(&t.0, &args);
        expect_code(&r, 2, &format!("{args:?}"));
        assert!(r.stderr.contains(message), "{args:?}: {}", r.stderr);
    }
    assert_eq!(fs::read_dir(t.join("ds/frames")).unwrap().count(), frames);
    assert!(!t.join("ds/frames/new").exists() && !t.join("m/plots").exists());
    assert!(t.join("cfg/rig.toml").exists());
    tactrace_store::read_dataset(&t.join("ds")).expect("the dataset is intact");
}

/// An `inputs.npy` whose header claims (100000000, 254) in a 1 KB file
/// aborted validate, train and predict (exit 134); now exit 2 naming the
/// file and the sizes.
#[test]
fn a_dataset_claiming_more_than_its_file_holds_is_bad_input() {
    let t = TempDir::new("npybomb");
    dataset_and_model(&t.0);
    fs::create_dir(t.join("bomb")).unwrap();
    for f in ["targets.npy", "meta.json"] {
        fs::copy(t.join("ds").join(f), t.join("bomb").join(f)).unwrap();
    }
    let mut dict =
        String::from("{'descr': '<f4', 'fortran_order': False, 'shape': (100000000, 254), }");
    while (10 + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    npy.extend((dict.len() as u16).to_le_bytes());
    npy.extend(dict.as_bytes());
    npy.resize(1024, 0);
    fs::write(t.join("bomb/inputs.npy"), npy).unwrap();
    let runs: [&[&str]; 3] = [
        &["validate", "--model", "m", "--data", "bomb"],
        &["train", "--train", "bomb", "--epochs", "1", "--out", "m2"],
        &["predict", "--model", "m", "--data", "bomb"],
    ];
    for args in runs {
        let r = tactrace(&t.0, args);
        expect_code(&r, 2, &format!("{args:?}"));
        assert!(
            r.stderr
                .contains("inputs.npy: its header declares a 100000000 x 254 array"),
            "{args:?}: {}",
            r.stderr
        );
    }
}

/// `[sensor.mechanics] patch_grid_mm = 0.01` (5 GB), `distance_grid_mm =
/// 1e-6` and `dome_radius_mm = 1e9` aborted; they are refused with the
/// bound in the message.
#[test]
fn configs_implying_huge_grids_are_refused_with_the_bound() {
    let t = TempDir::new("gridbomb");
    let cases = [
        (
            "[sensor.mechanics]\npatch_grid_mm = 0.01\n",
            "more than the 2e7 allowed",
        ),
        (
            "[sensor.mechanics]\ndistance_grid_mm = 1e-6\n",
            "more than the 4e6 allowed",
        ),
        (
            "[sensor.geometry]\ndome_radius_mm = 1e9\n",
            "must be at most 500 mm",
        ),
    ];
    for (toml, bound) in cases {
        fs::write(t.join("rig.toml"), toml).unwrap();
        let args = ["sensor", "render", "--config", "rig.toml", "--out", "x.png"];
        let r = tactrace_within(&t.0, &args, Duration::from_secs(60));
        expect_code(&r, 2, toml);
        assert!(r.stderr.contains(bound), "{toml}: {}", r.stderr);
        // collect reaches the same check through the rig: bad input too.
        let args = [
            "collect",
            "--config",
            "rig.toml",
            "--samples",
            "3",
            "--out",
            "c",
        ];
        let r = tactrace_within(&t.0, &args, Duration::from_secs(60));
        expect_code(&r, 2, toml);
        assert!(r.stderr.contains(bound), "{toml}: {}", r.stderr);
    }
}

/// A FIFO named like a frame hung `import`; a FIFO or a device where a
/// regular file is expected is refused at once (exit 2).
#[cfg(unix)]
#[test]
fn a_fifo_or_device_for_an_input_file_is_refused_at_once() {
    let t = TempDir::new("fifo");
    let r = tactrace(
        &t.0,
        &["collect", "--samples", "10", "--save-frames", "--out", "ds"],
    );
    expect_code(&r, 0, "collect");
    let mut csv = String::from("image_name,pose_2,pose_6\n");
    for k in 0..10 {
        csv += &format!("frame_{k:05}.png,{}.5,{}\n", k % 5, k % 7);
    }
    fs::write(t.join("targets.csv"), csv).unwrap();
    let mkfifo = |p: &Path| {
        let _ = fs::remove_file(p);
        assert!(Command::new("mkfifo").arg(p).status().unwrap().success());
    };
    mkfifo(&t.join("ds/frames/frame_00007.png"));
    mkfifo(&t.join("fifo.csv"));
    let import = |targets: &str, reference: &str| {
        let args = [
            "import",
            "--frames",
            "ds/frames",
            "--targets",
            targets,
            "--reference",
            reference,
            "--out",
            "real",
        ];
        tactrace_within(&t.0, &args, Duration::from_secs(60))
    };
    let reference = "ds/frames/reference.png";
    for (r, what) in [
        (import("targets.csv", reference), "frame_00007.png"),
        (import("fifo.csv", reference), "fifo.csv"),
        (
            import("targets.csv", "ds/frames/frame_00007.png"),
            "frame_00007.png",
        ),
    ] {
        expect_code(&r, 2, what);
        assert!(
            r.stderr.contains(what) && r.stderr.contains("not a regular file"),
            "{what}: {}",
            r.stderr
        );
    }
    let args = ["collect", "--config", "/dev/zero", "--out", "c"];
    let r = tactrace_within(&t.0, &args, Duration::from_secs(60));
    expect_refusal(
        &r,
        2,
        "/dev/zero as a configuration",
        "is a device, not a regular file",
    );
}

/// Sizes given on the command line that allocate up front: `collect
/// --samples 1e11` and `bench --taps 1e11` aborted (exit 134). A huge
/// collection now starts (buffers grow as taps come); bench's taps are
/// bounded (exit 2).
#[test]
fn huge_counts_on_the_command_line_do_not_abort() {
    let t = TempDir::new("counts");
    let r = tactrace(&t.0, &["bench", "--taps", "100000000000"]);
    expect_refusal(&r, 2, "bench --taps 1e11", "at most 20000");
    // Started and killed: it must be running, not aborted, after a moment.
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(["collect", "--samples", "100000000000", "--out", "big"])
        .current_dir(&t.0)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("binary starts");
    std::thread::sleep(Duration::from_millis(1500));
    let status = child.try_wait().unwrap();
    let _ = child.kill();
    child.wait().unwrap();
    assert!(status.is_none(), "collect --samples 1e11 ended: {status:?}");
}
