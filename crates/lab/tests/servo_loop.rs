//! The closed loop end to end on the simulated rig: a trained PDenNN follows
//! the disk and an unseen CSV contour round to closure, and a randomly
//! initialised model does not (the loop depends on what the sensor feels).
use std::sync::OnceLock;
use tactrace_geometry::{builtin_shape, parse_contour_csv, BuiltinShape, Contour};
use tactrace_lab::collect::{collect, CollectConfig};
use tactrace_lab::follow::{run_follow, FollowOutcome, FollowRunConfig};
use tactrace_lab::servo::Ending;
use tactrace_lab::train::{resolve_config, train};
use tactrace_learn::{ModelKind, PoseModel, Preset};

/// Training taps on the disk, collected once for every test here.
fn training_data() -> &'static tactrace_lab::dataset::TapData {
    static DATA: OnceLock<tactrace_lab::dataset::TapData> = OnceLock::new();
    DATA.get_or_init(|| {
        let cfg = CollectConfig {
            samples: 400,
            seed: 11,
            ..CollectConfig::default()
        };
        let rig = FollowRunConfig::simulated().rig;
        let disk = builtin_shape(BuiltinShape::Disk);
        collect(&rig, &disk, &cfg, "disk", |_| {}).unwrap().data
    })
}

fn model(toml: Option<&str>, epochs: usize) -> PoseModel {
    let cfg = resolve_config(ModelKind::PDenNN, Preset::Default, toml, Some(epochs)).unwrap();
    train(&cfg, training_data(), &mut |_| {}).unwrap().0
}

fn run(model: PoseModel, shape: &Contour, tag: &str) -> FollowOutcome {
    let mut cfg = FollowRunConfig::simulated();
    cfg.follow.max_steps = 700;
    let dir = std::env::temp_dir().join(format!("tactrace-servo-{tag}-{}", std::process::id()));
    let pins = Some(training_data().meta.reference_pins.as_slice());
    let out = run_follow(&cfg, (model, pins), shape, &dir, &mut |_| {}).unwrap();
    assert!(dir.join("trajectory.csv").exists() && dir.join("metrics.json").exists());
    std::fs::remove_dir_all(&dir).ok();
    out
}

#[test]
fn a_model_trained_on_pins_in_another_order_is_refused_before_the_loop() {
    let mut pins = training_data().meta.reference_pins.clone();
    pins.swap(10, 11);
    let cfg = FollowRunConfig::simulated();
    let dir = std::env::temp_dir().join(format!("tactrace-servo-order-{}", std::process::id()));
    let disk = builtin_shape(BuiltinShape::Disk);
    let err = run_follow(
        &cfg,
        (model(None, 1), Some(&pins)),
        &disk,
        &dir,
        &mut |_| {},
    )
    .err()
    .expect("pins in another order");
    assert!(
        err.is_bad_input() && err.to_string().contains("another order"),
        "{err}"
    );
    assert!(!dir.join("trajectory.csv").exists(), "no step was taken");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn trained_model_follows_the_disk_and_an_unseen_csv_ellipse_to_closure() {
    let trained = model(None, 60);
    let disk = run(trained.clone(), &builtin_shape(BuiltinShape::Disk), "disk");
    assert!(disk.summary.closed, "{}", disk.summary.message);
    assert!(disk.metrics.mean_l2_mm < 1.5, "{:?}", disk.metrics);
    assert!(disk.metrics.coverage > 0.95, "{:?}", disk.metrics);
    // An ellipse (70 x 45 mm semi-axes) the model was never trained on,
    // given as CSV text like a user's file.
    let csv: String = (0..360)
        .map(|i| {
            let t = (i as f64).to_radians();
            format!("{:.4},{:.4}\n", 70.0 * t.cos(), 45.0 * t.sin())
        })
        .collect();
    let ellipse = parse_contour_csv(&format!("x_mm,y_mm\n{csv}")).unwrap();
    let res = run(trained, &ellipse, "ellipse");
    assert!(res.summary.closed, "{}", res.summary.message);
    assert!(res.metrics.mean_l2_mm < 1.5, "{:?}", res.metrics);
    assert!(res.metrics.coverage > 0.95, "{:?}", res.metrics);
}

#[test]
fn randomly_initialised_model_fails_to_follow() {
    // One epoch at a negligible learning rate: the weights stay at their
    // random initialisation (standardisation and PCA are fitted as usual).
    let rates = "learning_rate = 1e-12\noutput_learning_rate = 1e-12\n";
    let toml = format!("[position]\n{rates}[angle]\n{rates}");
    let untrained = model(Some(&toml), 1);
    let res = run(untrained, &builtin_shape(BuiltinShape::Disk), "untrained");
    assert!(!res.summary.closed, "{}", res.summary.message);
    let lost = matches!(res.summary.ending, Ending::LostContact | Ending::Refused);
    assert!(
        lost || res.metrics.mean_l2_mm > 3.0,
        "{:?} {:?}",
        res.summary,
        res.metrics
    );
}
