//! Stick-slip of the skin under a slide or twist made in contact
//! (docs/sensor-model.md, eq. S7).
//!
//! The skin in contact sticks to the object while the sensor body slides,
//! so the whole membrane lags the slide until the elastic pull exceeds
//! friction; then it slips and the lag stays at a limit that grows with
//! the normal load (Coulomb: friction ~ mu N). The lag is spread over the
//! skin by a radial profile (the sensor body holds the skin at its base).
use crate::config::{Mechanics, SlipSpread};
use crate::contact::Shear;

/// Contact load (indented volume, mm^3) at which the slip limit equals
/// `Mechanics::shear_limit_mm` (eq. S7a).
pub const REFERENCE_LOAD_MM3: f64 = 1000.0;

/// Slip limit L(P) = L_ref (P / P_ref)^beta, mm (eq. S7a): the largest lag
/// the skin holds before it slips, for the contact load `load_mm3`.
pub fn slip_limit(mech: &Mechanics, load_mm3: f64) -> f64 {
    if load_mm3 <= 0.0 {
        return 0.0;
    }
    mech.shear_limit_mm * (load_mm3 / REFERENCE_LOAD_MM3).powf(mech.slip_load_exponent)
}

/// Lag of the skin (mm, sensor frame) for the slide `slide` (mm, sensor
/// frame): -L tanh(kappa |m| / L) m / |m| (eq. S7b). kappa is the stick
/// gain (lag per mm of slide while the skin sticks); L the slip limit.
/// Odd in the slide, zero at zero slide, |lag| < L.
pub fn skin_lag(mech: &Mechanics, load_mm3: f64, slide: [f64; 2]) -> [f64; 2] {
    let limit = slip_limit(mech, load_mm3);
    let size = slide[0].hypot(slide[1]);
    if size <= 1e-12 || limit <= 0.0 {
        return [0.0; 2];
    }
    let lag = limit * (mech.stick_gain * size / limit).tanh() / size;
    [-lag * slide[0], -lag * slide[1]]
}

/// Share of the skin lag a pin at distance `s` (mm along the skin from the
/// pole) carries: phi(s) = max(0, 1 - (s / S_T)^2) (eq. S7c).
pub fn lag_profile(mech: &Mechanics, s: f64) -> f64 {
    (1.0 - (s / mech.slip_profile_mm).powi(2)).max(0.0)
}

/// Slip displacement of every pin (mm on the skin, sensor frame; eq. S7):
/// the skin lag times the pin's share (1 - alpha) phi_i + alpha D_i / max D
/// (eq. S7e: a share alpha follows the contact pressure, the stuck patch,
/// the rest the radial profile), plus the twist, a rotation by
/// -Theta tanh(twist / Theta) about the contact centroid weighted by the
/// contact weight w_i = D_i / (D_i + D_0) and phi_i. Zero without load.
pub fn slip_field(
    mech: &Mechanics,
    pins_g: &[[f64; 2]],
    contact: ContactState,
    shear: Shear,
) -> Vec<[f64; 2]> {
    let ContactState {
        smoothed,
        load_mm3,
        edge_normal,
        cerruti,
    } = contact;
    let mut out = vec![[0.0; 2]; pins_g.len()];
    if load_mm3 <= 0.0 {
        return out;
    }
    let slide = edge_slide(mech, edge_normal, [shear.dx_mm, shear.dy_mm]);
    let lag = skin_lag(mech, load_mm3, slide);
    let bite = edge_bite(mech, edge_normal, [shear.dx_mm, shear.dy_mm]);
    let weights: Vec<f64> = smoothed
        .iter()
        .map(|d| d / (d + mech.contact_scale_mm))
        .collect();
    let centre = weighted_centre(pins_g, &weights);
    let peak = smoothed.iter().copied().fold(0.0, f64::max).max(1e-12);
    let alpha = mech.stick_share;
    let lim = mech.shear_limit_deg;
    let twist = -(lim * (shear.drz_deg / lim).tanh()).to_radians();
    let (c, s) = (twist.cos(), twist.sin());
    let spread = pressed_spread(mech, smoothed, cerruti, lag);
    let pins = pins_g.iter().zip(&weights).zip(smoothed).zip(spread);
    for ((((g, w), d), pressed_lag), o) in pins.zip(out.iter_mut()) {
        let phi = lag_profile(mech, g[0].hypot(g[1]));
        let r = [g[0] - centre[0], g[1] - centre[1]];
        let turn = [c * r[0] - s * r[1] - r[0], s * r[0] + c * r[1] - r[1]];
        let pressed = d / peak;
        let skin = (1.0 - alpha) * phi;
        *o = [
            skin * lag[0] + alpha * pressed_lag[0] + pressed * bite[0] + phi * w * turn[0],
            skin * lag[1] + alpha * pressed_lag[1] + pressed * bite[1] + phi * w * turn[1],
        ];
    }
    out
}

/// The lag the pressed skin passes to each pin (eq. S7e/h): the lag
/// times D_i / max D for the pressure spread; for the Cerruti spread the
/// half-space response (1 - nu) S_i lag + nu T_i lag (S_i = sum p dA / rho,
/// T_i = sum p dA d d^T / rho^3), divided by the largest S_i.
fn pressed_spread(
    mech: &Mechanics,
    smoothed: &[f64],
    cerruti: &[[f64; 4]],
    lag: [f64; 2],
) -> Vec<[f64; 2]> {
    if mech.slip_spread == SlipSpread::Pressure || cerruti.len() != smoothed.len() {
        let peak = smoothed.iter().copied().fold(0.0, f64::max).max(1e-12);
        return smoothed
            .iter()
            .map(|d| [d / peak * lag[0], d / peak * lag[1]])
            .collect();
    }
    let peak = cerruti.iter().map(|c| c[0]).fold(0.0, f64::max).max(1e-12);
    let nu = mech.slip_poisson;
    cerruti
        .iter()
        .map(|c| {
            let iso = (1.0 - nu) * c[0];
            [
                (iso * lag[0] + nu * (c[1] * lag[0] + c[2] * lag[1])) / peak,
                (iso * lag[1] + nu * (c[2] * lag[0] + c[3] * lag[1])) / peak,
            ]
        })
        .collect()
}

/// What [`slip_field`] needs of the contact (eqs. S5, S7a, S7f).
#[derive(Debug, Clone, Copy)]
pub struct ContactState<'a> {
    /// Smoothed indentation D_i under each pin, mm (eq. S5).
    pub smoothed: &'a [f64],
    /// Contact load P (indented volume), mm^3 (eq. S7a).
    pub load_mm3: f64,
    /// Edge normal into the object times the edge's proximity (eq. S7f).
    pub edge_normal: [f64; 2],
    /// Cerruti sums per pin (eq. S7h; empty for the pressure spread):
    /// [sum p dA / rho, sum p dA dx^2 / rho^3, dx dy, dy^2].
    pub cerruti: &'a [[f64; 4]],
}

/// The slide as the skin feels it at an edge (eq. S7f): its component
/// along the edge normal n (proximity e = |n|) scaled by
/// 1 + e (rho - 1), rho = `edge_gain_in` when the slide goes into the
/// object, `edge_gain_out` when it leaves it; the tangential part kept.
pub fn edge_slide(mech: &Mechanics, edge_normal: [f64; 2], slide: [f64; 2]) -> [f64; 2] {
    let e = edge_normal[0].hypot(edge_normal[1]);
    if e < 1e-12 {
        return slide;
    }
    let n = [edge_normal[0] / e, edge_normal[1] / e];
    let along = slide[0] * n[0] + slide[1] * n[1];
    let rho = if along > 0.0 {
        mech.edge_gain_in
    } else {
        mech.edge_gain_out
    };
    let extra = e * (rho - 1.0) * along;
    [slide[0] + extra * n[0], slide[1] + extra * n[1]]
}

/// The edge's bite (eq. S7g): the skin caught by the edge's corner is
/// pushed back along the normal without slipping, -gamma e (m . n) n
/// (mm), carried by the pressed pins (share D_i / max D).
pub fn edge_bite(mech: &Mechanics, edge_normal: [f64; 2], slide: [f64; 2]) -> [f64; 2] {
    let along = slide[0] * edge_normal[0] + slide[1] * edge_normal[1];
    let g = mech.edge_bite;
    [-g * along * edge_normal[0], -g * along * edge_normal[1]]
}

/// Centroid of the pins weighted by `weights` (the pole when all are zero).
fn weighted_centre(pins_g: &[[f64; 2]], weights: &[f64]) -> [f64; 2] {
    let total: f64 = weights.iter().sum();
    if total <= 1e-12 {
        return [0.0; 2];
    }
    pins_g.iter().zip(weights).fold([0.0; 2], |a, (g, w)| {
        [a[0] + w * g[0] / total, a[1] + w * g[1] / total]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mech() -> Mechanics {
        Mechanics::default()
    }

    fn state(smoothed: &[f64], load_mm3: f64) -> ContactState<'_> {
        ContactState {
            smoothed,
            load_mm3,
            edge_normal: [0.0; 2],
            cerruti: &[],
        }
    }

    #[test]
    fn an_edge_scales_only_the_normal_part_of_the_slide_by_its_side() {
        let mut m = mech();
        m.edge_gain_in = 1.5;
        m.edge_gain_out = 0.5;
        // No edge, or an edge with unit gains: the slide is unchanged.
        assert_eq!(edge_slide(&m, [0.0; 2], [2.0, -1.0]), [2.0, -1.0]);
        let mut iso = m.clone();
        (iso.edge_gain_in, iso.edge_gain_out) = (1.0, 1.0);
        assert_eq!(edge_slide(&iso, [0.0, 1.0], [2.0, -1.0]), [2.0, -1.0]);
        // Normal +y: into the object the normal part grows, out of it shrinks;
        // the tangential part stays.
        assert_eq!(edge_slide(&m, [0.0, 1.0], [2.0, 1.0]), [2.0, 1.5]);
        assert_eq!(edge_slide(&m, [0.0, 1.0], [2.0, -1.0]), [2.0, -0.5]);
        // Half proximity: half the change.
        assert_eq!(edge_slide(&m, [0.0, 0.5], [0.0, 1.0]), [0.0, 1.25]);
    }

    /// Eq. S7h's theory: a point load's response along the load is
    /// 1 / (1 - nu) times the response across it at the same distance, and
    /// a pin on the load's axis is not pushed sideways.
    #[test]
    fn the_cerruti_spread_pushes_twice_as_far_along_the_load_when_incompressible() {
        let mut m = mech();
        m.slip_spread = SlipSpread::Cerruti;
        m.slip_poisson = 0.5;
        // One unit load at the origin; pins at (5, 0) and (0, 5), no core:
        // [1 / rho, dx^2 / rho^3, dx dy / rho^3, dy^2 / rho^3].
        let sums = [[0.2, 0.2, 0.0, 0.0], [0.2, 0.0, 0.0, 0.2]];
        let out = pressed_spread(&m, &[1.0, 1.0], &sums, [1.0, 0.0]);
        assert!(
            (out[0][0] - 1.0).abs() < 1e-12 && out[0][1] == 0.0,
            "{out:?}"
        );
        assert!(
            (out[1][0] - 0.5).abs() < 1e-12 && out[1][1] == 0.0,
            "{out:?}"
        );
        m.slip_poisson = 0.25;
        let out = pressed_spread(&m, &[1.0, 1.0], &sums, [1.0, 0.0]);
        assert!(
            (out[0][0] / out[1][0] - 1.0 / 0.75).abs() < 1e-12,
            "{out:?}"
        );
        // The pressure spread ignores the sums.
        m.slip_spread = SlipSpread::Pressure;
        let out = pressed_spread(&m, &[1.0, 0.5], &sums, [2.0, 0.0]);
        assert_eq!(out, vec![[2.0, 0.0], [1.0, 0.0]]);
    }

    #[test]
    fn zero_slide_or_zero_load_gives_no_lag() {
        let m = mech();
        assert_eq!(skin_lag(&m, 800.0, [0.0, 0.0]), [0.0, 0.0]);
        assert_eq!(skin_lag(&m, 0.0, [3.0, -1.0]), [0.0, 0.0]);
        let pins = [[0.0, 0.0], [4.0, 1.0]];
        let none = Shear::default();
        assert_eq!(
            slip_field(&m, &pins, state(&[0.5, 0.2], 900.0), none),
            vec![[0.0; 2]; 2]
        );
    }

    #[test]
    fn lag_opposes_the_slide_is_odd_and_saturates_at_the_slip_limit() {
        let m = mech();
        let load = 1500.0;
        let limit = slip_limit(&m, load);
        let a = skin_lag(&m, load, [0.3, 0.4]);
        let b = skin_lag(&m, load, [-0.3, -0.4]);
        assert!(a[0] < 0.0 && a[1] < 0.0, "lag opposes the slide: {a:?}");
        assert!((a[0] + b[0]).abs() < 1e-12 && (a[1] + b[1]).abs() < 1e-12);
        // Small slides stick: lag = kappa |m|.
        let small = skin_lag(&m, load, [1e-4, 0.0]);
        assert!((small[0] + m.stick_gain * 1e-4).abs() < 1e-9);
        // Large slides slip: lag -> L(P), never beyond.
        let huge = skin_lag(&m, load, [0.0, 100.0]);
        assert!(
            (huge[1] + limit).abs() < 1e-6 * limit,
            "{huge:?} vs {limit}"
        );
        for size in [0.5, 1.0, 2.0, 4.0, 8.0] {
            assert!(skin_lag(&m, load, [size, 0.0])[0].abs() < limit);
        }
    }

    #[test]
    fn heavier_contact_holds_a_larger_lag() {
        let mut m = mech();
        m.slip_load_exponent = 0.8;
        let light = slip_limit(&m, 400.0);
        let heavy = slip_limit(&m, 1600.0);
        assert!((slip_limit(&m, REFERENCE_LOAD_MM3) - m.shear_limit_mm).abs() < 1e-12);
        assert!((heavy / light - 4f64.powf(0.8)).abs() < 1e-9);
    }

    #[test]
    fn profile_is_one_at_the_pole_and_zero_beyond_its_reach() {
        let m = mech();
        assert_eq!(lag_profile(&m, 0.0), 1.0);
        assert_eq!(lag_profile(&m, m.slip_profile_mm * 1.01), 0.0);
        assert!(lag_profile(&m, 10.0) > lag_profile(&m, 20.0));
    }

    #[test]
    fn a_pure_slide_moves_every_pin_the_same_way_scaled_by_the_profile() {
        let m = mech();
        let pins = [[0.0, 0.0], [4.0, 0.0], [0.0, -12.0]];
        let shear = Shear {
            dx_mm: 2.0,
            dy_mm: 0.0,
            drz_deg: 0.0,
        };
        let pressure = [1.0, 0.5, 0.0];
        let f = slip_field(&m, &pins, state(&pressure, 1000.0), shear);
        let lag = skin_lag(&m, 1000.0, [2.0, 0.0]);
        for ((g, u), d) in pins.iter().zip(&f).zip(pressure) {
            let phi = lag_profile(&m, g[0].hypot(g[1]));
            let share = (1.0 - m.stick_share) * phi + m.stick_share * d;
            assert!((u[0] - share * lag[0]).abs() < 1e-12 && u[1].abs() < 1e-12);
        }
    }
}
