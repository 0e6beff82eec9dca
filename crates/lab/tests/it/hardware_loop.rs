//! The real-rig path end to end without a robot: the UR5 driver talks to
//! the loopback fake controller and the camera replays the frames a
//! simulated run captured. Fed the same frames, the hardware path must
//! command exactly the trajectory the simulated path commanded: the same
//! pipeline runs on both rigs.
use crate::common;
use common::fake_rig::{fake_ur5_above, rig_file, write_replay_frames};
use std::path::{Path, PathBuf};
use std::time::Duration;
use tactrace_arm::{Pose, Workspace};
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_hw::{
    FakeDashboard, FakeDashboardState, FakeUrController, FakeUrOptions, StateInterface,
};
use tactrace_lab::collect::{collect, CollectConfig};
use tactrace_lab::follow::{follow_on_rig, perception_for, RunHooks, SimFollowConfig};
use tactrace_lab::hardware::{
    collect_hardware, rig_check, FrameSourceConfig, HardwareConfig, StopFlag,
};
use tactrace_lab::train::{resolve_config, train};
use tactrace_lab::world::World;
use tactrace_learn::{ModelKind, Preset};
use tactrace_sensor::{Frame, SensorError, TactileSensor};
use tactrace_servo::{pose_at_edge, start_pose, SimRig};
use tactrace_store::StoredModel;

/// A sensor that saves every frame it hands out as a numbered PNG.
struct Recorder<'a> {
    inner: &'a mut dyn TactileSensor,
    dir: PathBuf,
    count: usize,
}

impl Recorder<'_> {
    fn save(&mut self, frame: &Frame) {
        frame
            .save(self.dir.join(format!("{:05}.png", self.count)))
            .unwrap();
        self.count += 1;
    }
}

impl TactileSensor for Recorder<'_> {
    fn capture(&mut self) -> Result<Frame, SensorError> {
        let frame = self.inner.capture()?;
        self.save(&frame);
        Ok(frame)
    }
}

/// A fresh folder `tag` under `root`.
fn scratch(root: &tempfile::TempDir, tag: &str) -> PathBuf {
    let dir = root.path().join(tag);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn trajectory(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("trajectory.csv")).unwrap()
}

/// The loopback fake controller with the tool 5 mm above `near`, serving
/// its state on `state`.
fn fake_near(near: Pose, state: StateInterface) -> FakeUrController {
    let options = FakeUrOptions {
        state,
        ..FakeUrOptions::default()
    };
    fake_ur5_above([near.x, near.y, near.z], near.rz, options)
}

#[test]
fn replayed_frames_on_the_fake_ur5_command_the_simulated_trajectory() {
    const STEPS: usize = 12;
    let sim = SimFollowConfig::default();
    let disk = builtin_shape(BuiltinShape::Disk);
    let data = collect(
        &sim.rig,
        &disk,
        &CollectConfig {
            samples: 150,
            seed: 5,
            ..CollectConfig::default()
        },
        "disk",
        |_| {},
    )
    .unwrap()
    .data;
    let mcfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, Some(15)).unwrap();
    let net = train(&mcfg, &data, &mut |_| {}).unwrap().0;
    let model = StoredModel::new(net.clone(), data.meta.reference_pins.clone());
    let root = tempfile::tempdir().unwrap();

    // The simulated run, recording its frames (reference first).
    let start = start_pose(&disk, &sim.start, sim.rig.tap.height_mm).unwrap();
    let mut steps = sim.clone();
    steps.follow.steps = Some(STEPS);
    let settings = steps.servo_settings().unwrap();
    let follow = settings.follow().clone();
    let frames = scratch(&root, "frames");
    let sim_out = scratch(&root, "sim");
    let mut rig = SimRig::new(&sim.rig, disk.clone(), start, follow.seed).unwrap();
    let reference = rig.reference_frame();
    let perception = perception_for(&reference, &model, &settings).unwrap();
    let (arm, sensor) = rig.parts();
    let mut recorder = Recorder {
        inner: sensor,
        dir: frames.clone(),
        count: 0,
    };
    recorder.save(&reference);
    let (sim_summary, _) = follow_on_rig(
        arm,
        &mut recorder,
        &perception,
        &settings,
        &sim_out,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(sim_summary.steps, STEPS, "{}", sim_summary.message);

    // The same frames through the UR5 driver and the camera sensor, with
    // the arm's state read over RTDE and over the real-time fallback.
    for state in [StateInterface::Rtde, StateInterface::Realtime] {
        let fake = fake_near(start, state);
        let hw = HardwareConfig {
            follow: follow.clone(),
            ..rig_file(
                fake.config(),
                (&frames, false),
                (start.x, start.y, start.rz),
                60.0,
            )
        };
        assert_eq!(hw.arm.state, state);
        let hw_out = root.path().join(format!("hw-{state:?}"));
        let stop = StopFlag::new();
        let hooks = RunHooks {
            stop: Some(&stop),
            ..RunHooks::default()
        };
        let world = World::Hardware(hw).open().unwrap();
        let shape = Some(("disk", &disk));
        let res = tactrace_lab::follow::run(world, &model, shape, (&hw_out, false), hooks).unwrap();
        assert_eq!(
            res.summary.steps, STEPS,
            "{state:?}: {}",
            res.summary.message
        );
        assert_eq!(trajectory(&hw_out), trajectory(&sim_out), "{state:?}");
        assert!(res.metrics.is_some() && hw_out.join("metrics.json").exists());
        // Every move went to the controller as URScript.
        let moves = fake
            .received_lines()
            .iter()
            .filter(|l| l.contains("movel"))
            .count();
        assert!(moves >= 3 * STEPS - 1, "{state:?}: {moves} movel commands");
    }

    // `rig check` on the same rig: the reference frame's pins are the
    // model's; a model trained on pins in another order is refused.
    let fake = fake_near(start, StateInterface::Rtde);
    let dashboard =
        FakeDashboard::start(FakeDashboardState::default(), Duration::from_secs(20)).unwrap();
    let mut hw = rig_file(
        fake.config(),
        (&frames, false),
        (start.x, start.y, start.rz),
        60.0,
    );
    hw.arm.dashboard_port = dashboard.port();
    let check = rig_check(&hw, Some(&model), None).unwrap();
    assert!(check.ready(), "{check:#?}");
    let reference = check.items.iter().find(|i| i.name == "reference").unwrap();
    assert!(
        reference
            .detail
            .contains("in the order the model was trained on"),
        "{reference:?}"
    );
    let mut reversed = data.meta.reference_pins.clone();
    reversed.reverse();
    let other = StoredModel::new(net, reversed);
    let fake = fake_near(start, StateInterface::Rtde);
    hw.arm = fake.config();
    hw.arm.dashboard_port = dashboard.port();
    let check = rig_check(&hw, Some(&other), None).unwrap();
    assert!(!check.ready(), "{check:#?}");
    let reference = check.items.iter().find(|i| i.name == "reference").unwrap();
    assert!(
        !reference.ready && reference.detail.contains("the model has"),
        "{reference:?}"
    );
    assert!(
        check.items.iter().filter(|i| !i.ready).count() == 1,
        "{check:#?}"
    );
}

#[test]
fn a_collection_replayed_on_the_fake_ur5_gives_the_simulated_dataset() {
    let sim = SimFollowConfig::default();
    let disk = builtin_shape(BuiltinShape::Disk);
    let cfg = CollectConfig {
        samples: 20,
        seed: 8,
        save_frames: true,
        ..CollectConfig::default()
    };
    let simulated = collect(&sim.rig, &disk, &cfg, "disk", |_| {}).unwrap();
    // Replay order: the reference first, then the taps.
    let root = tempfile::tempdir().unwrap();
    let frames = scratch(&root, "collect-frames");
    write_replay_frames(&frames, &simulated.frames);
    let (edge, normal) = disk.at_arc_length(cfg.edge_arc_mm);
    let angle = normal.y.atan2(normal.x).to_degrees();
    let first = pose_at_edge(
        edge,
        normal,
        0.0,
        -cfg.theta_range_deg,
        sim.rig.tap.height_mm,
    );
    let fake = fake_near(first, StateInterface::Rtde);
    let hw = rig_file(
        fake.config(),
        (&frames, false),
        (edge.x, edge.y, angle),
        60.0,
    );
    let real = collect_hardware(&hw, &cfg, "rig", &StopFlag::new(), |_| {}).unwrap();
    assert_eq!(real.data.targets, simulated.data.targets);
    assert_eq!(real.data.inputs, simulated.data.inputs);
    assert_eq!(real.data.meta.source, "real");
    // A collection that would leave the workspace never moves the arm.
    let narrow = HardwareConfig {
        workspace: Workspace {
            min: [edge.x - 2.0, edge.y - 2.0, -15.0],
            max: [edge.x + 2.0, edge.y + 2.0, 20.0],
            ..Workspace::default()
        },
        ..hw
    };
    let err = collect_hardware(&narrow, &cfg, "rig", &StopFlag::new(), |_| {})
        .err()
        .unwrap();
    assert!(err.to_string().contains("outside the workspace"), "{err}");
}

#[test]
fn a_rig_file_without_workspace_or_with_the_start_outside_is_refused() {
    let text = r#"
[arm]
host = "127.0.0.1"
[camera.folder]
path = "/nonexistent"
[start]
x_mm = 0.0
y_mm = 0.0
"#;
    let err = HardwareConfig::from_toml(text, "rig.toml").err().unwrap();
    assert!(err.to_string().contains("workspace"), "{err}");
    let text = format!("{text}[workspace]\nmin = [10.0, 10.0, -15.0]\nmax = [50.0, 50.0, 20.0]\n");
    let cfg = HardwareConfig::from_toml(&text, "rig.toml").unwrap();
    let err = cfg.validate().err().unwrap();
    assert!(
        err.is_bad_input() && err.to_string().contains("outside the workspace"),
        "{err}"
    );
    let unknown = format!("{text}speed = 3\n");
    assert!(HardwareConfig::from_toml(&unknown, "rig.toml").is_err());
}

#[test]
fn the_rig_file_example_of_the_hardware_guide_is_valid() {
    let text = include_str!("../../../../docs/hardware.md");
    let block = text
        .split("```toml\n")
        .skip(1)
        .filter_map(|rest| rest.split("```").next())
        .find(|b| b.contains("[camera.v4l2]") && b.contains("[workspace]"))
        .expect("docs/hardware.md has a rig file example");
    let cfg = HardwareConfig::from_toml(block, "docs/hardware.md").unwrap();
    cfg.validate().unwrap();
    assert_eq!(cfg.arm.tcp.rx, 180.0);
    assert!(matches!(&cfg.camera, FrameSourceConfig::V4l2(c) if c.device == "/dev/video0"));
}
