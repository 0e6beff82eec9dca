//! The real-rig path without a robot, set up one way for the lab's
//! hardware tests and the binary's (`tests/it/hardware_runs.rs` includes this
//! file by path): the loopback fake UR5 with its tool just above a start,
//! a rig file for it whose camera replays a folder of frames with the
//! simulated rig's settings, and what the fake received.
#![allow(dead_code)]
use std::path::Path;
use std::time::{Duration, Instant};
use tactrace_arm::Workspace;
use tactrace_hw::{FakeUrController, FakeUrOptions, PreprocessConfig, Ur5Config};
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::hardware::{FrameSourceConfig, HardwareConfig, HardwareStart};

/// The loopback fake UR5 (`options` for all but its start) with its tool
/// 5 mm above (x, y, z) mm in the base frame, level, turned `rz_deg`
/// about the vertical.
pub fn fake_ur5_above(
    [x, y, z]: [f64; 3],
    rz_deg: f64,
    options: FakeUrOptions,
) -> FakeUrController {
    FakeUrController::start(FakeUrOptions {
        start: [
            x / 1000.0,
            y / 1000.0,
            (z + 5.0) / 1000.0,
            0.0,
            0.0,
            rz_deg.to_radians(),
        ],
        ..options
    })
    .unwrap()
}

/// A rig file for `arm`: the camera replaying the raw frames in `frames`
/// (over and over when `looping`) through grey-only preprocessing, the
/// run starting at (x, y) mm facing `angle` deg, a workspace of
/// +-`reach_mm` round the start (z from -15 to 20 mm), and the simulated
/// rig's tap, detector, controller and loop settings.
pub fn rig_file(
    arm: Ur5Config,
    (frames, looping): (&Path, bool),
    (x, y, angle): (f64, f64, f64),
    reach_mm: f64,
) -> HardwareConfig {
    let sim = SimFollowConfig::default();
    HardwareConfig {
        arm,
        camera: FrameSourceConfig::Folder {
            path: frames.to_path_buf(),
            looping,
            preprocessed: false,
        },
        sensor: None,
        preprocess: PreprocessConfig::grayscale_only(),
        workspace: Workspace {
            min: [x - reach_mm, y - reach_mm, -15.0],
            max: [x + reach_mm, y + reach_mm, 20.0],
            ..Workspace::default()
        },
        start: HardwareStart {
            x_mm: x,
            y_mm: y,
            angle_deg: angle,
        },
        tap: sim.rig.tap,
        blob: sim.rig.blob.clone(),
        controller: sim.controller.clone(),
        follow: sim.follow.clone(),
    }
}

/// A collection's frames (name, PNG bytes) as `dir/00000.png`, ... in the
/// order a camera replays them: the reference first, then by name.
pub fn write_replay_frames(dir: &Path, frames: &[(String, Vec<u8>)]) {
    let mut files = frames.to_vec();
    files.sort_by_key(|(name, _)| (name != "reference.png", name.clone()));
    for (k, (_, png)) in files.iter().enumerate() {
        std::fs::write(dir.join(format!("{k:05}.png")), png).unwrap();
    }
}

/// Waits (3 s at most) until the driver has hung up on `fake`; whether it
/// did.
pub fn wait_for_hang_up(fake: &FakeUrController) -> bool {
    let deadline = Instant::now() + Duration::from_secs(3);
    while !fake.finished() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(5));
    }
    fake.finished()
}

/// Every URScript line `fake` got, once the driver has hung up (or 3 s
/// have passed).
pub fn lines_after_hang_up(fake: &FakeUrController) -> Vec<String> {
    wait_for_hang_up(fake);
    fake.received_lines()
}

/// The `movel` count, and whether a `stopl` came after the last one.
pub fn moves(lines: &[String]) -> (usize, bool) {
    let count = lines.iter().filter(|l| l.contains("movel(")).count();
    let last = lines.iter().rposition(|l| l.contains("movel("));
    let stopped = last.is_some_and(|i| lines[i..].iter().any(|l| l.contains("stopl(")));
    (count, stopped)
}
