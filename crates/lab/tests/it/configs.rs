//! The controllers the lab runs by default: `follow` the tuned one,
//! `reproduce` the report's, and the shipped configs/follow-report.toml
//! gives the report's back (issue 12).
use std::path::Path;
use tactrace_control::PbtsConfig;
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::reproduce::ReproduceConfig;
use tactrace_store::load_config;

#[test]
fn follow_runs_the_tuned_controller_and_reproduce_the_reports() {
    assert_eq!(SimFollowConfig::default().controller, PbtsConfig::tuned());
    assert_eq!(
        ReproduceConfig::default().follow.controller,
        PbtsConfig::report()
    );
    assert!(PbtsConfig::report().policy.is_off());
    PbtsConfig::tuned().validate().unwrap();
    assert!(!PbtsConfig::tuned().policy.is_off());
}

#[test]
fn the_shipped_report_config_restores_the_reports_controller() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/follow-report.toml");
    let cfg: SimFollowConfig = load_config(Some(&path), "follow configuration").unwrap();
    assert_eq!(cfg.controller, PbtsConfig::report());
    let rest = SimFollowConfig::report();
    assert_eq!(
        toml::to_string(&cfg).unwrap(),
        toml::to_string(&rest).unwrap()
    );
}

/// The shipped configuration of the file `name` in configs/.
fn shipped(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs")
        .join(name);
    std::fs::read_to_string(path).unwrap()
}

/// The 127-pin edge's pin model (configs/pdennn-edge127.toml) is the
/// search's best trial as an ensemble of five, and the shipped residual
/// image model (configs/residual-edge127.toml) carries exactly that pin
/// model as its base: the two files cannot drift apart.
#[test]
fn the_shipped_edge_residual_carries_the_shipped_pin_model() {
    use tactrace_learn::{ModelKind, Preset};
    let pins = tactrace_lab::train::resolve_config(
        ModelKind::PDenNN,
        Preset::Default,
        Some(&shipped("pdennn-edge127.toml")),
        None,
    )
    .unwrap();
    assert_eq!(pins.ensemble, 5);
    let (position, angle) = (pins.position.as_ref(), pins.angle.as_ref());
    assert_eq!(position.and_then(|n| n.n_components), Some(27));
    assert_eq!(angle.and_then(|n| n.n_components), Some(39));
    assert_eq!(position.map(|n| n.hidden.clone()), Some(vec![385]));
    for kind in [
        tactrace_convnet::ModelKind::ConvMlp,
        tactrace_convnet::ModelKind::ConvDennn,
    ] {
        let text = shipped("residual-edge127.toml");
        let (image, base) =
            tactrace_lab::train_image::resolve_image_settings(kind, Some(&text), None).unwrap();
        assert!(image.input.reads_base(), "{}", kind.name());
        let base = base.expect("a residual model has a base");
        assert_eq!(base.kind().unwrap(), ModelKind::PDenNN);
        assert_eq!(base.config().unwrap(), pins);
    }
}

/// The shipped edge_5d config `name` is edge_5d's preset with the
/// integral gains of the components `zeroed` at 0 (each nonzero in the
/// preset), the policy off, and nothing else changed.
fn assert_preset_without_integral(name: &str, zeroed: &[usize]) {
    use tactrace_control::Se3Config;
    use tactrace_lab::follow::edge3d::Edge3dConfig;
    let cfg: Edge3dConfig = toml::from_str(&shipped(name)).unwrap();
    let mut want = Se3Config::edge_5d();
    for &k in zeroed {
        assert_ne!(want.ki[k], 0.0, "{name}: ki[{k}] is 0 in the preset");
        want.ki[k] = 0.0;
    }
    assert_eq!(cfg.controller, want, "{name}");
    assert!(cfg.controller.policy.is_off(), "{name}");
}

/// configs/edge5d-no-tilt-integral.toml: without the tilts' integral terms.
#[test]
fn the_shipped_edge_config_is_the_preset_without_the_tilt_integral() {
    assert_preset_without_integral("edge5d-no-tilt-integral.toml", &[3, 4]);
}

/// configs/edge5d-no-surface-integral.toml (the corners' preset): without
/// the depth's and the tilts' integral terms.
#[test]
fn the_shipped_corner_config_is_the_preset_without_the_surface_integral() {
    assert_preset_without_integral("edge5d-no-surface-integral.toml", &[2, 3, 4]);
}

/// The 331-pin edge's three shipped members
/// (configs/pcadennn-edge331-*.toml) are one PCADenNN recipe of 60
/// components on the six turned copies, the edge angle turned back at
/// prediction; they differ only in the seed and the band of r weighted
/// twice, so the recipe cannot drift between them.
#[test]
fn the_shipped_331_edge_members_differ_only_in_seed_and_band() {
    use tactrace_learn::{ModelKind, Preset};
    let resolve = |name: &str| {
        tactrace_lab::train::resolve_config(
            ModelKind::PcaDenNN,
            Preset::Default,
            Some(&shipped(name)),
            Some(100),
        )
        .unwrap()
    };
    let members = [
        ("pcadennn-edge331-rim5.toml", 0, 5.0),
        ("pcadennn-edge331-rim5-seed1.toml", 1, 5.0),
        ("pcadennn-edge331-rim3.toml", 0, 3.0),
    ];
    let first = resolve(members[0].0);
    for (name, seed, min) in members {
        let mut cfg = resolve(name);
        assert_eq!(cfg.seed, seed, "{name}");
        let band = cfg.band_weight.clone().expect("a band of r weighted");
        assert_eq!(
            (band.target.as_str(), band.min, band.max, band.weight),
            ("pose_2", Some(min), None, 2),
            "{name}"
        );
        let pose = cfg.pose.as_ref().expect("one pose net");
        assert_eq!(pose.n_components, Some(60), "{name}");
        assert_eq!(pose.hidden, vec![512, 256], "{name}");
        let turns = cfg.rotations.expect("turned copies");
        assert_eq!(
            (turns.order, turns.angle_sign, turns.at_prediction),
            (6, -1, true),
            "{name}"
        );
        cfg.seed = first.seed;
        cfg.band_weight = first.band_weight.clone();
        assert_eq!(
            cfg, first,
            "{name} differs from the first member beyond seed and band"
        );
    }
}
