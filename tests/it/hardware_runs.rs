//! Hardware runs of the real binary against the loopback fake UR5 (issue
//! 20): `follow --hardware` interrupted by SIGINT or SIGTERM sends `stopl`,
//! keeps `OUT.partial/trajectory.csv` with whole rows and exits 130 / 143;
//! a fault on the way to the start exits 1 and a start too far exits 2,
//! nothing moved; a simulation command keeps the default Ctrl-C.
#[path = "../../crates/lab/tests/it/common/fake_rig.rs"]
mod fake_rig;
use crate::util;

use fake_rig::{fake_ur5_above, lines_after_hang_up, moves, rig_file};

use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_hw::{
    FakeBehaviour, FakeUrController, FakeUrOptions, PreprocessConfig, StateInterface,
};
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::hardware::{FrameSourceConfig, HardwareConfig};
use util::{tactrace, TempDir};

/// A trained model (`m`) and a camera folder (`cam`: the reference, then
/// a collection's taps) made by the binary once for every test.
struct Fixture {
    dir: PathBuf,
    /// The edge point of the collection and its normal's angle, degrees.
    edge: (f64, f64, f64),
}

fn fixture() -> &'static Fixture {
    static FIXTURE: OnceLock<Fixture> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hardware-runs");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let collect = [
            "collect",
            "--samples",
            "40",
            "--seed",
            "8",
            "--save-frames",
            "--out",
            "ds",
        ];
        let r = tactrace(&dir, &collect);
        assert_eq!(r.code, 0, "collect: {}", r.stderr);
        let train = [
            "train", "--model", "pdennn", "--train", "ds", "--epochs", "2", "--out", "m",
        ];
        let r = tactrace(&dir, &train);
        assert_eq!(r.code, 0, "train: {}", r.stderr);
        let cam = dir.join("cam");
        std::fs::create_dir_all(&cam).unwrap();
        std::fs::copy(dir.join("ds/frames/reference.png"), cam.join("00000.png")).unwrap();
        for k in 0..40 {
            let from = dir.join(format!("ds/frames/frame_{k:05}.png"));
            std::fs::copy(from, cam.join(format!("{:05}.png", k + 1))).unwrap();
        }
        let (edge, normal) = builtin_shape(BuiltinShape::Disk).at_arc_length(0.0);
        let angle = normal.y.atan2(normal.x).to_degrees();
        Fixture {
            dir,
            edge: (edge.x, edge.y, angle),
        }
    })
}

/// The fake UR5 (RTDE) with its tool 5 mm above the start, moving at
/// `speed_mm_s`, `dx_mm` off in x, behaving as `behaviour` from the first
/// move.
fn fake(speed_mm_s: f64, dx_mm: f64, behaviour: FakeBehaviour) -> FakeUrController {
    let (x, y, angle) = fixture().edge;
    let height = SimFollowConfig::default().rig.tap.height_mm;
    let options = FakeUrOptions {
        speed_mm_s,
        behaviour,
        state: StateInterface::Rtde,
        lifetime: Duration::from_secs(40),
        ..FakeUrOptions::default()
    };
    fake_ur5_above([x + dx_mm, y, height], angle, options)
}

/// `rig.toml` in `dir` for `fake`: the camera looping over the fixture's
/// frames (a dataset's, already preprocessed), the
/// simulated rig's tap, blob and loop settings, a workspace of +-150 mm
/// around the start.
fn write_rig(dir: &Path, fake: &FakeUrController) {
    let cam = fixture().dir.join("cam");
    let mut arm = fake.config();
    arm.timeout_s = 2.0;
    let cfg = HardwareConfig {
        camera: FrameSourceConfig::Folder {
            path: cam.clone(),
            looping: true,
            preprocessed: true,
        },
        preprocess: PreprocessConfig::default(),
        ..rig_file(arm, (&cam, true), fixture().edge, 150.0)
    };
    std::fs::write(dir.join("rig.toml"), toml::to_string(&cfg).unwrap()).unwrap();
}

/// `tactrace follow --hardware rig.toml` in `dir`, started.
fn start_follow(dir: &Path, steps: &str) -> Child {
    let model = fixture().dir.join("m");
    Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(["follow", "--hardware", "rig.toml", "--model"])
        .arg(&model)
        .args(["--steps", steps, "--out", "run"])
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary starts")
}

/// Rows of `run.partial/trajectory.csv` in `dir` so far.
fn partial_rows(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("run.partial/trajectory.csv"))
        .map(|t| t.lines().count().saturating_sub(1))
        .unwrap_or(0)
}

fn send(child: &Child, signal: &str) {
    let ok = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .expect("kill runs")
        .success();
    assert!(ok, "kill {signal}");
}

/// Waits (bounded) for `child` to end; its exit status and stderr.
fn finish(mut child: Child) -> (std::process::ExitStatus, String) {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let out = child.wait_with_output().unwrap();
            return (status, String::from_utf8_lossy(&out.stderr).into_owned());
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the run did not end within 20 s of the signal");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Runs `follow --hardware` against a slow fake, sends `signals` once the
/// partial trajectory has two rows, and checks the stop.
fn interrupt_follow(tag: &str, signals: &[&str], code: i32) {
    let t = TempDir::new(tag);
    let arm = fake(40.0, 0.0, FakeBehaviour::Follow);
    write_rig(&t.0, &arm);
    let mut child = start_follow(&t.0, "500");
    let deadline = Instant::now() + Duration::from_secs(30);
    while partial_rows(&t.0) < 2 {
        if child.try_wait().unwrap().is_some() {
            let (status, stderr) = finish(child);
            panic!("the run ended before two steps: {status:?}: {stderr}");
        }
        assert!(Instant::now() < deadline, "the run made no two steps");
        std::thread::sleep(Duration::from_millis(10));
    }
    for signal in signals {
        send(&child, signal);
    }
    let (status, stderr) = finish(child);
    assert_eq!(status.code(), Some(code), "{status:?}: {stderr}");
    let lines = lines_after_hang_up(&arm);
    let (count, stopped) = moves(&lines);
    assert!(stopped, "no stopl after the last movel: {lines:#?}");
    // The start and at least two whole steps (tap down, up, next pose).
    let at_least = 1 + 3 * 2;
    assert!(count >= at_least, "{lines:#?}");
    assert!(
        !t.join("run").exists(),
        "an interrupted run is not complete"
    );
    let csv = std::fs::read_to_string(t.join("run.partial/trajectory.csv")).unwrap();
    assert!(csv.ends_with('\n'), "{csv}");
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert!(rows.len() >= 2, "{csv}");
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.split(',').count(), 8, "{row}");
        assert!(row.starts_with(&format!("{k},")), "{row}");
    }
    if signals.len() == 1 {
        assert!(stderr.contains("interrupted by SIG"), "{stderr}");
        assert!(stderr.contains("run.partial"), "{stderr}");
    }
}

#[test]
fn sigint_mid_follow_sends_stopl_keeps_the_partial_run_and_exits_130() {
    interrupt_follow("sigint", &["-INT"], 130);
}

#[test]
fn sigterm_twice_mid_follow_stops_the_arm_first_and_exits_143() {
    interrupt_follow("sigterm", &["-TERM", "-TERM"], 143);
}

#[test]
fn a_fault_on_the_way_to_the_start_exits_1_and_a_start_too_far_exits_2() {
    let t = TempDir::new("start-fault");
    let frozen = fake(400.0, 0.0, FakeBehaviour::ProtectiveStopOnMove);
    write_rig(&t.0, &frozen);
    let child = start_follow(&t.0, "5");
    let (status, stderr) = finish(child);
    assert_eq!(status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot move the arm to the start"),
        "{stderr}"
    );
    assert!(stderr.contains("protective stop"), "{stderr}");
    assert!(!stderr.contains("invalid configuration"), "{stderr}");
    assert_eq!(moves(&lines_after_hang_up(&frozen)), (1, true));
    let far = fake(400.0, 66.0, FakeBehaviour::Follow);
    write_rig(&t.0, &far);
    let child = start_follow(&t.0, "5");
    let (status, stderr) = finish(child);
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("jog the arm"), "{stderr}");
    assert!(stderr.contains("exceeds the maximum"), "{stderr}");
    assert_eq!(moves(&lines_after_hang_up(&far)).0, 0);
    assert!(!t.join("run").exists() && !t.join("run.partial").exists());
}

#[test]
fn a_simulation_command_keeps_the_default_ctrl_c() {
    let t = TempDir::new("sim-ctrl-c");
    let mut command = Command::new(env!("CARGO_BIN_EXE_tactrace"));
    // A terminal's Ctrl-C reaches a command whose SIGINT is at its default
    // action; a test run started in the background by a non-interactive
    // shell (`.ci/run &`) would pass it on ignored, and the default kept
    // would then be "ignored". Start the child as a terminal would.
    // SAFETY: between fork and exec only `signal`, which is
    // async-signal-safe, is called.
    unsafe {
        command.pre_exec(|| {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
            Ok(())
        });
    }
    let child = command
        .args(["collect", "--samples", "1000000", "--out", "big"])
        .current_dir(&t.0)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(500));
    send(&child, "-INT");
    let (status, _) = finish(child);
    assert_eq!(status.signal(), Some(2), "{status:?}");
}
