//! Heading control on surfaces (issue 23): a surface_3d run whose
//! controller holds a direction of travel turns onto it, and its
//! metrics.json scores the heading at the reached poses.
use tactrace_control::heading_error_deg;
use tactrace_lab::collect3d::{collect_3d, Collect3dConfig};
use tactrace_lab::follow::task3d::{run_surface, PathConfig, Surface3dConfig};
use tactrace_lab::follow::Run3dSettings;
use tactrace_lab::train::{resolve_config, train};
use tactrace_learn::{ModelKind, Preset};
use tactrace_servo::{Ending, RigConfig};
use tactrace_shape3d::ObjectConfig;
use tactrace_store::StoredModel;

/// A small surface model: 120 taps on the flat floor, a 16-unit net.
fn small_model() -> StoredModel {
    let plane = ObjectConfig::named("plane").unwrap().build().unwrap();
    let cfg = Collect3dConfig {
        samples: 120,
        seed: 5,
        ..Collect3dConfig::default()
    };
    let data = collect_3d(&RigConfig::default(), &plane, &cfg, "plane", |_| {})
        .unwrap()
        .data;
    let net_cfg = resolve_config(
        ModelKind::DisDenNN,
        Preset::Default,
        Some("[pose]\nhidden = [16]\n"),
        Some(3),
    )
    .unwrap();
    let (net, _) = train(&net_cfg, &data, &mut |_| {}).unwrap();
    StoredModel::new(net, data.meta.reference_pins.clone())
}

/// The direction of travel (deg from +x) of the last `n` reached
/// positions of a run folder's trajectory, and their heading errors.
fn last_steps(dir: &std::path::Path, n: usize, heading: f64) -> (f64, Vec<f64>) {
    let text = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let cols: Vec<usize> = [
        "x_reached_mm",
        "y_reached_mm",
        "z_reached_mm",
        "rx_reached_deg",
        "ry_reached_deg",
        "rz_reached_deg",
    ]
    .iter()
    .map(|c| col(c))
    .collect();
    let poses: Vec<tactrace_arm::Pose> = lines
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap_or(0.0)).collect();
            tactrace_arm::Pose::new(
                f[cols[0]], f[cols[1]], f[cols[2]], f[cols[3]], f[cols[4]], f[cols[5]],
            )
        })
        .collect();
    let last = &poses[poses.len() - n..];
    let (a, b) = (last[0], last[n - 1]);
    let errors = last
        .iter()
        .map(|p| heading_error_deg(*p, heading))
        .collect();
    ((b.y - a.y).atan2(b.x - a.x).to_degrees(), errors)
}

#[test]
fn surface_run_turns_onto_the_held_heading() {
    let model = small_model();
    let plane = ObjectConfig::named("plane").unwrap().build().unwrap();
    let root = tempfile::tempdir().unwrap();
    let run = |heading: Option<f64>, out: &str| {
        let mut cfg = Surface3dConfig {
            path: PathConfig {
                length_mm: 14.0,
                ..PathConfig::for_object("plane")
            },
            run: Run3dSettings {
                settle_steps: 3,
                ..Run3dSettings::default()
            },
            ..Surface3dConfig::default()
        };
        cfg.controller.heading_deg = heading;
        let out = root.path().join(out);
        let res = run_surface(&cfg, &plane, "plane", &model, (&out, false), &mut |_| {}).unwrap();
        assert_eq!(
            res.summary.ending,
            Ending::StepsDone,
            "{}",
            res.summary.message
        );
        (res, out)
    };
    // Started along +x, held at 60 deg: the surface_3d preset's rz gain 1
    // turns it at the first step; the path then runs along 60 deg.
    let (res, out) = run(Some(60.0), "steered");
    let (direction, errors) = last_steps(&out, 8, 60.0);
    assert!((direction - 60.0).abs() < 3.0, "{direction}");
    assert!(errors.iter().all(|e| e.abs() < 1.0), "{errors:?}");
    assert_eq!(res.metrics.heading_deg, 60.0);
    assert!(res.metrics.max_heading_error_deg < 1.0, "{:?}", res.metrics);
    let text = std::fs::read_to_string(out.join("metrics.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "heading_deg",
        "mean_heading_error_deg",
        "max_heading_error_deg",
    ] {
        assert!(m[key].is_number(), "{key}: {text}");
    }
    let config = std::fs::read_to_string(out.join("config.toml")).unwrap();
    assert!(config.contains("heading_deg = 60"), "{config}");
    // Without a held heading the path keeps the start's (+x): scored
    // against 0, its heading error stays small too.
    let (res, out) = run(None, "straight");
    let (direction, _) = last_steps(&out, 8, 0.0);
    assert!(direction.abs() < 3.0, "{direction}");
    assert_eq!(res.metrics.heading_deg, 0.0);
    assert!(res.metrics.max_heading_error_deg < 1.0, "{:?}", res.metrics);
}
