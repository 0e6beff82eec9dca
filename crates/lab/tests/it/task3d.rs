//! The surface_3d task end to end in simulation (issue 23 items 4-5): a
//! collection on a 3D object with named targets, a small model trained on
//! it, and a follow run over a flat floor scored into metrics.json.
use std::sync::OnceLock;
use tactrace_control::Task;
use tactrace_lab::collect3d::{collect_3d, Collect3dConfig};
use tactrace_lab::follow::task3d::{run_surface, PathConfig, Surface3dConfig};
use tactrace_lab::follow::Run3dSettings;
use tactrace_lab::train::{resolve_config, train};
use tactrace_learn::{ModelKind, Preset, Unit};
use tactrace_servo::{Ending, RigConfig};
use tactrace_shape3d::{ObjectConfig, Surface};
use tactrace_store::{StoredModel, TapData};

fn object(name: &str) -> Surface {
    ObjectConfig::named(name).unwrap().build().unwrap()
}

/// 120 taps on the flat floor, collected once for the tests here.
fn data() -> &'static TapData {
    static DATA: OnceLock<TapData> = OnceLock::new();
    DATA.get_or_init(|| {
        let cfg = Collect3dConfig {
            samples: 120,
            seed: 3,
            ..Collect3dConfig::default()
        };
        collect_3d(
            &RigConfig::default(),
            &object("plane"),
            &cfg,
            "plane",
            |_| {},
        )
        .unwrap()
        .data
    })
}

/// A small DisDenNN (one hidden layer of 16, 3 epochs) of [`data`], with
/// its pins.
fn small_model() -> StoredModel {
    let cfg = resolve_config(
        ModelKind::DisDenNN,
        Preset::Default,
        Some("[pose]\nhidden = [16]\n"),
        Some(3),
    )
    .unwrap();
    let (net, _) = train(&cfg, data(), &mut |_| {}).unwrap();
    StoredModel::new(net, data().meta.reference_pins.clone())
}

#[test]
fn collect_surface_3d_writes_named_targets_in_the_anchors_ranges() {
    let d = data();
    let c = &d.meta.target_columns;
    assert_eq!(c.target_names, ["z", "rx", "ry"]);
    assert_eq!(c.target_units, [Unit::Mm, Unit::Deg, Unit::Deg]);
    assert_eq!(c.target_circular, [false; 3]);
    assert_eq!(d.meta.targets, ["z (mm)", "rx (deg)", "ry (deg)"]);
    assert_eq!(d.targets.len(), 3 * 120);
    assert_eq!(d.inputs.len(), 120 * 2 * d.meta.pins);
    let targets = d.meta.model_targets().unwrap();
    assert_eq!(targets.len(), 3);
    for row in d.targets.chunks(3) {
        assert!((1.0..=5.0).contains(&row[0]), "{row:?}");
        assert!(row[1].abs() <= 25.0 && row[2].abs() <= 25.0, "{row:?}");
    }
    // The taps feel the depth: a deeper press moves the pins further.
    let p = d.meta.pins;
    let mean_disp = |i: usize| {
        let r = &d.inputs[i * 2 * p..(i + 1) * 2 * p];
        (0..p).map(|k| f32::hypot(r[k], r[p + k])).sum::<f32>() / p as f32
    };
    let (shallow, deep): (Vec<usize>, Vec<usize>) = (0..120)
        .filter(|&i| d.targets[3 * i] < 2.0 || d.targets[3 * i] > 4.0)
        .partition(|&i| d.targets[3 * i] < 2.0);
    let avg = |v: &[usize]| v.iter().map(|&i| mean_disp(i)).sum::<f32>() / v.len() as f32;
    assert!(
        avg(&deep) > avg(&shallow) * 1.3,
        "{} {}",
        avg(&deep),
        avg(&shallow)
    );
    // The planar task is collected with --shape, not here.
    let edge = Collect3dConfig {
        task: Task::Edge2d,
        ..Collect3dConfig::default()
    };
    assert!(edge.validate().is_err());
}

#[test]
fn collect_edge_5d_on_the_foil_writes_five_targets_rz_circular() {
    let cfg = Collect3dConfig {
        samples: 40,
        seed: 4,
        task: Task::Edge5d,
        ..Collect3dConfig::default()
    };
    let d = collect_3d(&RigConfig::default(), &object("foil"), &cfg, "foil", |_| {})
        .unwrap()
        .data;
    let c = &d.meta.target_columns;
    assert_eq!(c.target_names, ["x", "z", "rx", "ry", "rz"]);
    assert_eq!(c.target_circular, [false, false, false, false, true]);
    assert_eq!(d.meta.model_targets().unwrap().len(), 5);
    for row in d.targets.chunks(5) {
        assert!(
            row[0].abs() <= 5.0 && (1.0..=5.0).contains(&row[1]),
            "{row:?}"
        );
        assert!(row[2].abs() <= 25.0 && row[3].abs() <= 25.0, "{row:?}");
        assert!(row[4].abs() <= 180.0, "{row:?}");
    }
    let rz: Vec<f32> = d.targets.chunks(5).map(|r| r[4]).collect();
    assert!(rz.iter().any(|v| *v > 90.0) && rz.iter().any(|v| *v < -90.0));
    // An object without an edge cannot give edge_5d taps.
    let err = collect_3d(
        &RigConfig::default(),
        &object("saddle"),
        &cfg,
        "saddle",
        |_| {},
    );
    assert!(err.is_err_and(|e| e.is_bad_input() && e.to_string().contains("no edge")));
}

#[test]
fn follow_surface_3d_on_a_plane_writes_metrics_and_figures() {
    let model = small_model();
    let run_cfg = Surface3dConfig {
        path: PathConfig {
            length_mm: 6.0,
            ..PathConfig::for_object("plane")
        },
        run: Run3dSettings {
            settle_steps: 2,
            ..Run3dSettings::default()
        },
        ..Surface3dConfig::default()
    };
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("run");
    let mut seen = 0;
    let res = run_surface(
        &run_cfg,
        &object("plane"),
        "plane",
        &model,
        (&out, false),
        &mut |_| seen += 1,
    )
    .unwrap();
    assert_eq!(res.dir, out);
    assert!(seen >= 1);
    let text = std::fs::read_to_string(out.join("metrics.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "mean_distance_mm",
        "max_distance_mm",
        "mean_normal_error_deg",
        "coverage",
        "closed",
        "ending",
    ] {
        assert!(m.get(key).is_some(), "{key} missing: {text}");
    }
    assert_eq!(m["closed"], false);
    if res.summary.ending == Ending::StepsDone {
        assert_eq!(m["steps"], 7);
    }
    for f in [
        "config.toml",
        "trajectory.csv",
        "replay.html",
        "trajectory_3d.png",
        "trajectory_3d.svg",
        "errors.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert!(csv.starts_with("step,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,z_pred_mm"));
    assert_eq!(csv.lines().count(), 1 + res.metrics.steps);
}

/// The real-frame world for surfaces on a synthetic bank (simulated taps
/// standing in for real rows): every tap is answered by a bank row, listed
/// in answers.csv with its labels and label distance, and the run is
/// scored as a simulated one.
#[test]
fn surface_replay_answers_every_tap_from_the_bank() {
    use tactrace_lab::follow::surface_replay::run_surface_replay;
    use tactrace_lab::world::SurfaceBank;
    let model = small_model();
    let bank = SurfaceBank::from_dataset(data()).unwrap();
    assert_eq!(bank.len(), 120);
    let run_cfg = Surface3dConfig {
        path: PathConfig {
            length_mm: 5.0,
            ..PathConfig::for_object("plane")
        },
        run: Run3dSettings {
            settle_steps: 1,
            ..Run3dSettings::default()
        },
        ..Surface3dConfig::default()
    };
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("run");
    let plane = object("plane");
    let (res, stats) = run_surface_replay(
        &run_cfg,
        (&plane, "plane"),
        &bank,
        &model,
        (&out, false),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(stats.taps, res.metrics.steps);
    assert_eq!(stats.bank_rows, 120);
    assert!(stats.mean_label_distance.is_finite() && stats.max_label_distance >= 0.0);
    let answers = std::fs::read_to_string(out.join("answers.csv")).unwrap();
    let mut lines = answers.lines();
    assert_eq!(
        lines.next(),
        Some("step,row,image,label_distance,z_mm,rx_deg,ry_deg")
    );
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let row: usize = f[1].parse().unwrap();
        let l = bank.label(row);
        for k in 0..3 {
            let v: f64 = f[4 + k].parse().unwrap();
            assert!((v - l[k]).abs() < 1e-3, "{line}");
        }
    }
    assert!(out.join("replay.json").is_file() && out.join("metrics.json").is_file());
    assert_eq!(
        stats.bank_rows_seen_in_training, None,
        "this model records no training rows"
    );
    // A bank whose rows the model was trained on says so in replay.json.
    let out2 = root.path().join("run-seen");
    let seen = bank.clone().with_rows_seen_in_training(Some(7));
    let (_, stats) = run_surface_replay(
        &run_cfg,
        (&plane, "plane"),
        &seen,
        &model,
        (&out2, false),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(stats.bank_rows_seen_in_training, Some(7));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out2.join("replay.json")).unwrap()).unwrap();
    assert_eq!(json["bank_rows_seen_in_training"], 7);
}
