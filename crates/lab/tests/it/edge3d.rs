//! edge_5d following in simulation (issue 23 item 4): a small model trained
//! on taps at one point of a curved edge (the extruded disk's rim) follows
//! the rim part of the way; the run folder's metrics say how near the
//! edge it stayed.
use tactrace_control::Task;
use tactrace_lab::collect3d::{collect_3d, Collect3dConfig};
use tactrace_lab::follow::edge3d::{edge_of, run_edge, start_pose, Edge3dConfig};
use tactrace_lab::follow::edge3d_results::edge_truth;
use tactrace_lab::train::{resolve_config, train};
use tactrace_learn::{ModelKind, Preset};
use tactrace_servo::{Ending, RigConfig};
use tactrace_shape3d::{ObjectConfig, Surface};
use tactrace_store::StoredModel;

fn object(name: &str) -> Surface {
    ObjectConfig::named(name).unwrap().build().unwrap()
}

#[test]
fn edge_truth_of_the_start_is_the_reference() {
    let foil = object("foil");
    let edge = edge_of(&foil, "foil").unwrap();
    let cfg = Edge3dConfig::default();
    let start = start_pose(&edge, &cfg);
    let t = edge_truth(&edge, start, cfg.controller.reference);
    assert_eq!(t.sample, 0);
    assert!(t.distance_mm < 1e-6, "{t:?}");
    assert!((t.label[2] - 3.0).abs() < 1e-9 && t.label[0].abs() < 1e-9);
    assert!(t.normal_error_deg < 1e-6);
    // The foil's face is tilted at its first sample (x = 40 mm).
    assert!(start.ry.abs() > 20.0, "{start:?}");
    // An object without an edge is refused.
    assert!(edge_of(&object("saddle"), "saddle").is_err_and(|e| e.is_bad_input()));
}

#[test]
fn the_step_cap_doubles_with_the_curvature_policy_on() {
    let bowl = object("bowl");
    let edge = edge_of(&bowl, "bowl").unwrap();
    let mut cfg = Edge3dConfig::default();
    // The rim, about 377 mm, at 1 mm a step: 1.5 times that, plus 10.
    let length = edge.length();
    assert!(
        (length - 120.0 * std::f64::consts::PI).abs() < 1.0,
        "{length}"
    );
    assert_eq!(cfg.steps(&edge), (1.5 * length).ceil() as usize + 10);
    cfg.controller.policy.step_curvature_mm = 5.0;
    assert_eq!(cfg.steps(&edge), (3.0 * length).ceil() as usize + 10);
    cfg.max_steps = Some(100);
    assert_eq!(cfg.steps(&edge), 100);
}

#[test]
fn edge_5d_follows_a_curved_rim_and_writes_metrics() {
    let disk = object("disk");
    // Taps near the poses a run meets (x +-3 mm, tilts +-8, rz +-30 deg).
    let collect = Collect3dConfig {
        samples: 400,
        seed: 5,
        task: Task::Edge5d,
        x_range_mm: 3.0,
        tilt_range_deg: 8.0,
        rz_range_deg: 30.0,
        ..Collect3dConfig::default()
    };
    let rig = RigConfig::default();
    let data = collect_3d(&rig, &disk, &collect, "disk", |_| {})
        .unwrap()
        .data;
    let model_cfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, Some(15)).unwrap();
    let (net, _) = train(&model_cfg, &data, &mut |_| {}).unwrap();
    let model = StoredModel::new(net, data.meta.reference_pins.clone());
    let cfg = Edge3dConfig {
        max_steps: Some(40),
        ..Edge3dConfig::default()
    };
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("run");
    let res = run_edge(&cfg, &disk, "disk", &model, (&out, false), &mut |_| {}).unwrap();
    assert_eq!(
        res.summary.ending,
        Ending::StepCap,
        "{}",
        res.summary.message
    );
    let text = std::fs::read_to_string(out.join("metrics.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "mean_distance_mm",
        "max_distance_mm",
        "mean_normal_error_deg",
        "coverage",
        "closed",
        "ending",
        "mean_abs_error",
    ] {
        assert!(m.get(key).is_some(), "{key} missing: {text}");
    }
    assert_eq!(m["task"], "edge_5d");
    assert_eq!(m["closed"], false);
    assert_eq!(m["steps"], 40);
    let metrics = &res.metrics;
    assert!(metrics.mean_distance_mm < 1.0, "{text}");
    assert!(metrics.mean_normal_error_deg < 5.0, "{text}");
    // 40 steps of 1 mm along the rim (347 mm): about 40 mm of it passed.
    let expected = 39.0 / metrics.edge_length_mm;
    assert!((metrics.coverage - expected).abs() < 0.03, "{text}");
    for f in [
        "config.toml",
        "trajectory.csv",
        "replay.html",
        "trajectory_3d.png",
        "errors.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert!(csv.starts_with("step,x_mm,y_mm,z_mm,rx_deg,ry_deg,rz_deg,x_pred_mm"));
    assert_eq!(csv.lines().count(), 41);
}
