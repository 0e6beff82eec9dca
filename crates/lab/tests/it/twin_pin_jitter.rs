//! The pin jitter of a calibrated sensor's twin (`twin --pin-jitter`,
//! docs/calibration.md "Pin jitter in the twin"): without it the
//! recipe's renders of a row are identical; with it they differ by about
//! the jitter (two independent draws: sqrt(2) x the jitter per axis,
//! before the detector's own quantisation), centred on each other, with
//! the labels kept and the jitter recorded; a jitter below 0 or not a
//! number is refused as bad input.
use tactrace_lab::calibrate::calibrate_sensor;
use tactrace_lab::import::Imported;
use tactrace_lab::pin_jitter::with_pin_jitter;
use tactrace_lab::twin::{renders_differ, simulate_twin_calibrated};
use tactrace_sensor::TacTipConfig;

use crate::common;
use common::{calibration, distorted_sensor_set};

/// The inputs and targets of render `k` of a twin of `rows` rows.
fn render(got: &Imported, rows: usize, k: usize) -> (&[f32], &[f32]) {
    let d = got.data.inputs.len() / got.data.len();
    let t = got.data.targets.len() / got.data.len();
    (
        &got.data.inputs[k * rows * d..(k + 1) * rows * d],
        &got.data.targets[k * rows * t..(k + 1) * rows * t],
    )
}

#[test]
fn renders_are_identical_without_jitter_and_differ_by_it_with() {
    let root = tempfile::tempdir().unwrap();
    let set = distorted_sensor_set(root.path(), 40);
    let cfg = calibration(set.clone(), 20);
    let sensor = calibrate_sensor(&cfg, &TacTipConfig::default(), &|| {})
        .unwrap()
        .sensor;
    assert!(!renders_differ(&sensor.spec.sensor));
    let plain = simulate_twin_calibrated(&set, &sensor, 1, (false, None), &|| {}).unwrap();
    let c = plain.composition.unwrap();
    assert_eq!((c.renders, c.real_tap_repeats), (3, 0));
    let rows = c.rows;
    assert_eq!(render(&plain, rows, 0), render(&plain, rows, 2));
    assert!(plain.data.meta.settings.get("pin_jitter_px").is_none());

    let px = 0.3;
    let mut jittered = sensor.clone();
    jittered.spec.sensor = with_pin_jitter(&sensor.spec.sensor, px).unwrap();
    assert!(renders_differ(&jittered.spec.sensor));
    let got = simulate_twin_calibrated(&set, &jittered, 1, (false, None), &|| {}).unwrap();
    let ((a, la), (b, lb)) = (render(&got, rows, 0), render(&got, rows, 1));
    assert_eq!(la, lb, "the labels are kept");
    let diff: Vec<f64> = a.iter().zip(b).map(|(x, y)| f64::from(x - y)).collect();
    let n = diff.len() as f64;
    let rms = (diff.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
    let mean = diff.iter().sum::<f64>() / n;
    let expected = std::f64::consts::SQRT_2 * px;
    assert!(
        rms > 0.5 * expected && rms < 2.5 * expected,
        "renders differ by {rms:.3} px RMS per axis, a jitter of {px} px gives about {expected:.3}"
    );
    assert!(
        mean.abs() < 0.1 * expected,
        "renders offset by {mean:.4} px"
    );
    let recorded = &got.data.meta.settings["pin_jitter_px"];
    assert_eq!(recorded.as_f64(), Some(px), "{recorded}");

    for bad in [-0.1, f64::NAN] {
        let err = with_pin_jitter(&sensor.spec.sensor, bad).unwrap_err();
        assert!(err.is_bad_input(), "{err}");
        assert!(err.to_string().contains("pin_jitter_px"), "{err}");
    }
}
