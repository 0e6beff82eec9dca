//! The closed loop end to end on the simulated rig: a trained PDenNN follows
//! the disk and an unseen CSV contour round to closure, and a randomly
//! initialised model does not (the loop depends on what the sensor feels).
use std::sync::OnceLock;
use tactrace_geometry::{builtin_shape, parse_contour_csv, BuiltinShape, Contour};
use tactrace_lab::collect::{collect, CollectConfig};
use tactrace_lab::follow::{FollowOutcome, RunHooks, SimFollowConfig};
use tactrace_lab::train::{resolve_config, train};
use tactrace_learn::{ModelKind, Preset};
use tactrace_servo::{Ending, FollowMetrics};
use tactrace_store::StoredModel;

/// Follow `shape` in the world of `cfg` into `dir`, as `tactrace follow` does.
fn follow_simulated(
    cfg: &SimFollowConfig,
    model: &StoredModel,
    shape: (&str, &Contour),
    dir: &std::path::Path,
) -> tactrace_lab::Result<FollowOutcome> {
    let world = cfg.world().open()?;
    tactrace_lab::follow::run(world, model, Some(shape), (dir, false), RunHooks::default())
}

/// Training taps on the disk, collected once for every test here.
fn training_data() -> &'static tactrace_store::TapData {
    static DATA: OnceLock<tactrace_store::TapData> = OnceLock::new();
    DATA.get_or_init(|| {
        let cfg = CollectConfig {
            samples: 400,
            seed: 11,
            ..CollectConfig::default()
        };
        let rig = SimFollowConfig::default().rig;
        let disk = builtin_shape(BuiltinShape::Disk);
        collect(&rig, &disk, &cfg, "disk", |_| {}).unwrap().data
    })
}

fn model(toml: Option<&str>, epochs: usize) -> StoredModel {
    let cfg = resolve_config(ModelKind::PDenNN, Preset::Default, toml, Some(epochs)).unwrap();
    let net = train(&cfg, training_data(), &mut |_| {}).unwrap().0;
    StoredModel::new(net, training_data().meta.reference_pins.clone())
}

fn run(model: &StoredModel, shape: &Contour) -> (FollowOutcome, FollowMetrics) {
    let mut cfg = SimFollowConfig::default();
    // Room for the 60-epoch model's slow progress: the ellipse takes about
    // 1030 steps with the stage-7 sensor (855 with stage 5's), the disk 974.
    cfg.follow.max_steps = 1500;
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("run");
    let out = follow_simulated(&cfg, model, ("shape", shape), &dir).unwrap();
    assert!(dir.join("trajectory.csv").exists() && dir.join("metrics.json").exists());
    let metrics = out.metrics.clone().expect("scored");
    (out, metrics)
}

#[test]
fn a_model_trained_on_pins_in_another_order_is_refused_before_the_loop() {
    let mut pins = training_data().meta.reference_pins.clone();
    pins.swap(10, 11);
    let net = model(None, 1).into_model_for(&training_data().meta.reference_pins, "x".as_ref());
    let swapped = StoredModel::new(net.unwrap(), pins);
    let cfg = SimFollowConfig::default();
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("run");
    let disk = builtin_shape(BuiltinShape::Disk);
    let err = follow_simulated(&cfg, &swapped, ("disk", &disk), &dir)
        .err()
        .expect("pins in another order");
    let chain = format!("{:?}", anyhow_chain(&err));
    assert!(
        err.is_bad_input() && chain.contains("another order"),
        "{chain}"
    );
    assert_eq!(
        std::fs::read_dir(root.path()).unwrap().count(),
        0,
        "nothing written: no step was taken"
    );
}

#[test]
fn trained_model_follows_the_disk_and_an_unseen_csv_ellipse_to_closure() {
    let trained = model(None, 60);
    let (disk, m) = run(&trained, &builtin_shape(BuiltinShape::Disk));
    assert!(disk.summary.closed, "{}", disk.summary.message);
    assert!(m.mean_l2_mm < 1.5, "{m:?}");
    assert!(m.coverage > 0.95, "{m:?}");
    // An ellipse (70 x 45 mm semi-axes) the model was never trained on,
    // given as CSV text like a user's file.
    let csv: String = (0..360)
        .map(|i| {
            let t = (i as f64).to_radians();
            format!("{:.4},{:.4}\n", 70.0 * t.cos(), 45.0 * t.sin())
        })
        .collect();
    let ellipse = parse_contour_csv(&format!("x_mm,y_mm\n{csv}")).unwrap();
    let (res, m) = run(&trained, &ellipse);
    assert!(res.summary.closed, "{}", res.summary.message);
    assert!(m.mean_l2_mm < 1.5, "{m:?}");
    assert!(m.coverage > 0.95, "{m:?}");
}

#[test]
fn randomly_initialised_model_fails_to_follow() {
    // One epoch at a negligible learning rate: the weights stay at their
    // random initialisation (standardisation and PCA are fitted as usual).
    let rates = "learning_rate = 1e-12\noutput_learning_rate = 1e-12\n";
    let toml = format!("[position]\n{rates}[angle]\n{rates}");
    let untrained = model(Some(&toml), 1);
    let (res, m) = run(&untrained, &builtin_shape(BuiltinShape::Disk));
    assert!(!res.summary.closed, "{}", res.summary.message);
    assert!(!res.summary.ending.succeeded(), "{:?}", res.summary);
    let lost = matches!(res.summary.ending, Ending::LostContact | Ending::Refused);
    assert!(lost || m.mean_l2_mm > 3.0, "{:?} {m:?}", res.summary);
}

/// Every message in an error's source chain.
fn anyhow_chain(err: &dyn std::error::Error) -> Vec<String> {
    let mut out = vec![err.to_string()];
    let mut next = err.source();
    while let Some(e) = next {
        out.push(e.to_string());
        next = e.source();
    }
    out
}
