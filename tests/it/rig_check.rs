//! `tactrace rig check` end to end against the fakes: the fake UR
//! controller (RTDE state), the fake dashboard server and a camera
//! replaying a simulated reference frame. Exit codes: 0 all ready, 1 a
//! part not ready, 2 a bad rig file.
use crate::util;

use std::time::Duration;
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_hw::{
    FakeDashboard, FakeDashboardState, FakeStateFault, FakeUrController, FakeUrOptions,
    PreprocessConfig, StateInterface,
};
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::hardware::{FrameSourceConfig, HardwareConfig, HardwareStart};
use tactrace_servo::{start_pose, SimRig};
use util::{tactrace, Run, TempDir};

/// The rig's start, in the work frame (the fake's base frame here).
const START: (f64, f64) = (60.0, 0.0);

/// A 640 x 480 camera image in `dir/frames/00000.png`: a simulated
/// undeformed frame placed where the default crop of the 127-pin TacTip
/// looks, so the default preprocessing runs on it.
fn reference_frame(dir: &TempDir) -> std::path::PathBuf {
    let sim = SimFollowConfig::default();
    let disk = builtin_shape(BuiltinShape::Disk);
    let start = start_pose(&disk, &sim.start, sim.rig.tap.height_mm).unwrap();
    let rig = SimRig::new(&sim.rig, disk, start, 1).unwrap();
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    as_camera_image(&rig.reference_frame())
        .save(frames.join("00000.png"))
        .unwrap();
    frames
}

/// Writes `rig.toml` for the fakes and the frame folder.
fn write_rig(
    dir: &TempDir,
    ur: &FakeUrController,
    dashboard: &FakeDashboard,
    frames: &std::path::Path,
) {
    let sim = SimFollowConfig::default();
    let mut arm = ur.config();
    arm.dashboard_port = dashboard.port();
    let cfg = HardwareConfig {
        arm,
        camera: FrameSourceConfig::Folder {
            path: frames.to_path_buf(),
            looping: true,
            preprocessed: false,
        },
        sensor: None,
        preprocess: PreprocessConfig::default(),
        workspace: tactrace_arm::Workspace {
            min: [START.0 - 50.0, START.1 - 50.0, -15.0],
            max: [START.0 + 50.0, START.1 + 50.0, 20.0],
            ..tactrace_arm::Workspace::default()
        },
        start: HardwareStart {
            x_mm: START.0,
            y_mm: START.1,
            angle_deg: 0.0,
        },
        tap: sim.rig.tap,
        blob: tactrace_vision::BlobParams::preset("real256").unwrap(),
        controller: sim.controller.clone(),
        follow: sim.follow.clone(),
    };
    std::fs::write(dir.join("rig.toml"), toml::to_string(&cfg).unwrap()).unwrap();
}

/// The fake arm with its tool 5 mm above the start, serving RTDE.
fn fake_ur() -> FakeUrController {
    FakeUrController::start(FakeUrOptions {
        start: [START.0 / 1000.0, START.1 / 1000.0, 0.010, 0.0, 0.0, 0.0],
        state: StateInterface::Rtde,
        lifetime: Duration::from_secs(20),
        ..FakeUrOptions::default()
    })
    .unwrap()
}

/// A binarised 256 x 256 sensor frame made to look like a camera image
/// (soft grey pins on a dark grey background, 640 x 480, placed where the
/// default crop of the 127-pin TacTip collection looks), so the default
/// preprocessing has real work to do.
fn as_camera_image(frame: &image::GrayImage) -> image::GrayImage {
    let soft = image::imageops::blur(frame, 1.0);
    let mut camera = image::GrayImage::from_pixel(640, 480, image::Luma([30]));
    for (x, y, p) in soft.enumerate_pixels() {
        let level = 30.0 + 0.7 * f64::from(p[0]);
        camera.put_pixel(x + 190, y + 132, image::Luma([level as u8]));
    }
    camera
}

/// The real TacTip's undeformed frame (`init_0.png` of the 127-pin edge
/// set) as a camera image in `dir/real-frames`; `None` when the data is
/// absent and its tests may be skipped.
fn real_reference_frame(dir: &TempDir) -> Option<std::path::PathBuf> {
    let data = util::real_data()?;
    let frames = dir.join("real-frames");
    std::fs::create_dir_all(&frames).unwrap();
    let init = image::open(data.join("frames/init_0.png"))
        .unwrap()
        .to_luma8();
    as_camera_image(&init)
        .save(frames.join("00000.png"))
        .unwrap();
    Some(frames)
}

/// Which camera the rig replays.
enum Camera {
    Real,
    Missing,
}

/// `rig check` on a fresh pair of fakes; `None` when the real data it
/// needs is absent (and may be skipped).
fn check_with(dashboard: FakeDashboardState, camera: Camera) -> Option<Run> {
    let dir = TempDir::new("rig-check");
    let frames = match camera {
        Camera::Real => real_reference_frame(&dir)?,
        Camera::Missing => dir.join("no-camera-here"),
    };
    let ur = fake_ur();
    let dash = FakeDashboard::start(dashboard, Duration::from_secs(20)).unwrap();
    write_rig(&dir, &ur, &dash, &frames);
    let run = tactrace(&dir.0, &["rig", "check", "rig.toml"]);
    assert!(
        !dash
            .commands()
            .iter()
            .any(|c| c == "play" || c.starts_with("load")),
        "rig check must not start programs"
    );
    assert!(
        ur.received_lines().is_empty(),
        "rig check must not command the arm"
    );
    Some(run)
}

fn line<'a>(run: &'a Run, name: &str) -> &'a str {
    run.stdout
        .lines()
        .find(|l| l.trim_start().starts_with(name))
        .unwrap_or_else(|| panic!("no `{name}` line in\n{}", run.stdout))
}

#[test]
fn a_ready_rig_passes_every_check_and_exits_0() {
    let Some(run) = check_with(FakeDashboardState::default(), Camera::Real) else {
        return;
    };
    println!("{}", run.stdout);
    assert_eq!(run.code, 0, "{}\n{}", run.stdout, run.stderr);
    for name in ["dashboard", "safety", "state", "camera", "reference"] {
        assert!(line(&run, name).contains(" ready "), "{}", run.stdout);
    }
    assert!(line(&run, "dashboard").contains("PolyScope 5.11, robot mode RUNNING, remote control"));
    assert!(
        line(&run, "state").contains("RTDE (controller 5.11.0)"),
        "{}",
        run.stdout
    );
    assert!(
        line(&run, "state").contains("8.0 mm from the start"),
        "{}",
        run.stdout
    );
    // The real TacTip's undeformed frame, softened into a camera-like
    // image and binarised again by the default (Bristol) preprocessing:
    // about its 127 pins (the round trip is not exact: a pin may merge
    // with the rim or a rim arc split off).
    let reference = line(&run, "reference");
    let count: usize = reference
        .split_whitespace()
        .nth(2)
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no pin count in `{reference}`"));
    assert!((122..=132).contains(&count), "{reference}");
    assert!(run.stdout.trim_end().ends_with("all ready"));
    // docs/hardware.md shows this very screen.
    let docs = include_str!("../../docs/hardware.md");
    let shown = docs
        .split("```text\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("docs/hardware.md shows a rig check screen");
    assert_eq!(
        shown, run.stdout,
        "docs/hardware.md's rig check output is stale"
    );
    // --pins makes the count a condition.
    let dir = TempDir::new("rig-check-pins");
    let frames = real_reference_frame(&dir).unwrap();
    let (ur, dash) = (
        fake_ur(),
        FakeDashboard::start(FakeDashboardState::default(), Duration::from_secs(20)).unwrap(),
    );
    write_rig(&dir, &ur, &dash, &frames);
    let exact = count.to_string();
    let run = tactrace(&dir.0, &["rig", "check", "rig.toml", "--pins", &exact]);
    assert_eq!(run.code, 0, "{}\n{}", run.stdout, run.stderr);
    assert!(
        line(&run, "reference").contains("as expected"),
        "{}",
        run.stdout
    );
    let (ur, dash) = (
        fake_ur(),
        FakeDashboard::start(FakeDashboardState::default(), Duration::from_secs(20)).unwrap(),
    );
    write_rig(&dir, &ur, &dash, &frames);
    let other = (count + 1).to_string();
    let run = tactrace(&dir.0, &["rig", "check", "rig.toml", "--pins", &other]);
    assert_eq!(run.code, 1, "{}\n{}", run.stdout, run.stderr);
    assert!(
        line(&run, "reference").contains("NOT READY"),
        "{}",
        run.stdout
    );
}

#[test]
fn a_protective_stop_and_a_missing_camera_are_not_ready_and_exit_1() {
    let run = check_with(
        FakeDashboardState {
            safety_status: "PROTECTIVE_STOP".into(),
            remote_control: Some(false),
            ..FakeDashboardState::default()
        },
        Camera::Missing,
    )
    .unwrap();
    println!("{}", run.stdout);
    assert_eq!(run.code, 1, "{}\n{}", run.stdout, run.stderr);
    assert!(line(&run, "safety").contains("NOT READY  PROTECTIVE_STOP: remove its cause"));
    assert!(line(&run, "camera").contains("NOT READY"), "{}", run.stdout);
    assert!(
        line(&run, "reference").contains("not checked"),
        "{}",
        run.stdout
    );
    assert!(
        line(&run, "note:").contains("local control"),
        "{}",
        run.stdout
    );
    assert!(
        run.stderr
            .contains("the rig is not ready (3 of 5 checks failed)"),
        "{}",
        run.stderr
    );
}

#[test]
fn an_unreachable_arm_is_not_ready_and_a_bad_rig_file_exits_2() {
    let dir = TempDir::new("rig-check-bad");
    let frames = reference_frame(&dir);
    let ur = fake_ur();
    let dash = FakeDashboard::start(FakeDashboardState::default(), Duration::from_secs(5)).unwrap();
    write_rig(&dir, &ur, &dash, &frames);
    let text = std::fs::read_to_string(dir.join("rig.toml")).unwrap();
    drop((ur, dash));
    let run = tactrace(&dir.0, &["rig", "check", "rig.toml"]);
    assert_eq!(run.code, 1, "{}\n{}", run.stdout, run.stderr);
    assert!(
        line(&run, "dashboard").contains("unreachable"),
        "{}",
        run.stdout
    );
    assert!(line(&run, "state").contains("NOT READY"), "{}", run.stdout);
    assert!(line(&run, "camera").contains(" ready "), "{}", run.stdout);

    // A V4L2 camera that is not there: a clear camera line.
    let mut v4l2 = HardwareConfig::from_toml(&text, "rig.toml").unwrap();
    v4l2.camera = FrameSourceConfig::V4l2(tactrace_hw::V4l2Config::new("/dev/video-tactrace-none"));
    std::fs::write(dir.join("v4l2.toml"), toml::to_string(&v4l2).unwrap()).unwrap();
    let run = tactrace(&dir.0, &["rig", "check", "v4l2.toml"]);
    assert_eq!(run.code, 1, "{}\n{}", run.stdout, run.stderr);
    assert!(
        line(&run, "camera").contains("no camera at /dev/video-tactrace-none"),
        "{}",
        run.stdout
    );

    std::fs::write(dir.join("bad.toml"), format!("{text}\nspeed = 3\n")).unwrap();
    let run = tactrace(&dir.0, &["rig", "check", "bad.toml"]);
    assert_eq!(run.code, 2, "{}\n{}", run.stdout, run.stderr);
    assert!(run.stdout.is_empty(), "{}", run.stdout);
    let run = tactrace(&dir.0, &["rig", "check", "missing.toml"]);
    assert_eq!(run.code, 2, "{}", run.stderr);
}

#[test]
fn camera_list_and_grab_say_clearly_when_there_is_no_camera() {
    let dir = TempDir::new("camera");
    let run = tactrace(&dir.0, &["camera", "list"]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stdout.contains("/dev/video") || run.stdout.contains("no video capture device"),
        "{}",
        run.stdout
    );
    let missing = "/dev/video-tactrace-none";
    let run = tactrace(
        &dir.0,
        &["camera", "grab", "--device", missing, "--out", "f.png"],
    );
    assert_eq!(run.code, 2, "{}\n{}", run.stdout, run.stderr);
    assert!(
        run.stderr.contains("no camera at /dev/video-tactrace-none"),
        "{}",
        run.stderr
    );
    assert!(!dir.join("f.png").exists());
    std::fs::write(dir.join("f.png"), b"keep").unwrap();
    let run = tactrace(
        &dir.0,
        &["camera", "grab", "--device", missing, "--out", "f.png"],
    );
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert_eq!(std::fs::read(dir.join("f.png")).unwrap(), b"keep");
}

/// Issue 20: `rig check` said "all ready" with the tool 666 mm from the
/// start (which `follow` then refuses) and with a state of 1e306 m (the
/// tool at NaN in the work frame). Both are not ready, exit 1, with the
/// reason; nothing is commanded.
#[test]
fn rig_check_is_not_ready_far_from_the_start_or_on_an_impossible_state() {
    let dir = TempDir::new("rig-check-issue20");
    let frames = reference_frame(&dir);
    let cases = [
        (666.0, FakeStateFault::None, "666.0 mm from the start"),
        (
            0.0,
            FakeStateFault::HugePosition,
            "impossible actual TCP pose",
        ),
        (0.0, FakeStateFault::NotFinite, "not finite"),
    ];
    for (dx, state_fault, reason) in cases {
        let ur = FakeUrController::start(FakeUrOptions {
            start: [
                (START.0 + dx) / 1000.0,
                START.1 / 1000.0,
                0.010,
                0.0,
                0.0,
                0.0,
            ],
            state: StateInterface::Rtde,
            state_fault,
            lifetime: Duration::from_secs(20),
            ..FakeUrOptions::default()
        })
        .unwrap();
        let dash =
            FakeDashboard::start(FakeDashboardState::default(), Duration::from_secs(20)).unwrap();
        write_rig(&dir, &ur, &dash, &frames);
        let run = tactrace(&dir.0, &["rig", "check", "rig.toml"]);
        assert_eq!(run.code, 1, "{}\n{}", run.stdout, run.stderr);
        let state = line(&run, "state");
        assert!(
            state.contains("NOT READY") && state.contains(reason),
            "{}",
            run.stdout
        );
        assert!(!state.contains("NaN"), "{state}");
        assert!(!run.stdout.contains("all ready"), "{}", run.stdout);
        if dx > 0.0 {
            assert!(state.contains("follow would refuse the move to the start"));
        }
        assert!(
            ur.received_lines().is_empty(),
            "rig check commanded the arm"
        );
    }
}

/// Issue 20: `camera grab` on a path that is no camera exited 1 (a failed
/// run); it is bad input, 2, saying so, and the file is untouched.
#[test]
fn camera_grab_on_a_non_camera_path_exits_2() {
    let dir = TempDir::new("camera-not");
    std::fs::write(dir.join("notes.txt"), b"not a camera").unwrap();
    let folder = dir.0.display().to_string();
    for device in ["notes.txt", "/dev/null", folder.as_str()] {
        let run = tactrace(
            &dir.0,
            &["camera", "grab", "--device", device, "--out", "f.png"],
        );
        assert_eq!(run.code, 2, "{device}: {}", run.stderr);
        assert!(run.stderr.contains("is not a camera"), "{}", run.stderr);
        assert!(!dir.join("f.png").exists());
    }
    assert_eq!(
        std::fs::read(dir.join("notes.txt")).unwrap(),
        b"not a camera"
    );
}

/// The rig file of `write_rig` in `dir` as a TOML table.
fn rig_table(dir: &TempDir) -> toml::Table {
    let text = std::fs::read_to_string(dir.join("rig.toml")).unwrap();
    text.parse().unwrap()
}

/// The rig's camera read through a sensor file holding the Bristol
/// settings of the `[preprocess]` and `[blob]` tables finds the same pins
/// as the tables do; a rig file giving both ways exits 2 before anything
/// is touched.
#[test]
fn rig_check_reads_the_camera_through_a_sensor_file() {
    let dir = TempDir::new("rig-check-sensor");
    let frames = reference_frame(&dir);
    let ur = fake_ur();
    let dash =
        FakeDashboard::start(FakeDashboardState::default(), Duration::from_secs(20)).unwrap();
    write_rig(&dir, &ur, &dash, &frames);
    let tables = tactrace(&dir.0, &["rig", "check", "rig.toml"]);
    assert_eq!(tables.code, 0, "{}\n{}", tables.stdout, tables.stderr);

    let sight = tactrace_store::SightFile {
        sensor: tactrace_store::SensorSummary {
            pins: 127,
            layout: tactrace_vision::LayoutKind::Hexagonal,
            spacing_px: 20.0,
            pin_pixels: 30.0,
            frame_size: [640, 480],
        },
        preprocess: PreprocessConfig::default().to_params(),
        detect: tactrace_vision::DetectorParams::Blobs(
            tactrace_vision::BlobParams::preset("real256").unwrap(),
        ),
    };
    std::fs::create_dir_all(dir.join("rigs")).unwrap();
    std::fs::write(dir.join("rigs/sensor.toml"), sight.to_toml()).unwrap();
    // A fake serves one check: fresh ones for the sensor file's.
    let ur = fake_ur();
    let dash =
        FakeDashboard::start(FakeDashboardState::default(), Duration::from_secs(20)).unwrap();
    write_rig(&dir, &ur, &dash, &frames);
    let mut table = rig_table(&dir);
    table.remove("preprocess");
    table.remove("blob");
    table.insert("sensor".into(), "sensor.toml".into());
    std::fs::write(dir.join("rigs/rig.toml"), toml::to_string(&table).unwrap()).unwrap();
    let file = tactrace(&dir.0, &["rig", "check", "rigs/rig.toml"]);
    assert_eq!(file.code, 0, "{}\n{}", file.stdout, file.stderr);
    for name in ["camera", "reference"] {
        assert_eq!(line(&file, name), line(&tables, name), "{}", file.stdout);
    }
    let count: usize = line(&file, "reference")
        .split_whitespace()
        .nth(2)
        .and_then(|n| n.parse().ok())
        .unwrap();
    assert!(count > 100, "{}", file.stdout);

    let preprocess = toml::Value::try_from(PreprocessConfig::default()).unwrap();
    table.insert("preprocess".into(), preprocess);
    std::fs::write(dir.join("rigs/both.toml"), toml::to_string(&table).unwrap()).unwrap();
    let both = tactrace(&dir.0, &["rig", "check", "rigs/both.toml"]);
    assert_eq!(both.code, 2, "{}\n{}", both.stdout, both.stderr);
    assert!(both.stderr.contains("keep one way"), "{}", both.stderr);
}
