//! The stick-slip law (eq. S7) in the whole model and its fit: a slide
//! moves the whole skin against it, the lag saturates and grows with the
//! contact load, opposite slides give opposite lags, and `fit_slip`
//! recovers known parameters from simulated fields (docs/sensor-model.md).
use crate::common;
use common::*;
use tactrace_sensor::{fit_slip, EdgeTap, FitSample, Shear, SlipParams, TacTipConfig, TacTipModel};

fn slide(dx_mm: f64, dy_mm: f64) -> Option<Shear> {
    Some(Shear {
        dx_mm,
        dy_mm,
        drz_deg: 0.0,
    })
}

/// Mean image displacement (px) that the slide adds to an edge tap.
fn slip_translation(model: &TacTipModel, depth_offset: f64, dx: f64) -> [f64; 2] {
    let mut tap = EdgeTap {
        r_mm: 0.0,
        theta_deg: 0.0,
        dz_mm: depth_offset,
        shear: None,
    };
    let base = model.edge_tap_pins(&tap);
    tap.shear = slide(dx, 0.0);
    let moved = model.edge_tap_pins(&tap);
    let d = displacement(model, &moved);
    let b = displacement(model, &base);
    let n = d.len() as f64;
    d.iter().zip(&b).fold([0.0; 2], |a, (p, q)| {
        [a[0] + (p[0] - q[0]) / n, a[1] + (p[1] - q[1]) / n]
    })
}

#[test]
fn a_slide_translates_the_whole_field_saturating_and_odd() {
    let model = plain_model();
    let zero = slip_translation(&model, 0.0, 0.0);
    assert_eq!(zero, [0.0, 0.0], "no slide, no translation");
    let t = |dx| slip_translation(&model, 0.0, dx);
    let (small, mid, big, huge) = (t(0.3), t(2.0), t(8.0), t(16.0));
    assert!(
        small[0].abs() > 0.2,
        "a small slide moves the field: {small:?}"
    );
    assert!(mid[0].abs() > small[0].abs() && big[0].abs() > mid[0].abs());
    assert!(
        (huge[0] - big[0]).abs() < 0.02 * big[0].abs(),
        "saturates: {huge:?} vs {big:?}"
    );
    // Odd on the skin (unit tests of eq. S7b); in the image only up to
    // the projection's curvature (eq. S8).
    let back = t(-2.0);
    assert!(
        (back[0] + mid[0]).abs() < 0.02 * mid[0].abs(),
        "odd: {back:?} vs {mid:?}"
    );
}

#[test]
fn deeper_taps_hold_a_larger_lag_before_slipping() {
    // dz = -1 mm is 1 mm deeper than nominal (depth_per_offset = -1).
    let model = plain_model();
    let shallow = slip_translation(&model, 1.0, 8.0)[0].abs();
    let deep = slip_translation(&model, -1.0, 8.0)[0].abs();
    assert!(deep > 1.2 * shallow, "deep {deep} vs shallow {shallow}");
}

#[test]
fn a_slide_off_the_object_moves_nothing() {
    let model = plain_model();
    let tap = EdgeTap {
        r_mm: -30.0,
        theta_deg: 10.0,
        dz_mm: 0.0,
        shear: slide(3.0, -2.0),
    };
    assert_eq!(model.edge_tap_pins(&tap), model.rest_pins());
}

fn taps() -> Vec<EdgeTap> {
    (0..48)
        .map(|k| {
            let f = k as f64;
            EdgeTap {
                r_mm: -4.0 + (f * 0.37) % 8.0,
                theta_deg: -40.0 + (f * 13.0) % 80.0,
                dz_mm: -0.9 + (f * 0.29) % 1.8,
                shear: Some(Shear {
                    dx_mm: 5.0 * (f * 1.3).sin(),
                    dy_mm: 5.0 * (f * 0.7).cos(),
                    drz_deg: 4.0 * (f * 2.1).sin(),
                }),
            }
        })
        .collect()
}

#[test]
fn the_slip_fit_recovers_known_parameters_from_simulated_fields() {
    let mut truth = TacTipConfig::default();
    let known = SlipParams {
        shear_angle_offset_deg: 8.0,
        stick_gain: 1.2,
        shear_limit_mm: 1.5,
        slip_load_exponent: 0.7,
        slip_profile_mm: 30.0,
        shear_limit_deg: 2.0,
        stick_share: 0.4,
        edge_gain_in: 1.4,
        edge_gain_out: 0.7,
        edge_bite: 0.3,
        slip_poisson: 0.5,
    };
    known.apply(&mut truth);
    let model = TacTipModel::new(truth.clone()).expect("valid");
    let samples: Vec<FitSample> = taps()
        .into_iter()
        .map(|tap| FitSample {
            disp: displacement(&model, &model.edge_tap_pins(&tap))
                .into_iter()
                .map(Some)
                .collect(),
            tap,
        })
        .collect();
    let mut start = truth.clone();
    SlipParams {
        shear_angle_offset_deg: 0.0,
        stick_gain: 1.0,
        shear_limit_mm: 2.0,
        slip_load_exponent: 0.3,
        slip_profile_mm: 40.0,
        shear_limit_deg: 1.0,
        stick_share: 0.1,
        edge_gain_in: 1.0,
        edge_gain_out: 1.0,
        edge_bite: 0.0,
        slip_poisson: 0.5,
    }
    .apply(&mut start);
    let rest = model.rest_pins().to_vec();
    let fit = fit_slip(&start, rest, &samples, 4, 400).expect("fit runs");
    let p = fit.params;
    assert!(fit.rms_start_px > 0.3, "start misfit {}", fit.rms_start_px);
    assert!(fit.rms_px < 0.01, "end misfit {} px; {p:?}", fit.rms_px);
    assert!((p.shear_angle_offset_deg - 8.0).abs() < 0.5, "{p:?}");
    assert!((p.stick_gain - 1.2).abs() < 0.05, "{p:?}");
    assert!((p.shear_limit_mm - 1.5).abs() < 0.1, "{p:?}");
    assert!((p.slip_load_exponent - 0.7).abs() < 0.1, "{p:?}");
    assert!((p.slip_profile_mm - 30.0).abs() < 1.5, "{p:?}");
    assert!((p.stick_share - 0.4).abs() < 0.05, "{p:?}");
    assert!((p.edge_gain_in - 1.4).abs() < 0.05, "{p:?}");
    assert!((p.edge_gain_out - 0.7).abs() < 0.05, "{p:?}");
    assert!((p.edge_bite - 0.3).abs() < 0.05, "{p:?}");
}
