//! Fault injection in the servo loop (issue 10, item 5): a frame missing,
//! blank, noise or with too few pins, a model that predicts NaN, and on
//! the real-rig path a UR5 that times out or makes a protective stop (its
//! state read over the real-time interface or RTDE), an RTDE connection
//! lost mid-run, a camera that runs out of frames, or a V4L2 camera
//! unplugged mid-run. Each must end the run safely (`Fault`,
//! with a message naming the reason), keep the steps before the fault in
//! `trajectory.csv`, record `succeeded: false` in `metrics.json`, and on
//! the UR5 send no move after the fault (only the retraction of the tap
//! after a camera fault, only `stopl` after an arm fault).
use crate::common;
use common::fake_rig::{fake_ur5_above, moves, rig_file, wait_for_hang_up};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose};
use tactrace_geometry::{builtin_shape, BuiltinShape, Contour};
use tactrace_hw::camera::v4l2::{CameraFormat, FakeDevice, StreamFormat, V4l2Source};
use tactrace_hw::{
    CameraSensor, FakeBehaviour, FakeUrController, FakeUrOptions, StateInterface, Ur5Arm,
};
use tactrace_lab::collect::{collect, CollectConfig};
use tactrace_lab::follow::{
    follow_on_rig, perception_for, write_results, RunFolder, SimFollowConfig,
};
use tactrace_lab::hardware::HardwareConfig;
use tactrace_lab::train::{resolve_config, train};
use tactrace_lab::world::World;
use tactrace_learn::{ModelKind, Preset};
use tactrace_sensor::{Frame, SensorError, TactileSensor};
use tactrace_servo::{start_pose, Ending, LoopSummary, SimRig};
use tactrace_store::StoredModel;

/// Steps before the injected fault.
const K: usize = 3;

struct Fixture {
    model: StoredModel,
    /// The same network with its input scaling broken (std 1e-300): any
    /// tap with contact gives a non-finite prediction.
    nan_model: StoredModel,
    disk: Contour,
    start: Pose,
    /// A simulated run's frames: the reference, then 10 taps.
    frames: PathBuf,
}

fn fixture() -> &'static Fixture {
    static FIXTURE: OnceLock<Fixture> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let sim = SimFollowConfig::default();
        let disk = builtin_shape(BuiltinShape::Disk);
        let cfg = CollectConfig {
            samples: 150,
            seed: 5,
            ..CollectConfig::default()
        };
        let data = collect(&sim.rig, &disk, &cfg, "disk", |_| {}).unwrap().data;
        let mcfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, Some(15)).unwrap();
        let net = train(&mcfg, &data, &mut |_| {}).unwrap().0;
        let pins = data.meta.reference_pins.clone();
        let (json, weights) = net.to_bytes().unwrap();
        let mut doc: serde_json::Value = serde_json::from_str(&json).unwrap();
        for s in doc["standardiser"]["std"].as_array_mut().unwrap() {
            *s = serde_json::json!(1e-300);
        }
        let broken = tactrace_learn::PoseModel::from_bytes(&doc.to_string(), &weights).unwrap();
        let model = StoredModel::new(net, pins.clone());
        let nan_model = StoredModel::new(broken, pins);
        let start = start_pose(&disk, &sim.start, sim.rig.tap.height_mm).unwrap();

        let frames = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("faults-frames");
        let _ = std::fs::remove_dir_all(&frames);
        std::fs::create_dir_all(&frames).unwrap();
        let mut rig = SimRig::new(&sim.rig, disk.clone(), start, sim.follow.seed).unwrap();
        let mut ten = sim.clone();
        ten.follow.steps = Some(10);
        let settings = ten.servo_settings().unwrap();
        let reference = rig.reference_frame();
        let perception = perception_for(&reference, &model, &settings).unwrap();
        let scratch = tempfile::tempdir().unwrap();
        let (arm, sensor) = rig.parts();
        let mut recorder = Injector::new(sensor, Injection::None, 0);
        recorder.keep = Some(vec![reference]);
        let (summary, _) = follow_on_rig(
            arm,
            &mut recorder,
            &perception,
            &settings,
            scratch.path(),
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(summary.steps, 10, "{}", summary.message);
        for (k, f) in recorder.keep.unwrap().iter().enumerate() {
            f.save(frames.join(format!("{k:05}.png"))).unwrap();
        }
        Fixture {
            model,
            nan_model,
            disk,
            start,
            frames,
        }
    })
}

/// What the sensor does wrong at capture `at`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Injection {
    None,
    /// The capture fails.
    Missing,
    /// A uniform grey image.
    Blank,
    /// Uniform random pixels.
    Noise,
    /// The real frame with the left half painted over (its pins gone).
    FewPins,
    /// Until `at`, the undeformed reference frame (no contact).
    ReferenceUntil,
}

/// A sensor that passes frames through, except at capture `at`; can keep
/// every frame it hands out.
struct Injector<'a> {
    inner: &'a mut dyn TactileSensor,
    injection: Injection,
    at: usize,
    count: usize,
    keep: Option<Vec<Frame>>,
    reference: Option<Frame>,
}

impl<'a> Injector<'a> {
    fn new(inner: &'a mut dyn TactileSensor, injection: Injection, at: usize) -> Self {
        Self {
            inner,
            injection,
            at,
            count: 0,
            keep: None,
            reference: None,
        }
    }
}

impl TactileSensor for Injector<'_> {
    fn capture(&mut self) -> Result<Frame, SensorError> {
        let real = self.inner.capture()?;
        let k = self.count;
        self.count += 1;
        let frame = match self.injection {
            Injection::ReferenceUntil if k < self.at => self.reference.clone().unwrap(),
            _ if k != self.at => real,
            Injection::None | Injection::ReferenceUntil => real,
            Injection::Missing => {
                return Err(SensorError::FrameUnreadable {
                    path: "camera".into(),
                    reason: "injected: no frame arrived".into(),
                })
            }
            Injection::Blank => Frame::from_pixel(real.width(), real.height(), [128].into()),
            Injection::Noise => {
                let mut state = 0x9e37_79b9_7f4a_7c15u64;
                Frame::from_fn(real.width(), real.height(), |_, _| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    [(state >> 56) as u8].into()
                })
            }
            Injection::FewPins => {
                let mut f = real.clone();
                let background = mode(&real);
                for (x, _, p) in f.enumerate_pixels_mut() {
                    if x < real.width() / 2 {
                        *p = [background].into();
                    }
                }
                f
            }
        };
        if let Some(keep) = &mut self.keep {
            keep.push(frame.clone());
        }
        Ok(frame)
    }
}

/// The most common grey level of a frame (its background).
fn mode(f: &Frame) -> u8 {
    let mut counts = [0usize; 256];
    for p in f.pixels() {
        counts[p[0] as usize] += 1;
    }
    (0..=255u8).max_by_key(|&v| counts[v as usize]).unwrap()
}

/// A simulated run of at most 10 steps with `injection` at capture `at`,
/// into a run folder, as `follow::run` does it.
fn sim_run(model: &StoredModel, injection: Injection, at: usize) -> (LoopSummary, Run) {
    let f = fixture();
    let mut sim = SimFollowConfig::default();
    sim.follow.steps = Some(10);
    let mut rig = SimRig::new(&sim.rig, f.disk.clone(), f.start, sim.follow.seed).unwrap();
    let settings = sim.servo_settings().unwrap();
    let reference = rig.reference_frame();
    let perception = perception_for(&reference, model, &settings).unwrap();
    let run = Run::new();
    let folder = RunFolder::start(&run.out, false, &sim).unwrap();
    let (arm, sensor) = rig.parts();
    let mut injector = Injector::new(sensor, injection, at);
    injector.reference = Some(reference);
    let (summary, records) = follow_on_rig(
        arm,
        &mut injector,
        &perception,
        &settings,
        folder.path(),
        &mut |_| {},
    )
    .unwrap();
    write_results(
        Some(("disk", &f.disk)),
        &records,
        &summary,
        &sim.follow,
        tactrace_lab::follow::tactip_diameter_mm(),
        folder.path(),
    )
    .unwrap();
    folder.finish().unwrap();
    (summary, run)
}

/// A run folder `out` in a fresh temporary directory.
struct Run {
    _root: tempfile::TempDir,
    out: PathBuf,
}

impl Run {
    fn new() -> Self {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("run");
        Self { _root: root, out }
    }
}

/// The run stopped safely at a fault naming `reason`, after `steps` steps,
/// all of them in `trajectory.csv` as whole rows, and says so in
/// `metrics.json`.
fn assert_safe_stop(summary: &LoopSummary, dir: &Path, steps: usize, reason: &str) {
    assert_eq!(summary.ending, Ending::Fault, "{summary:?}");
    assert_eq!(summary.steps, steps, "{summary:?}");
    assert!(summary.message.contains(reason), "{summary:?}");
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    assert!(csv.ends_with('\n'), "{csv}");
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), steps, "{csv}");
    for (k, row) in rows.iter().enumerate() {
        let fields: Vec<&str> = row.split(',').collect();
        assert_eq!(fields.len(), 8, "{row}");
        assert_eq!(fields[0], k.to_string(), "{row}");
    }
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["succeeded"], false, "{metrics}");
    assert_eq!(metrics["ending"], "fault", "{metrics}");
    assert_eq!(metrics["message"], summary.message.as_str(), "{metrics}");
}

#[test]
fn a_missing_frame_stops_the_run_safely_and_keeps_the_steps_before() {
    let (summary, run) = sim_run(&fixture().model, Injection::Missing, K);
    assert_safe_stop(&summary, &run.out, K, "injected: no frame arrived");
    assert!(summary.message.contains("the tap failed"), "{summary:?}");
}

#[test]
fn a_blank_a_noise_or_a_half_erased_frame_stops_the_run_safely() {
    for injection in [Injection::Blank, Injection::Noise, Injection::FewPins] {
        let (summary, run) = sim_run(&fixture().model, injection, K);
        assert_safe_stop(&summary, &run.out, K, "the frame could not be read");
        assert!(
            summary.message.contains("pins"),
            "{injection:?}: {summary:?}"
        );
    }
}

#[test]
fn a_nan_prediction_stops_the_run_safely() {
    let f = fixture();
    // Two taps that feel nothing (the NaN is not used), then contact.
    let (summary, run) = sim_run(&f.nan_model, Injection::ReferenceUntil, 2);
    assert_safe_stop(&summary, &run.out, 2, "non-finite");
    // The same model without the injection faults on the first tap.
    let (summary, run) = sim_run(&f.nan_model, Injection::None, 0);
    assert_safe_stop(&summary, &run.out, 0, "non-finite");
}

/// The loopback fake UR5 with the tool 5 mm above `near`, following
/// `normal_moves` moves before `behaviour`.
fn fake_near(
    near: Pose,
    behaviour: FakeBehaviour,
    normal_moves: usize,
    state: StateInterface,
) -> FakeUrController {
    let options = FakeUrOptions {
        behaviour,
        normal_moves,
        state,
        ..FakeUrOptions::default()
    };
    fake_ur5_above([near.x, near.y, near.z], near.rz, options)
}

/// A rig file for the fake arm and the camera replaying `frames` once,
/// 8 steps.
fn rig_at_start(fake: &FakeUrController, frames: &Path) -> HardwareConfig {
    let start = fixture().start;
    let mut arm = fake.config();
    arm.timeout_s = 1.0;
    let mut cfg = rig_file(arm, (frames, false), (start.x, start.y, start.rz), 60.0);
    cfg.follow.steps = Some(8);
    cfg
}

/// Follow on the fake UR5 (after `normal_moves` moves it behaves as
/// `behaviour`) with the camera replaying `frames`, the state read over
/// the real-time interface; the run, and the URScript lines the fake
/// received.
fn hardware_run(
    behaviour: FakeBehaviour,
    normal_moves: usize,
    frames: &Path,
) -> (LoopSummary, Run, Vec<String>) {
    hardware_run_on(behaviour, normal_moves, frames, StateInterface::Realtime)
}

/// [`hardware_run`] with the state read over `state`.
fn hardware_run_on(
    behaviour: FakeBehaviour,
    normal_moves: usize,
    frames: &Path,
    state: StateInterface,
) -> (LoopSummary, Run, Vec<String>) {
    let f = fixture();
    let fake = fake_near(f.start, behaviour, normal_moves, state);
    let run = Run::new();
    let world = World::Hardware(rig_at_start(&fake, frames)).open().unwrap();
    let shape = Some(("disk", &f.disk));
    let hooks = tactrace_lab::follow::RunHooks::default();
    let res = tactrace_lab::follow::run(world, &f.model, shape, (&run.out, false), hooks).unwrap();
    // The driver has hung up: wait (bounded) until the fake has read all.
    assert!(
        wait_for_hang_up(&fake),
        "the fake controller did not see the driver leave"
    );
    let lines = fake.received_lines();
    (res.summary, run, lines)
}

// Moves on the rig: one to the start, then per step the tap down, the tap
// up and the move to the next pose.

#[test]
fn an_arm_timeout_on_the_fake_ur5_stops_safely_and_sends_no_further_move() {
    // The tap down of step K never arrives.
    let normal = 1 + 3 * K;
    let (summary, run, lines) = hardware_run(FakeBehaviour::IgnoreMoves, normal, &fixture().frames);
    assert_safe_stop(&summary, &run.out, K, "timeout");
    assert!(summary.message.contains("the tap failed"), "{summary:?}");
    let (count, stopped) = moves(&lines);
    assert_eq!(count, normal + 1, "{lines:#?}");
    assert!(stopped, "no stopl after the timeout: {lines:#?}");
}

/// The move after step K's tap is refused by the controller (its state
/// read over `state`): step K is recorded, nothing more is sent.
fn protective_stop_is_safe(state: StateInterface) {
    let normal = 1 + 3 * K + 2;
    let (summary, run, lines) = hardware_run_on(
        FakeBehaviour::ProtectiveStopOnMove,
        normal,
        &fixture().frames,
        state,
    );
    assert_safe_stop(&summary, &run.out, K + 1, "protective stop");
    assert!(summary.message.contains("the arm failed"), "{summary:?}");
    assert_eq!(moves(&lines).0, normal + 1, "{lines:#?}");
}

#[test]
fn a_protective_stop_on_the_fake_ur5_stops_safely_and_sends_no_further_move() {
    protective_stop_is_safe(StateInterface::Realtime);
}

#[test]
fn a_protective_stop_read_over_rtde_stops_safely_and_sends_no_further_move() {
    protective_stop_is_safe(StateInterface::Rtde);
}

#[test]
fn a_lost_rtde_connection_mid_run_stops_safely_and_keeps_the_steps_before() {
    // The controller hangs up on the move after step K's tap.
    let normal = 1 + 3 * K + 2;
    let (summary, run, _) = hardware_run_on(
        FakeBehaviour::DisconnectOnMove,
        normal,
        &fixture().frames,
        StateInterface::Rtde,
    );
    assert_safe_stop(&summary, &run.out, K + 1, "state stream failed");
    assert!(summary.message.contains("the arm failed"), "{summary:?}");
}

#[test]
fn a_camera_out_of_frames_on_the_real_rig_path_stops_after_retracting() {
    // The reference and K taps only: capture K fails.
    let dir = tempfile::tempdir().unwrap();
    for k in 0..=K {
        let name = format!("{k:05}.png");
        std::fs::copy(fixture().frames.join(&name), dir.path().join(&name)).unwrap();
    }
    let (summary, run, lines) = hardware_run(FakeBehaviour::Follow, 0, dir.path());
    assert_safe_stop(&summary, &run.out, K, "exhausted");
    // Step K's tap went down and came back up; nothing after.
    assert_eq!(moves(&lines).0, 1 + 3 * K + 2, "{lines:#?}");
}

/// The simulated run's frames (reference first) as the 8-bit grey
/// buffers a GREY V4L2 camera would fill, and their format.
fn grey_buffers(count: usize) -> (StreamFormat, Vec<Vec<u8>>) {
    let frames: Vec<image::GrayImage> = (0..count)
        .map(|k| {
            image::open(fixture().frames.join(format!("{k:05}.png")))
                .unwrap()
                .to_luma8()
        })
        .collect();
    let (w, h) = frames[0].dimensions();
    let format = StreamFormat {
        format: CameraFormat::Grey,
        width: w,
        height: h,
        bytes_per_line: w,
    };
    (format, frames.into_iter().map(|f| f.into_raw()).collect())
}

#[test]
fn a_v4l2_camera_unplugged_mid_run_stops_safely_and_keeps_the_steps_before() {
    // The camera (a fake device replaying the simulated frames, arm state
    // over RTDE) goes away after the reference and K taps.
    let f = fixture();
    let fake = fake_near(f.start, FakeBehaviour::Follow, 0, StateInterface::Rtde);
    let cfg = rig_at_start(&fake, &f.frames);
    let ur5 = Ur5Arm::connect(cfg.arm.clone()).unwrap();
    let mut arm = LimitedArm::new(ur5, cfg.workspace.clone(), LimitMode::Refuse);
    arm.move_to(cfg.start_pose()).unwrap();
    let (format, buffers) = grey_buffers(K + 3);
    let device = FakeDevice::new(format, vec![], buffers).unplug_after(1 + K);
    let source = V4l2Source::new(device, 0, Duration::from_secs(1)).unwrap();
    let mut sensor = CameraSensor::new(source, cfg.preprocess.validate().unwrap());
    let reference = sensor.capture().unwrap();
    let settings = cfg.servo_settings().unwrap();
    let perception = perception_for(&reference, &f.model, &settings).unwrap();
    let run = Run::new();
    let folder = RunFolder::start(&run.out, false, &cfg).unwrap();
    let (summary, records) = follow_on_rig(
        &mut arm,
        &mut sensor,
        &perception,
        &settings,
        folder.path(),
        &mut |_| {},
    )
    .unwrap();
    write_results(
        None,
        &records,
        &summary,
        &cfg.follow,
        tactrace_lab::follow::tactip_diameter_mm(),
        folder.path(),
    )
    .unwrap();
    folder.finish().unwrap();
    assert_safe_stop(&summary, &run.out, K, "unplugged");
}
