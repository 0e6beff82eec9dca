//! The real-rig path end to end without a robot: the UR5 driver talks to
//! the loopback fake controller and the camera replays the frames a
//! simulated run captured. Fed the same frames, the hardware path must
//! command exactly the trajectory the simulated path commanded: the same
//! pipeline runs on both rigs.
use std::path::{Path, PathBuf};
use tactrace_arm::Workspace;
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_hw::{FakeUrController, FakeUrOptions, PreprocessConfig};
use tactrace_lab::collect::{collect, CollectConfig};
use tactrace_lab::follow::{run_servo, start_pose, FollowRunConfig, LoopSettings};
use tactrace_lab::hardware::{run_follow_hardware, CameraConfig, HardwareConfig, HardwareStart};
use tactrace_lab::train::{resolve_config, train};
use tactrace_learn::{ModelKind, Preset};
use tactrace_sensor::{Frame, SensorError, TactileSensor};

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

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tactrace-hw-{tag}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn trajectory(dir: &Path) -> String {
    std::fs::read_to_string(dir.join("trajectory.csv")).unwrap()
}

#[test]
fn replayed_frames_on_the_fake_ur5_command_the_simulated_trajectory() {
    const STEPS: usize = 12;
    let sim = FollowRunConfig::simulated();
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
    let model = train(&mcfg, &data, &mut |_| {}).unwrap().0;

    // The simulated run, recording its frames (reference first).
    let start = start_pose(&disk, &sim.start, sim.rig.tap.height_mm).unwrap();
    let mut follow = sim.follow.clone();
    follow.steps = Some(STEPS);
    let settings = LoopSettings {
        blob: &sim.rig.blob,
        controller: &sim.controller,
        follow: &follow,
        tap: &sim.rig.tap,
        contact_threshold_px: sim.contact_threshold_px,
    };
    let frames = scratch("frames");
    let sim_out = scratch("sim");
    let mut rig =
        tactrace_lab::rig::SimRig::new(&sim.rig, disk.clone(), start, follow.seed).unwrap();
    let reference = rig.reference_frame();
    let mut recorder = Recorder {
        inner: &mut rig.sensor,
        dir: frames.clone(),
        count: 0,
    };
    recorder.save(&reference);
    let (sim_summary, _) = run_servo(
        &mut rig.arm,
        &mut recorder,
        &reference,
        model.clone(),
        &settings,
        &sim_out,
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(sim_summary.steps, STEPS, "{}", sim_summary.message);

    // The same frames through the UR5 driver and the camera sensor.
    let fake = FakeUrController::start(FakeUrOptions {
        start: [
            start.x / 1000.0,
            start.y / 1000.0,
            (start.z + 5.0) / 1000.0,
            0.0,
            0.0,
            start.rz.to_radians(),
        ],
        ..FakeUrOptions::default()
    })
    .unwrap();
    let hw = HardwareConfig {
        arm: fake.config(),
        camera: CameraConfig::Folder {
            path: frames.clone(),
            looping: false,
        },
        preprocess: PreprocessConfig::grayscale_only(),
        workspace: Workspace {
            min: [start.x - 60.0, start.y - 60.0, -15.0],
            max: [start.x + 60.0, start.y + 60.0, 20.0],
            ..Workspace::default()
        },
        start: HardwareStart {
            x_mm: start.x,
            y_mm: start.y,
            angle_deg: start.rz,
        },
        tap: sim.rig.tap,
        blob: sim.rig.blob.clone(),
        controller: sim.controller.clone(),
        follow: follow.clone(),
        contact_threshold_px: sim.contact_threshold_px,
    };
    let hw_out = scratch("hw");
    let res = run_follow_hardware(&hw, model, Some(&disk), &hw_out, &mut |_| {}).unwrap();
    assert_eq!(res.summary.steps, STEPS, "{}", res.summary.message);
    assert_eq!(trajectory(&hw_out), trajectory(&sim_out));
    assert!(res.metrics.is_some() && hw_out.join("metrics.json").exists());
    // Every move went to the controller as URScript.
    let moves = fake
        .received_lines()
        .iter()
        .filter(|l| l.contains("movel"))
        .count();
    assert!(moves >= 3 * STEPS - 1, "{moves} movel commands");
    for d in [frames, sim_out, hw_out] {
        std::fs::remove_dir_all(d).ok();
    }
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
