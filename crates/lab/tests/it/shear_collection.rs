//! The 3D tasks' unlabelled shear in collection and their metrics at the
//! poses the arm reached (issue 23, edge_5d over the anchors' ranges).
//!
//! - A sheared collection has the unsheared one's labels at the same seed,
//!   other pin fields, is the same again at the same seed, and records its
//!   shear in the dataset's meta.
//! - With a noisy simulated arm, a surface run's and an edge run's
//!   metrics are the truths at the reached poses (trajectory.csv's
//!   `*_reached_*` columns), not at the commanded ones.
use std::path::Path;
use std::sync::OnceLock;
use tactrace_arm::Pose;
use tactrace_control::Task;
use tactrace_lab::collect3d::{collect_3d, tap_shear, Collect3dConfig};
use tactrace_lab::follow::edge3d::{edge_of, run_edge, Edge3dConfig};
use tactrace_lab::follow::edge3d_results::edge_truth;
use tactrace_lab::follow::task3d::{run_surface, PathConfig, Surface3dConfig};
use tactrace_lab::follow::Run3dSettings;
use tactrace_lab::train::{resolve_config, train};
use tactrace_learn::{ModelKind, Preset};
use tactrace_servo::RigConfig;
use tactrace_shape3d::{ObjectConfig, Surface};
use tactrace_store::{StoredModel, TapData};

fn object(name: &str) -> Surface {
    ObjectConfig::named(name).unwrap().build().unwrap()
}

fn edge_taps(shear: (f64, f64), samples: usize) -> TapData {
    let cfg = Collect3dConfig {
        samples,
        seed: 9,
        task: Task::Edge5d,
        x_range_mm: 3.0,
        tilt_range_deg: 8.0,
        rz_range_deg: 30.0,
        shear_mm: shear.0,
        shear_deg: shear.1,
        ..Collect3dConfig::default()
    };
    collect_3d(&RigConfig::default(), &object("disk"), &cfg, "disk", |_| {})
        .unwrap()
        .data
}

#[test]
fn shear_keeps_the_labels_moves_the_pins_and_is_recorded() {
    let plain = edge_taps((0.0, 0.0), 24);
    let sheared = edge_taps((5.0, 5.0), 24);
    assert_eq!(
        plain.targets, sheared.targets,
        "the shear is not in the labels"
    );
    let p = plain.meta.pins;
    let mut moved = 0;
    for (a, b) in plain.inputs.chunks(2 * p).zip(sheared.inputs.chunks(2 * p)) {
        let diff = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        moved += usize::from(diff > 0.3);
    }
    assert!(
        moved >= 20,
        "the shear moves the pins of most taps: {moved} of 24"
    );
    // Seeded: the same again.
    assert_eq!(sheared.inputs, edge_taps((5.0, 5.0), 24).inputs);
    // Recorded in the meta.
    let meta = serde_json::to_value(&sheared.meta).unwrap();
    let text = meta.to_string();
    assert!(text.contains("\"shear_mm\":5.0"), "{text}");
    assert!(text.contains("\"shear_deg\":5.0"), "{text}");
    // The draws stay in their ranges and vary from tap to tap.
    let cfg = Collect3dConfig {
        shear_mm: 2.0,
        shear_deg: 3.0,
        ..Collect3dConfig::default()
    };
    let draws: Vec<_> = (0..200).map(|i| tap_shear(&cfg, i).unwrap()).collect();
    assert!(draws
        .iter()
        .all(|s| s.dx_mm.abs() <= 2.0 && s.dy_mm.abs() <= 2.0 && s.drz_deg.abs() <= 3.0));
    assert!(draws.iter().any(|s| s.dx_mm > 1.5) && draws.iter().any(|s| s.drz_deg < -2.5));
    assert!(tap_shear(&Collect3dConfig::default(), 0).is_none());
    // Ranges that cannot work are bad input.
    for (m, a) in [(-1.0, 0.0), (0.0, f64::NAN), (11.0, 0.0), (0.0, 50.0)] {
        let bad = Collect3dConfig {
            shear_mm: m,
            shear_deg: a,
            ..Collect3dConfig::default()
        };
        assert!(bad.validate().is_err_and(|e| e.is_bad_input()), "{m} {a}");
    }
}

/// A 3D run, seed 3, on a rig whose arm misses its poses by about
/// 0.4 mm and 2 deg.
fn noisy_run() -> Run3dSettings {
    let mut run = Run3dSettings {
        seed: 3,
        ..Run3dSettings::default()
    };
    run.rig.arm.repeatability_mm = 0.4;
    run.rig.arm.repeatability_deg = 2.0;
    run
}

/// A quickly trained model of `data`.
fn model_of(data: &TapData) -> StoredModel {
    let cfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, Some(8)).unwrap();
    let (net, _) = train(&cfg, data, &mut |_| {}).unwrap();
    StoredModel::new(net, data.meta.reference_pins.clone())
}

/// trajectory.csv as a header and rows of cells.
fn trajectory(dir: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let mut lines = text
        .lines()
        .map(|l| l.split(',').map(String::from).collect());
    let header: Vec<String> = lines.next().unwrap();
    (header, lines.collect())
}

/// The commanded and the reached pose of each row.
fn poses(header: &[String], rows: &[Vec<String>]) -> Vec<(Pose, Pose)> {
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let names = ["x", "y", "z", "rx", "ry", "rz"];
    let read = |row: &[String], suffix: &str| {
        let v: Vec<f64> = names
            .iter()
            .map(|n| {
                let unit = if n.starts_with('r') { "deg" } else { "mm" };
                row[col(&format!("{n}{suffix}_{unit}"))].parse().unwrap()
            })
            .collect();
        Pose::new(v[0], v[1], v[2], v[3], v[4], v[5])
    };
    rows.iter()
        .map(|r| (read(r, ""), read(r, "_reached")))
        .collect()
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.collect();
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn surface_metrics_are_at_the_reached_poses() {
    static MODEL: OnceLock<StoredModel> = OnceLock::new();
    let plane = object("plane");
    let model = MODEL.get_or_init(|| {
        let cfg = Collect3dConfig {
            samples: 150,
            seed: 4,
            ..Collect3dConfig::default()
        };
        model_of(
            &collect_3d(&RigConfig::default(), &plane, &cfg, "plane", |_| {})
                .unwrap()
                .data,
        )
    });
    let cfg = Surface3dConfig {
        run: noisy_run(),
        path: PathConfig {
            length_mm: 14.0,
            ..PathConfig::for_object("plane")
        },
        ..Surface3dConfig::default()
    };
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("run");
    let res = run_surface(&cfg, &plane, "plane", model, (&out, false), &mut |_| {}).unwrap();
    let (header, rows) = trajectory(&out);
    assert_eq!(header.len(), 20);
    let both = poses(&header, &rows);
    assert!(
        both.len() > cfg.run.settle_steps + 3,
        "{}",
        res.summary.message
    );
    let off = mean(
        both.iter()
            .map(|(c, r)| (c.z - r.z).abs() + (c.x - r.x).abs()),
    );
    assert!(off > 0.2, "the noisy arm misses its poses: {off}");
    // The plane is the floor z = 0: the true depth error is -z - 3.
    let scored = &both[res.metrics.settle_steps..];
    let at_reached = mean(scored.iter().map(|(_, r)| (-r.z - 3.0).abs()));
    let at_commanded = mean(scored.iter().map(|(c, _)| (-c.z - 3.0).abs()));
    let m = res.metrics.mean_distance_mm;
    assert!((m - at_reached).abs() < 1e-3, "{m} vs reached {at_reached}");
    assert!(
        (m - at_commanded).abs() > 0.05,
        "{m} vs commanded {at_commanded}"
    );
}

#[test]
fn edge_metrics_are_at_the_reached_poses() {
    let disk = object("disk");
    let model = model_of(&edge_taps((0.0, 0.0), 200));
    let cfg = Edge3dConfig {
        run: noisy_run(),
        max_steps: Some(16),
        ..Edge3dConfig::default()
    };
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("run");
    let res = run_edge(&cfg, &disk, "disk", &model, (&out, false), &mut |_| {}).unwrap();
    let (header, rows) = trajectory(&out);
    let both = poses(&header, &rows);
    assert!(
        both.len() > cfg.run.settle_steps + 3,
        "{}",
        res.summary.message
    );
    let edge = edge_of(&disk, "disk").unwrap();
    let reference = cfg.controller.reference;
    let scored = &both[res.metrics.settle_steps..];
    let dist = |p: &Pose| edge_truth(&edge, *p, reference).distance_mm;
    let at_reached = mean(scored.iter().map(|(_, r)| dist(r)));
    let at_commanded = mean(scored.iter().map(|(c, _)| dist(c)));
    let m = res.metrics.mean_distance_mm;
    // The CSV's poses have 4 decimals.
    assert!((m - at_reached).abs() < 2e-3, "{m} vs reached {at_reached}");
    assert!(
        (m - at_commanded).abs() > 0.02,
        "{m} vs commanded {at_commanded}"
    );
}
