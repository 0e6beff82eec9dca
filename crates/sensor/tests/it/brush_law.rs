//! The brush slip law (eqs. B1-B3) through the whole model.
use tactrace_geometry::{Pose, Vec2};
use tactrace_sensor::{Shear, SlipLaw, TacTipConfig, TacTipModel};

fn model(law: SlipLaw) -> TacTipModel {
    let mut cfg = TacTipConfig::default();
    cfg.mechanics.slip_law = law;
    cfg.nuisance.pin_jitter_px = 0.0;
    TacTipModel::new(cfg).expect("valid")
}

/// Mean pin displacement (px) between two sets of pins.
fn mean_shift(a: &[[f64; 2]], b: &[[f64; 2]]) -> [f64; 2] {
    let n = a.len() as f64;
    a.iter().zip(b).fold([0.0; 2], |s, (p, q)| {
        [s[0] + (p[0] - q[0]) / n, s[1] + (p[1] - q[1]) / n]
    })
}

#[test]
fn no_slide_is_no_slip_and_opposite_slides_drag_the_skin_opposite_ways() {
    let brush = model(SlipLaw::Brush);
    // Object: the half-plane y > -3 (the sensor's centre 3 mm inside).
    let sd = |p: Vec2| -3.0 - p.y;
    let tip = Pose::planar(0.0, 0.0, -5.0, 0.0);
    let still = brush.pins_sdf(&sd, tip, None);
    let zero = brush.pins_sdf(&sd, tip, Some(Shear::default()));
    assert_eq!(still, zero, "a zero slide is no slide");
    let along = |dx: f64| Shear {
        dx_mm: dx,
        dy_mm: 0.0,
        drz_deg: 0.0,
    };
    let plus = mean_shift(&brush.pins_sdf(&sd, tip, Some(along(2.0))), &still);
    let minus = mean_shift(&brush.pins_sdf(&sd, tip, Some(along(-2.0))), &still);
    let size = plus[0].hypot(plus[1]);
    assert!(
        size > 0.2,
        "a 2 mm slide in contact moves the pins: {plus:?}"
    );
    let dot = plus[0] * minus[0] + plus[1] * minus[1];
    assert!(dot < -0.5 * size * size, "{plus:?} vs {minus:?}");
    // The lumped law gives the same direction for the same slide.
    let lag = model(SlipLaw::Lag);
    let still_lag = lag.pins_sdf(&sd, tip, None);
    let lag_plus = mean_shift(&lag.pins_sdf(&sd, tip, Some(along(2.0))), &still_lag);
    assert!(
        plus[0] * lag_plus[0] + plus[1] * lag_plus[1] > 0.0,
        "{plus:?} vs {lag_plus:?}"
    );
}
