//! The simulated world of a calibrated sensor (`--sensor`): taps collected
//! in it carry the sensor's own labels and pin order, and a model trained
//! on them closes the loop round the disk through the label convention
//! (eq. L1) and the sensor's mount (eq. L2). The sensor is the synthetic
//! "real" TacTip of `common`, calibrated like a user's.
use crate::common;

use common::{distorted_sensor_set, sensor_set};
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_lab::calibrate::{calibrate_sensor, CalibrateConfig};
use tactrace_lab::collect::{collect_calibrated, CollectConfig};
use tactrace_lab::follow::{RunHooks, SimFollowConfig};
use tactrace_lab::train::{resolve_config, train};
use tactrace_learn::{ModelKind, Preset};
use tactrace_sensor::TacTipConfig;
use tactrace_servo::{Ending, RigConfig};
use tactrace_store::{LabelledCollection, SensorFolder, StoredModel};

/// A synthetic sensor labelled in the real edge set's convention (its
/// label angle zero is 74 deg from the loop's, its r offset 2.3 mm),
/// calibrated on 100 of its taps and written to `dir/sensor`.
fn calibrated_sensor(dir: &std::path::Path) -> SensorFolder {
    let twin = distorted_sensor_set(dir, 140);
    let cfg = CalibrateConfig {
        collection: twin,
        render_seed: 1,
        samples: Some(100),
        seed: 2,
        allowed_rows: None,
        score_rows: None,
        fit_physics: false,
        labelled_depth: false,
        pin_jitter: Default::default(),
    };
    let got = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap();
    got.sensor.write(&dir.join("sensor"), false).unwrap();
    SensorFolder::read(&dir.join("sensor")).unwrap()
}

#[test]
fn a_model_of_the_calibrated_sensor_follows_the_disk_in_its_world() {
    let root = tempfile::tempdir().unwrap();
    let sensor = calibrated_sensor(root.path());
    let disk = builtin_shape(BuiltinShape::Disk);
    let rig = RigConfig::default();
    let ccfg = CollectConfig {
        samples: 600,
        seed: 4,
        ..CollectConfig::default()
    };
    let got = collect_calibrated(&rig, &sensor, &disk, &ccfg, "disk", |_| {}).unwrap();
    let data = got.data;
    // The sensor's labels, names and pin order.
    assert!(
        data.meta.targets[0].contains("pose_2"),
        "{:?}",
        data.meta.targets
    );
    let (rs, ts): (Vec<f32>, Vec<f32>) = data.targets.chunks(2).map(|t| (t[0], t[1])).unzip();
    assert!(rs.iter().all(|r| r.abs() <= 5.0) && ts.iter().all(|t| t.abs() <= 45.0));
    let worst = data
        .meta
        .reference_pins
        .iter()
        .zip(&sensor.spec.reference_pins)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-9,
        "pins listed off the sensor's reference by {worst} px"
    );
    // A model of these taps closes the loop in the sensor's world.
    let mcfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, Some(60)).unwrap();
    let (model, _) = train(&mcfg, &data, &mut |_| {}).unwrap();
    let stored = StoredModel::new(model, data.meta.reference_pins.clone());
    let fcfg = SimFollowConfig {
        calibrated_sensor: Some(root.path().join("sensor")),
        ..SimFollowConfig::default()
    };
    let out = root.path().join("run");
    let world = fcfg.world().open().unwrap();
    let shape = Some(("disk", &disk));
    let res = tactrace_lab::follow::run(world, &stored, shape, (&out, false), RunHooks::default())
        .unwrap();
    let m = res.metrics.unwrap();
    assert_eq!(
        res.summary.ending,
        Ending::Closed,
        "{}",
        res.summary.message
    );
    assert!(m.mean_l2_mm < 1.0 && m.coverage > 0.95, "{m:?}");
}

/// A TacTip with 61 pins seen in a 320 x 240 frame by another camera:
/// calibrate lays the simulator out like it, and its world works.
/// Calibration of the synthetic set `twin` with 80 taps, seed 1.
fn calibrate_80(twin: LabelledCollection, fit_physics: bool) -> CalibrateConfig {
    CalibrateConfig {
        collection: twin,
        render_seed: 1,
        samples: Some(80),
        seed: 1,
        allowed_rows: None,
        score_rows: None,
        fit_physics,
        labelled_depth: false,
        pin_jitter: Default::default(),
    }
}

#[test]
fn a_sensor_with_another_pin_count_and_frame_size_is_calibrated() {
    let root = tempfile::tempdir().unwrap();
    let mut other = TacTipConfig::default();
    other.geometry.rings = 4;
    other.geometry.pin_spacing_mm *= 1.5;
    other.geometry.pin_radius_mm *= 1.2;
    other.camera.width = 320;
    other.camera.height = 240;
    other.camera.centre_px = [161.0, 117.0];
    other.camera.focal_px = 72.0;
    other.camera.rotation_deg = 165.0;
    let twin = sensor_set(root.path(), 120, other.clone());
    let cfg = calibrate_80(twin, false);
    let got = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap();
    let spec = &got.sensor.spec;
    assert_eq!(spec.reference_pins.len(), 61);
    assert_eq!(spec.sensor.geometry.rings, 4);
    assert_eq!(
        (spec.sensor.camera.width, spec.sensor.camera.height),
        (320, 240)
    );
    let after = spec.calibration.held_out_after.unwrap();
    assert!(after.rms_px < 0.5, "held-out field RMS {} px", after.rms_px);
    // Its simulated taps come out in its reference's pin order.
    let disk = builtin_shape(BuiltinShape::Disk);
    let ccfg = CollectConfig {
        samples: 50,
        ..CollectConfig::default()
    };
    let data = collect_calibrated(
        &RigConfig::default(),
        &got.sensor,
        &disk,
        &ccfg,
        "disk",
        |_| {},
    )
    .unwrap()
    .data;
    assert_eq!(data.dim(), 2 * 61);
    // The transfer-fitted mechanics press harder and sharper (issue 11):
    // on this coarser, larger synthetic dome a deep tap can merge two
    // pins now and then (2 of 50 with seed 1); never more than one in ten.
    assert!(data.meta.frames_with_missing_pins <= 5, "{:?}", data.meta);
}

/// A sensor whose labels follow another convention (angle and edge
/// offsets, edge scale): `--fit-physics` finds it.
#[test]
fn the_physics_fit_finds_another_label_convention() {
    let root = tempfile::tempdir().unwrap();
    let mut other = TacTipConfig::default();
    other.calibration.angle_offset_deg = -6.0;
    other.calibration.edge_offset_mm = 1.2;
    other.calibration.edge_scale = 1.25;
    let twin = sensor_set(root.path(), 120, other.clone());
    let run = |fit_physics| {
        let cfg = calibrate_80(twin.clone(), fit_physics);
        calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap()
    };
    let (plain, fitted) = (run(false), run(true));
    let cal = &fitted.sensor.spec.sensor.calibration;
    assert!((cal.angle_offset_deg + 6.0).abs() < 2.0, "{cal:?}");
    assert!((cal.edge_offset_mm - 1.2).abs() < 0.4, "{cal:?}");
    assert!((cal.edge_scale - 1.25).abs() < 0.15, "{cal:?}");
    let before = |c: &tactrace_lab::calibrate::Calibrated| {
        c.sensor.spec.calibration.held_out_before.unwrap().rms_px
    };
    assert!(
        before(&fitted) < 0.6 * before(&plain),
        "uncorrected held-out misfit {} px with the physics fit, {} px without",
        before(&fitted),
        before(&plain)
    );
}

/// A sensor whose labels put the object on the other side of the edge (a
/// 180 deg turn no local fit makes): found, by the label convention's
/// search (as the object on this side seen half a turn round: the angle
/// offset turned by 180 deg, the position's sign and offset negated) or
/// by `--fit-physics`'s two sides.
#[test]
fn the_physics_fit_finds_the_object_on_the_other_side() {
    let root = tempfile::tempdir().unwrap();
    let mut other = TacTipConfig::default();
    other.calibration.object_side = -other.calibration.object_side;
    let twin = sensor_set(root.path(), 120, other.clone());
    let cfg = calibrate_80(twin, true);
    let fitted = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {}).unwrap();
    let cal = &fitted.sensor.spec.sensor.calibration;
    let want = &other.calibration;
    if cal.object_side != want.object_side {
        let turn = tactrace_sensor::wrap_deg(cal.angle_offset_deg - want.angle_offset_deg - 180.0);
        assert!(turn.abs() < 3.0, "{cal:?}");
        assert!(cal.edge_scale < 0.0, "{cal:?}");
        assert!(
            (cal.edge_offset_mm + want.edge_offset_mm).abs() < 0.4,
            "{cal:?}"
        );
    }
    let held_out = fitted
        .sensor
        .spec
        .calibration
        .held_out_before
        .unwrap()
        .rms_px;
    assert!(held_out < 0.6, "uncorrected held-out misfit {held_out} px");
}
