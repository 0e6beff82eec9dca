//! Issue 21: every world of a follow run builds its arm, sensor and
//! perception and runs a few steps through the one `follow::run`, into a
//! run folder whose `config.toml` runs the same world again: the simulated
//! TacTip, a (tiny) calibrated sensor, the real-frame world on the shared
//! set, and the real rig (the fake UR5 on loopback and a folder camera).
use crate::common;
use common::fake_rig::{fake_ur5_above, rig_file, write_replay_frames};

use std::path::Path;
use std::sync::OnceLock;
use tactrace_geometry::{builtin_shape, BuiltinShape, Contour};
use tactrace_hw::FakeUrOptions;
use tactrace_lab::calibrate::calibrate_sensor;
use tactrace_lab::collect::{collect, collect_calibrated, CollectConfig};
use tactrace_lab::follow::{run, FollowOutcome, RunHooks, SimFollowConfig};
use tactrace_lab::hardware::HardwareConfig;
use tactrace_lab::import::import;
use tactrace_lab::train::{resolve_config, train};
use tactrace_lab::world::{ReplayBank, World};
use tactrace_learn::{ModelKind, Preset};
use tactrace_sensor::TacTipConfig;
use tactrace_store::collection::{CollectionEdits, RowSelection};
use tactrace_store::{LabelledCollection, StoredModel, TapData};

const STEPS: usize = 5;

/// A PDenNN of a few epochs on `data`, with its pins.
fn model_of(data: &TapData) -> StoredModel {
    let cfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, Some(15)).unwrap();
    let net = train(&cfg, data, &mut |_| {}).unwrap().0;
    StoredModel::new(net, data.meta.reference_pins.clone())
}

/// Taps, their frames (name, PNG bytes) and a model of them.
type Simulated = (TapData, Vec<(String, Vec<u8>)>, StoredModel);

/// Taps of the simulated TacTip on the disk (frames kept) and a model of them.
fn simulated() -> &'static Simulated {
    static SET: OnceLock<Simulated> = OnceLock::new();
    SET.get_or_init(|| {
        let cfg = CollectConfig {
            samples: 150,
            seed: 5,
            save_frames: true,
            ..CollectConfig::default()
        };
        let disk = builtin_shape(BuiltinShape::Disk);
        let got = collect(&SimFollowConfig::default().rig, &disk, &cfg, "disk", |_| {}).unwrap();
        let model = model_of(&got.data);
        (got.data, got.frames, model)
    })
}

/// `STEPS` steps of `cfg`'s world on `shape` into `dir/run`; the outcome,
/// checked to have run every step, and its folder's files.
fn run_steps(
    cfg: &SimFollowConfig,
    model: &StoredModel,
    shape: &Contour,
    dir: &Path,
) -> FollowOutcome {
    let mut cfg = cfg.clone();
    cfg.follow.steps = Some(STEPS);
    let world = cfg.world().open().unwrap();
    let out = dir.join("run");
    let res = run(
        world,
        model,
        Some(("disk", shape)),
        (&out, false),
        RunHooks::default(),
    )
    .unwrap();
    assert_eq!(res.summary.steps, STEPS, "{}", res.summary.message);
    assert!(res.summary.ending.succeeded(), "{}", res.summary.message);
    for file in [
        "config.toml",
        "trajectory.csv",
        "metrics.json",
        "replay.html",
    ] {
        assert!(out.join(file).is_file(), "{file}");
    }
    let again: SimFollowConfig =
        tactrace_store::load_config(Some(&out.join("config.toml")), "run").unwrap();
    assert_eq!(
        toml::to_string(&again.world()).unwrap(),
        toml::to_string(&cfg.world()).unwrap(),
        "config.toml runs the same world again"
    );
    res
}

#[test]
fn the_simulated_world_runs_a_few_steps() {
    let (_, _, model) = simulated();
    let root = tempfile::tempdir().unwrap();
    let cfg = SimFollowConfig::default();
    assert!(matches!(cfg.world(), World::Simulated(_)));
    let disk = builtin_shape(BuiltinShape::Disk);
    let res = run_steps(&cfg, model, &disk, root.path());
    assert!(res.metrics.is_some() && res.replay.is_none());
}

/// The calibrated sensor's folder is read once, when its world is opened:
/// the run works on without it.
#[test]
fn the_calibrated_world_reads_its_sensor_once_and_runs() {
    let root = tempfile::tempdir().unwrap();
    let taps = common::distorted_sensor_set(&root.path().join("taps"), 40);
    let cfg = common::calibration(taps, 20);
    let got = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap();
    let dir = root.path().join("sensor");
    got.sensor.write(&dir, false).unwrap();
    let disk = builtin_shape(BuiltinShape::Disk);
    let collect = CollectConfig {
        samples: 150,
        seed: 4,
        ..CollectConfig::default()
    };
    let rig = SimFollowConfig::default().rig;
    let data = collect_calibrated(&rig, &got.sensor, &disk, &collect, "disk", |_| {})
        .unwrap()
        .data;
    let model = model_of(&data);
    let cfg = SimFollowConfig {
        calibrated_sensor: Some(dir.clone()),
        follow: tactrace_servo::LoopConfig {
            steps: Some(STEPS),
            ..SimFollowConfig::default().follow
        },
        ..SimFollowConfig::default()
    };
    assert!(matches!(cfg.world(), World::Calibrated(_)));
    let world = cfg.world().open().unwrap();
    std::fs::rename(&dir, root.path().join("moved")).unwrap();
    let out = root.path().join("run");
    let hooks = RunHooks::default();
    let res = run(world, &model, Some(("disk", &disk)), (&out, false), hooks).unwrap();
    assert_eq!(res.summary.steps, STEPS, "{}", res.summary.message);
    let config = std::fs::read_to_string(out.join("config.toml")).unwrap();
    assert!(config.contains("calibrated_sensor"), "{config}");
    // With the folder back, the whole round trip as any world.
    std::fs::rename(root.path().join("moved"), &dir).unwrap();
    run_steps(&cfg, &model, &disk, &root.path().join("again"));
}

#[test]
fn the_replay_world_answers_from_the_shared_set() {
    let Some(data) = tactrace_testdata::real_edge_set() else {
        return;
    };
    let training = LabelledCollection::bristol(&data).with_rows(RowSelection {
        limit: Some(300),
        keep: None,
    });
    let model = model_of(&import(&training, &|| {}).unwrap().data);
    let held_out = CollectionEdits {
        keep: Some("N%5==0".into()),
        ..CollectionEdits::default()
    };
    let cfg = SimFollowConfig {
        replay: Some(ReplayBank::from_dir(&data, &held_out).unwrap()),
        ..SimFollowConfig::default()
    };
    assert!(matches!(cfg.world(), World::Replay(_)));
    let root = tempfile::tempdir().unwrap();
    let disk = builtin_shape(BuiltinShape::Disk);
    let res = run_steps(&cfg, &model, &disk, root.path());
    let stats = res.replay.expect("the answers' statistics");
    assert_eq!(stats.taps, STEPS);
    assert!(stats.bank_frames >= 700, "the N%5==0 part: {stats:?}");
    let answers = std::fs::read_to_string(root.path().join("run/answers.csv")).unwrap();
    assert_eq!(
        answers.lines().count(),
        STEPS + 1,
        "a header and a line a tap"
    );
}

#[test]
fn the_hardware_world_runs_on_the_fake_ur5_and_a_folder_camera() {
    let (data, frames, model) = simulated();
    let root = tempfile::tempdir().unwrap();
    let folder = root.path().join("frames");
    std::fs::create_dir_all(&folder).unwrap();
    write_replay_frames(&folder, frames);
    assert_eq!(frames.len(), data.len() + 1);
    let sim = SimFollowConfig::default();
    let (edge, normal) = builtin_shape(BuiltinShape::Disk).at_arc_length(0.0);
    let angle = normal.y.atan2(normal.x).to_degrees();
    let height = sim.rig.tap.height_mm;
    let fake = fake_ur5_above([edge.x, edge.y, height], angle, FakeUrOptions::default());
    let mut rig = rig_file(
        fake.config(),
        (&folder, true),
        (edge.x, edge.y, angle),
        80.0,
    );
    rig.follow.steps = Some(STEPS);
    let world = World::Hardware(rig.clone()).open().unwrap();
    let out = root.path().join("run");
    let res = run(world, model, None, (&out, false), RunHooks::default()).unwrap();
    assert_eq!(res.summary.steps, STEPS, "{}", res.summary.message);
    assert!(res.metrics.is_none(), "no contour: not scored");
    let text = std::fs::read_to_string(out.join("config.toml")).unwrap();
    let mut again = HardwareConfig::from_toml(&text, "config.toml").unwrap();
    // (A `[preprocess]` without crop, size or blur reads back with the
    // defaults' crop and blur: the rig file's own overlay, not the run's.)
    again.preprocess = rig.preprocess.clone();
    assert_eq!(
        toml::to_string(&again).unwrap(),
        toml::to_string(&rig).unwrap(),
        "config.toml is the rig file"
    );
    let moves = fake
        .received_lines()
        .iter()
        .filter(|l| l.contains("movel"))
        .count();
    assert!(moves >= 3 * STEPS - 1, "{moves} movel commands");
}
