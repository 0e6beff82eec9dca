//! Issue 20 on the real-rig path, against the loopback fake UR5 (and the
//! fake dashboard for `rig check`): a state no UR arm can be in, a frozen
//! arm or a protective stop on the way to the start, a start too far away,
//! and a stop request (what SIGINT/SIGTERM set) during a follow run and a
//! collection. Nothing moves on a bad state; a stop sends `stopl`; a
//! follow run keeps its steps in `OUT.partial`; each failure has its kind
//! and exit code.
use crate::common;
use common::fake_rig::{fake_ur5_above, lines_after_hang_up, moves, rig_file, write_replay_frames};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Duration;
use tactrace_arm::ArmError;
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_hw::{
    FakeBehaviour, FakeDashboard, FakeDashboardState, FakeStateFault, FakeUrController,
    FakeUrOptions, StateInterface,
};
use tactrace_lab::collect::{collect, CollectConfig};
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::follow::{run, RunHooks};
use tactrace_lab::hardware::{collect_hardware, rig_check, HardwareConfig, StopFlag, StopSignal};
use tactrace_lab::train::{resolve_config, train};
use tactrace_lab::world::World;
use tactrace_lab::LabError;
use tactrace_learn::{ModelKind, Preset};
use tactrace_servo::pose_at_edge;
use tactrace_store::StoredModel;

/// A small model and the frames of a simulated collection (reference
/// first), with the collection's settings and its first pose's edge.
struct Fixture {
    model: StoredModel,
    frames: PathBuf,
    collect: CollectConfig,
    edge: (f64, f64, f64),
    _root: tempfile::TempDir,
}

fn fixture() -> &'static Fixture {
    static FIXTURE: OnceLock<Fixture> = OnceLock::new();
    FIXTURE.get_or_init(|| {
        let sim = SimFollowConfig::default();
        let disk = builtin_shape(BuiltinShape::Disk);
        let cfg = CollectConfig {
            samples: 40,
            seed: 8,
            save_frames: true,
            ..CollectConfig::default()
        };
        let got = collect(&sim.rig, &disk, &cfg, "disk", |_| {}).unwrap();
        let mcfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, Some(3)).unwrap();
        let net = train(&mcfg, &got.data, &mut |_| {}).unwrap().0;
        let model = StoredModel::new(net, got.data.meta.reference_pins.clone());
        let root = tempfile::tempdir().unwrap();
        let frames = root.path().join("frames");
        std::fs::create_dir_all(&frames).unwrap();
        write_replay_frames(&frames, &got.frames);
        let (edge, normal) = disk.at_arc_length(cfg.edge_arc_mm);
        let angle = normal.y.atan2(normal.x).to_degrees();
        Fixture {
            model,
            frames,
            collect: cfg,
            edge: (edge.x, edge.y, angle),
            _root: root,
        }
    })
}

/// The fake UR5 with its tool 5 mm above the work-frame point (x, y) at
/// tap height, turned by `angle` degrees; `options` for the rest.
fn fake_at(x: f64, y: f64, angle: f64, options: FakeUrOptions) -> FakeUrController {
    let height = SimFollowConfig::default().rig.tap.height_mm;
    fake_ur5_above([x, y, height], angle, options)
}

/// A rig file for `fake` at the fixture's edge, looping over its frames,
/// 8 steps.
fn rig_at_edge(fake: &FakeUrController) -> HardwareConfig {
    let f = fixture();
    let mut arm = fake.config();
    arm.timeout_s = 1.0;
    let mut cfg = rig_file(arm, (&f.frames, true), f.edge, 80.0);
    cfg.follow.steps = Some(8);
    cfg
}

/// The fake near the fixture's start.
fn fake_near_start(options: FakeUrOptions) -> FakeUrController {
    let (x, y, angle) = fixture().edge;
    fake_at(x, y, angle, options)
}

/// A follow run into a fresh folder: its result, `out`, and the folder.
fn follow_on(cfg: &HardwareConfig, stop: &StopFlag, at_step: Option<usize>) -> FollowTry {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("run");
    let asker = stop.clone();
    let mut progress = |r: &tactrace_servo::StepRecord| {
        if Some(r.step) == at_step {
            asker.request(StopSignal::Interrupt);
        }
    };
    let hooks = RunHooks {
        progress: Some(&mut progress),
        stop: Some(stop),
        ..RunHooks::default()
    };
    let result = World::Hardware(cfg.clone())
        .open()
        .and_then(|world| run(world, &fixture().model, None, (&out, false), hooks))
        .map(|_| ());
    FollowTry {
        result,
        out,
        _root: root,
    }
}

struct FollowTry {
    result: Result<(), LabError>,
    out: PathBuf,
    _root: tempfile::TempDir,
}

fn partial(out: &Path) -> PathBuf {
    out.with_file_name("run.partial")
}

#[test]
fn an_impossible_state_moves_nothing_and_is_a_fault() {
    let faults = [
        FakeStateFault::HugePosition,
        FakeStateFault::HugeRotation,
        FakeStateFault::NotFinite,
    ];
    for state in [StateInterface::Realtime, StateInterface::Rtde] {
        for state_fault in faults {
            let fake = fake_near_start(FakeUrOptions {
                state,
                state_fault,
                ..FakeUrOptions::default()
            });
            let run = follow_on(&rig_at_edge(&fake), &StopFlag::new(), None);
            let err = run.result.unwrap_err();
            assert!(
                matches!(err, LabError::Hardware(_)) && !err.is_bad_input(),
                "{state:?} {state_fault:?}: {err}"
            );
            assert!(err.signal_exit_code().is_none());
            let text = err.to_string();
            assert!(
                text.contains("impossible") || text.contains("not finite"),
                "{text}"
            );
            assert!(!run.out.exists() && !partial(&run.out).exists());
            let lines = lines_after_hang_up(&fake);
            assert_eq!(moves(&lines).0, 0, "{state:?} {state_fault:?}: {lines:#?}");
        }
    }
}

#[test]
fn a_frozen_arm_or_a_protective_stop_on_the_way_to_the_start_is_a_fault() {
    for behaviour in [
        FakeBehaviour::IgnoreMoves,
        FakeBehaviour::ProtectiveStopOnMove,
    ] {
        let fake = fake_near_start(FakeUrOptions {
            behaviour,
            state: StateInterface::Rtde,
            ..FakeUrOptions::default()
        });
        let run = follow_on(&rig_at_edge(&fake), &StopFlag::new(), None);
        let err = run.result.unwrap_err();
        assert!(
            matches!(
                &err,
                LabError::StartMove {
                    source: ArmError::Hardware(_)
                }
            ),
            "{behaviour:?}: {err}"
        );
        assert!(!err.is_bad_input(), "a fault is exit 1: {err}");
        let chain = anyhow_like(&err);
        let reason = match behaviour {
            FakeBehaviour::IgnoreMoves => "timeout",
            _ => "protective stop",
        };
        assert!(chain.contains(reason), "{chain}");
        assert!(!chain.contains("invalid configuration"), "{chain}");
        let lines = lines_after_hang_up(&fake);
        assert_eq!(moves(&lines), (1, true), "{behaviour:?}: {lines:#?}");
    }
}

#[test]
fn a_start_beyond_the_step_limit_is_the_set_up_and_moves_nothing() {
    let (x, y, angle) = fixture().edge;
    let fake = fake_at(x + 66.0, y, angle, FakeUrOptions::default());
    let run = follow_on(&rig_at_edge(&fake), &StopFlag::new(), None);
    let err = run.result.unwrap_err();
    assert!(
        matches!(
            &err,
            LabError::StartMove {
                source: ArmError::StepTooLarge { .. }
            }
        ),
        "{err}"
    );
    assert!(err.is_bad_input(), "the set-up is exit 2: {err}");
    assert!(err.to_string().contains("jog the arm"), "{err}");
    assert_eq!(moves(&lines_after_hang_up(&fake)).0, 0);
}

#[test]
fn a_stop_mid_follow_sends_stopl_and_keeps_the_steps_in_partial() {
    let fake = fake_near_start(FakeUrOptions {
        state: StateInterface::Rtde,
        ..FakeUrOptions::default()
    });
    let stop = StopFlag::new();
    let run = follow_on(&rig_at_edge(&fake), &stop, Some(2));
    let err = run.result.unwrap_err();
    let LabError::Interrupted {
        signal,
        arm_stopped,
        kept,
    } = &err
    else {
        panic!("{err}");
    };
    assert_eq!((*signal, *arm_stopped), (StopSignal::Interrupt, true));
    assert!(err.to_string().contains("the arm was sent stopl"), "{err}");
    assert_eq!(err.signal_exit_code(), Some(130));
    assert_eq!(kept.as_deref(), Some(partial(&run.out).as_path()));
    assert!(stop.halted());
    assert!(!run.out.exists(), "an interrupted run is not complete");
    let csv = std::fs::read_to_string(partial(&run.out).join("trajectory.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 3, "{csv}");
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.split(',').count(), 8, "{row}");
        assert!(row.starts_with(&format!("{k},")), "{row}");
    }
    assert!(partial(&run.out).join("metrics.json").exists());
    let lines = lines_after_hang_up(&fake);
    // The start, the tap down, the tap up and the next pose of steps 0
    // and 1, step 2's tap: nothing after the request but stopl.
    assert_eq!(moves(&lines), (1 + 3 * 2 + 2, true), "{lines:#?}");
}

#[test]
fn a_stop_before_the_arm_is_connected_moves_nothing() {
    let fake = fake_near_start(FakeUrOptions::default());
    let stop = StopFlag::new();
    stop.request(StopSignal::Terminate);
    let run = follow_on(&rig_at_edge(&fake), &stop, None);
    let err = run.result.unwrap_err();
    assert!(
        matches!(
            err,
            LabError::Interrupted {
                signal: StopSignal::Terminate,
                arm_stopped: false,
                kept: None
            }
        ),
        "{err}"
    );
    assert_eq!(err.signal_exit_code(), Some(143));
    assert!(stop.halted(), "a second signal may end the process now");
    assert!(!run.out.exists() && !partial(&run.out).exists());
    assert_eq!(moves(&fake.received_lines()).0, 0);
}

#[test]
fn a_stop_mid_collection_sends_stopl_and_ends_it() {
    let f = fixture();
    let fake = {
        let sim = SimFollowConfig::default();
        let disk = builtin_shape(BuiltinShape::Disk);
        let (edge, normal) = disk.at_arc_length(f.collect.edge_arc_mm);
        let first = pose_at_edge(
            edge,
            normal,
            0.0,
            -f.collect.theta_range_deg,
            sim.rig.tap.height_mm,
        );
        fake_at(first.x, first.y, first.rz, FakeUrOptions::default())
    };
    let stop = StopFlag::new();
    let asker = stop.clone();
    let err = collect_hardware(&rig_at_edge(&fake), &f.collect, "rig", &stop, |i| {
        if i == 3 {
            asker.request(StopSignal::Terminate);
        }
    })
    .err()
    .unwrap();
    assert!(
        matches!(
            err,
            LabError::Interrupted {
                signal: StopSignal::Terminate,
                arm_stopped: true,
                kept: None
            }
        ),
        "{err}"
    );
    assert_eq!(err.signal_exit_code(), Some(143));
    let lines = lines_after_hang_up(&fake);
    // The first pose, then three moves a sample for samples 0..=2.
    assert_eq!(moves(&lines), (1 + 3 * 3, true), "{lines:#?}");
}

#[test]
fn rig_check_is_not_ready_on_an_impossible_state_or_a_start_too_far() {
    let (x, y, angle) = fixture().edge;
    let dashboard =
        FakeDashboard::start(FakeDashboardState::default(), Duration::from_secs(20)).unwrap();
    let check = |fake: &FakeUrController| {
        let mut cfg = rig_at_edge(fake);
        cfg.arm.dashboard_port = dashboard.port();
        rig_check(&cfg, None, None).unwrap()
    };
    let huge = fake_at(
        x,
        y,
        angle,
        FakeUrOptions {
            state: StateInterface::Rtde,
            state_fault: FakeStateFault::HugePosition,
            ..FakeUrOptions::default()
        },
    );
    let report = check(&huge);
    let state = report.items.iter().find(|i| i.name == "state").unwrap();
    assert!(!state.ready && !report.ready(), "{report:#?}");
    assert!(state.detail.contains("1.000e306 m"), "{state:?}");
    assert!(!state.detail.contains("NaN"), "{state:?}");
    let far = fake_at(
        x + 666.0,
        y,
        angle,
        FakeUrOptions {
            state: StateInterface::Rtde,
            ..FakeUrOptions::default()
        },
    );
    let report = check(&far);
    let state = report.items.iter().find(|i| i.name == "state").unwrap();
    assert!(!state.ready && !report.ready(), "{report:#?}");
    assert!(
        state.detail.contains("666.0 mm from the start")
            && state
                .detail
                .contains("follow would refuse the move to the start"),
        "{state:?}"
    );
    assert!(huge.received_lines().is_empty() && far.received_lines().is_empty());
}

/// `err` with its sources, as the binary prints it (`{:#}`).
fn anyhow_like(err: &LabError) -> String {
    let mut text = err.to_string();
    let mut next = std::error::Error::source(err);
    while let Some(e) = next {
        text.push_str(": ");
        text.push_str(&e.to_string());
        next = e.source();
    }
    text
}
