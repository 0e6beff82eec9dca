//! The 3D runs' configuration files: the settings a surface and an edge
//! run share stand at the top level as before (flattened from
//! `Run3dSettings`), each task keeps its own controller, and any key
//! neither takes is refused by name.
use tactrace_control::Task;
use tactrace_lab::follow::edge3d::Edge3dConfig;
use tactrace_lab::follow::task3d::Surface3dConfig;
use tactrace_store::overlay;

/// The top-level keys of `cfg` as written to a run's `config.toml`.
fn top_keys<T: serde::Serialize>(cfg: &T) -> Vec<String> {
    let text = toml::to_string(cfg).unwrap();
    let table: toml::Table = toml::from_str(&text).unwrap();
    let mut keys: Vec<String> = table.keys().cloned().collect();
    keys.sort();
    keys
}

const SHARED: [&str; 6] = [
    "contact_threshold_px",
    "max_no_contact",
    "max_tilt_deg",
    "rig",
    "seed",
    "settle_steps",
];

fn with_shared(own: &[&str]) -> Vec<String> {
    let mut keys: Vec<String> = SHARED.iter().chain(own).map(|k| k.to_string()).collect();
    keys.sort();
    keys
}

#[test]
fn config_toml_keeps_its_keys_and_reads_back_the_same() {
    let surface = Surface3dConfig::default();
    assert_eq!(top_keys(&surface), with_shared(&["controller", "path"]));
    let edge = Edge3dConfig {
        start_mm: Some([1.0, 2.0]),
        max_steps: Some(40),
        ..Edge3dConfig::default()
    };
    let own = [
        "close_radius_mm",
        "controller",
        "max_steps",
        "min_excursion_mm",
        "start_mm",
    ];
    assert_eq!(top_keys(&edge), with_shared(&own));
    let text = toml::to_string(&edge).unwrap();
    let back: Edge3dConfig = overlay(&Edge3dConfig::default(), &text, "edge").unwrap();
    assert_eq!(toml::to_string(&back).unwrap(), text);
    let text = toml::to_string(&surface).unwrap();
    let back: Surface3dConfig = overlay(&Surface3dConfig::default(), &text, "surface").unwrap();
    assert_eq!(toml::to_string(&back).unwrap(), text);
}

#[test]
fn shared_keys_are_read_at_the_top_level_and_each_task_keeps_its_controller() {
    let text = "seed = 7\nmax_tilt_deg = 30\n[rig.tap]\nheight_mm = 4.0\n";
    let surface: Surface3dConfig = overlay(&Surface3dConfig::default(), text, "s").unwrap();
    let edge: Edge3dConfig = overlay(&Edge3dConfig::default(), text, "e").unwrap();
    for run in [&surface.run, &edge.run] {
        assert_eq!((run.seed, run.max_tilt_deg), (7, 30.0));
        assert_eq!(run.rig.tap.height_mm, 4.0);
        assert_eq!(run.settle_steps, 5);
    }
    assert_eq!(surface.controller.task, Task::Surface3d);
    assert_eq!(edge.controller.task, Task::Edge5d);
}

#[test]
fn unknown_keys_are_refused_naming_the_key() {
    let refused = |text: &str, key: &str| {
        let s = overlay(
            &Surface3dConfig::default(),
            text,
            "surface follow configuration",
        );
        let e = overlay(&Edge3dConfig::default(), text, "edge follow configuration");
        for err in [s.err(), e.err()] {
            let err = err.unwrap_or_else(|| panic!("{text:?} was taken"));
            assert!(err.to_string().contains(key), "{text:?}: {err}");
        }
    };
    refused("max_tilt = 30\n", "max_tilt");
    refused("seed = 1\nsettle = 2\n", "settle");
    refused("[rig]\nnoise = 1\n", "noise");
    refused("[controller]\ngain = 1\n", "gain");
    // One task's own keys are unknown to the other.
    let edge_key = overlay(&Surface3dConfig::default(), "close_radius_mm = 2\n", "s");
    assert!(edge_key.is_err_and(|e| e.to_string().contains("close_radius_mm")));
    let surface_key = overlay(&Edge3dConfig::default(), "[path]\nlength_mm = 9\n", "e");
    assert!(surface_key.is_err_and(|e| e.to_string().contains("path")));
}

#[test]
fn the_shared_bounds_are_checked_for_both_tasks() {
    for text in ["max_tilt_deg = 91\n", "max_no_contact = 0\n"] {
        let surface: Surface3dConfig = overlay(&Surface3dConfig::default(), text, "s").unwrap();
        let edge: Edge3dConfig = overlay(&Edge3dConfig::default(), text, "e").unwrap();
        assert!(
            surface.validate().is_err_and(|e| e.is_bad_input()),
            "{text}"
        );
        assert!(edge.validate().is_err_and(|e| e.is_bad_input()), "{text}");
    }
    Surface3dConfig::default().validate().unwrap();
    Edge3dConfig::default().validate().unwrap();
}
