//! The pivot offset found with the tap depth (`fit_depth`, eq. L3): taps
//! whose labelled angles go round the circle, made by a rig whose dome
//! sits elsewhere on the arm's turning point than the sensor's own
//! calibration says, give the rig's pivot back; taps over a narrow arc
//! (where the pivot trades against the edge offset) leave it alone.
use crate::common;

use tactrace_sensor::{
    fit_depth, DepthSearch, EdgeTap, FitSample, Shear, TacTipConfig, TacTipModel,
};

/// 36 taps of `truth`, r in [-3, 3] mm, theta spread evenly over
/// `arc_deg` (centred on 0), dz in [3, 5] and slides of up to 2 mm and
/// 2 deg, measured against the rest pins.
fn taps(truth: &TacTipConfig, arc_deg: f64) -> (Vec<[f64; 2]>, Vec<FitSample>) {
    let model = TacTipModel::new(truth.clone()).unwrap();
    let rest = model.rest_pins().to_vec();
    let n = 36;
    let samples = (0..n)
        .map(|k| {
            let u = |m: usize| ((k * m) % n) as f64 / (n - 1) as f64;
            let tap = EdgeTap {
                r_mm: -3.0 + 6.0 * u(7),
                theta_deg: arc_deg * (k as f64 / n as f64 - 0.5),
                dz_mm: 3.0 + 2.0 * u(13),
                shear: Some(Shear {
                    dx_mm: -2.0 + 4.0 * u(17),
                    dy_mm: -2.0 + 4.0 * u(19),
                    drz_deg: -2.0 + 4.0 * u(23),
                }),
            };
            common::fit_sample(&model, &rest, tap)
        })
        .collect();
    (rest, samples)
}

/// The sensor's own (the built-in one with a depth law for dz in [3, 5]
/// that reaches the skin) and a rig like it whose dome centre is on the
/// turning point (pivot 0) and pressed 0.3 mm shallower.
fn own_and_truth() -> (TacTipConfig, TacTipConfig) {
    let mut own = TacTipConfig::default();
    own.calibration.tap_depth_mm = 0.6;
    own.calibration.depth_per_offset = 1.0;
    let mut truth = own.clone();
    truth.calibration.tap_depth_mm = 0.3;
    truth.calibration.pivot_x_mm = 0.0;
    truth.calibration.pivot_y_mm = 0.0;
    (own, truth)
}

fn search() -> DepthSearch {
    DepthSearch {
        threads: 2,
        iterations: 150,
        ..DepthSearch::default()
    }
}

#[test]
fn taps_round_the_circle_give_the_rigs_pivot_back() {
    let (own, truth) = own_and_truth();
    assert!(own.calibration.pivot_x_mm.hypot(own.calibration.pivot_y_mm) > 1.0);
    let (rest, samples) = taps(&truth, 360.0);
    let fit = fit_depth(&own, &rest, &samples, &search()).unwrap();
    assert!(!fit.kept_own, "{}", fit.describe());
    let [x, y] = fit
        .chosen
        .pivot_mm
        .expect("the pivot is fitted over the circle");
    assert!(
        x.hypot(y) < 0.3,
        "pivot ({x:.2}, {y:.2}) mm for (0, 0); {}",
        fit.describe()
    );
    let applied = fit.apply(&own).calibration;
    assert_eq!([applied.pivot_x_mm, applied.pivot_y_mm], [x, y]);
    assert!(fit.describe().contains("pivot"), "{}", fit.describe());
}

#[test]
fn taps_over_a_narrow_arc_keep_the_sensors_pivot() {
    let (own, truth) = own_and_truth();
    let (rest, samples) = taps(&truth, 90.0);
    let fit = fit_depth(&own, &rest, &samples, &search()).unwrap();
    assert_eq!(fit.chosen.pivot_mm, None, "{}", fit.describe());
    let applied = fit.apply(&own).calibration;
    assert_eq!(
        [applied.pivot_x_mm, applied.pivot_y_mm],
        [own.calibration.pivot_x_mm, own.calibration.pivot_y_mm]
    );
    assert!(!fit.describe().contains("pivot"), "{}", fit.describe());
}
