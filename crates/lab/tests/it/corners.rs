//! Issue 12 in the closed loop: on a held-out square and a star whose
//! valleys have a 5.3 mm concave radius, the tuned controller (the
//! simulated world's default) meets the bar, with a PDenNN
//! trained on the disk as `reproduce` trains it (1000 taps, default
//! epochs).
use tactrace_geometry::{builtin_shape, BuiltinShape, ShapeSpec};
use tactrace_lab::collect::{collect, CollectConfig};
use tactrace_lab::follow::SimFollowConfig;
use tactrace_lab::train::{resolve_config, train};
use tactrace_lab::tune::simulate;
use tactrace_learn::{ModelKind, Preset};
use tactrace_store::{load_shape, StoredModel};

fn disk_model() -> StoredModel {
    let cfg = CollectConfig {
        samples: 1000,
        seed: 11,
        ..CollectConfig::default()
    };
    let rig = SimFollowConfig::default().rig;
    let disk = builtin_shape(BuiltinShape::Disk);
    let data = collect(&rig, &disk, &cfg, "disk", |_| {}).unwrap().data;
    let mcfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, None).unwrap();
    let net = train(&mcfg, &data, &mut |_| {}).unwrap().0;
    StoredModel::new(net, data.meta.reference_pins.clone())
}

/// Issue 12's bar on a held-out square and a star with 5.3 mm concave
/// valleys: the tuned controller closes the loop, covers at least 97 %
/// of the contour, keeps the mean L2 within 0.6 mm and the track error
/// within 2 mm, and cuts the corners no more than the report's controller.
/// (With the sensor before the transfer fit the report's controller also
/// cut the square by over 2 mm and lost coverage on the star; with the
/// transfer-fitted one it stays within the bar too: docs/results.md.)
#[test]
fn the_tuned_controller_traces_corners_and_valleys_within_the_bar() {
    let model = disk_model();
    for spec in ["square:70", "star:35,7,5"] {
        let contour = load_shape(&ShapeSpec::parse_checked(spec).unwrap()).unwrap();
        let report = simulate(&SimFollowConfig::report(), &model, (spec, &contour)).unwrap();
        let tuned = simulate(&SimFollowConfig::default(), &model, (spec, &contour)).unwrap();
        let (r, t) = (&report.metrics, &tuned.metrics);
        assert!(r.closed && t.closed, "{spec}: {r:?} {t:?}");
        assert!(
            t.coverage >= 0.97 && t.mean_l2_mm <= 0.6 && t.max_track_error_mm <= 2.0,
            "{spec}: {t:?}"
        );
        assert!(
            t.max_track_error_mm <= r.max_track_error_mm,
            "{spec}: max track error {} -> {}",
            r.max_track_error_mm,
            t.max_track_error_mm
        );
    }
}
