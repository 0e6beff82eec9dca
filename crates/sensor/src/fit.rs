//! Fit of the skin's stick-slip law (eq. S7) to measured displacement
//! fields, frame by frame with each frame's labelled slide
//! (docs/sensor-model.md, "Slip fit"). Pure: the caller reads the frames;
//! a `calibrate` command or the `fit_mechanics` example drives it.
//!
//! The contact state without slip (eqs. S4-S6) does not depend on the
//! slip parameters, so it is computed once per frame; each evaluation
//! only adds the slip (eq. S7) and projects (eq. S8).
use crate::contact::ContactField;
use crate::nelder_mead::minimise;
use crate::{EdgeTap, SensorError, TacTipConfig, TacTipModel};

/// One measured tap: its labels and the measured pin displacement (px,
/// image axes) in the order of the rest pins given to the fit (`None` =
/// pin not tracked).
#[derive(Debug, Clone)]
pub struct FitSample {
    pub tap: EdgeTap,
    pub disp: Vec<Option<[f64; 2]>>,
}

/// The parameters of eq. S7 that the fit moves.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SlipParams {
    /// `calibration.shear_angle_offset_deg` psi (eq. S7d).
    pub shear_angle_offset_deg: f64,
    /// `mechanics.stick_gain` kappa (eq. S7b).
    pub stick_gain: f64,
    /// `mechanics.shear_limit_mm` L_ref (eq. S7a).
    pub shear_limit_mm: f64,
    /// `mechanics.slip_load_exponent` beta (eq. S7a).
    pub slip_load_exponent: f64,
    /// `mechanics.slip_profile_mm` S_T (eq. S7c).
    pub slip_profile_mm: f64,
    /// `mechanics.shear_limit_deg` Theta (eq. S7).
    pub shear_limit_deg: f64,
    /// `mechanics.stick_share` alpha (eq. S7e).
    pub stick_share: f64,
    /// `mechanics.edge_gain_in` rho_in (eq. S7f).
    pub edge_gain_in: f64,
    /// `mechanics.edge_gain_out` rho_out (eq. S7f).
    pub edge_gain_out: f64,
    /// `mechanics.edge_bite` gamma (eq. S7g).
    pub edge_bite: f64,
    /// `mechanics.slip_poisson` nu (eq. S7h; moves only the Cerruti spread).
    pub slip_poisson: f64,
}

impl SlipParams {
    /// The slip parameters of `cfg`.
    pub fn of(cfg: &TacTipConfig) -> Self {
        let m = &cfg.mechanics;
        Self {
            shear_angle_offset_deg: cfg.calibration.shear_angle_offset_deg,
            stick_gain: m.stick_gain,
            shear_limit_mm: m.shear_limit_mm,
            slip_load_exponent: m.slip_load_exponent,
            slip_profile_mm: m.slip_profile_mm,
            shear_limit_deg: m.shear_limit_deg,
            stick_share: m.stick_share,
            edge_gain_in: m.edge_gain_in,
            edge_gain_out: m.edge_gain_out,
            edge_bite: m.edge_bite,
            slip_poisson: m.slip_poisson,
        }
    }

    /// Write these parameters into `cfg`.
    pub fn apply(&self, cfg: &mut TacTipConfig) {
        let m = &mut cfg.mechanics;
        cfg.calibration.shear_angle_offset_deg = self.shear_angle_offset_deg;
        m.stick_gain = self.stick_gain;
        m.shear_limit_mm = self.shear_limit_mm;
        m.slip_load_exponent = self.slip_load_exponent;
        m.slip_profile_mm = self.slip_profile_mm;
        m.shear_limit_deg = self.shear_limit_deg;
        m.stick_share = self.stick_share;
        m.edge_gain_in = self.edge_gain_in;
        m.edge_gain_out = self.edge_gain_out;
        m.edge_bite = self.edge_bite;
        m.slip_poisson = self.slip_poisson;
    }

    fn to_vec(self) -> Vec<f64> {
        vec![
            self.shear_angle_offset_deg,
            self.stick_gain,
            self.shear_limit_mm,
            self.slip_load_exponent,
            self.slip_profile_mm,
            self.shear_limit_deg,
            self.stick_share,
            self.edge_gain_in,
            self.edge_gain_out,
            self.edge_bite,
            self.slip_poisson,
        ]
    }

    /// From the search vector, `None` outside the physical ranges.
    fn from_vec(x: &[f64]) -> Option<Self> {
        let ok = x[0].abs() < 60.0
            && (0.01..5.0).contains(&x[1])
            && (0.05..15.0).contains(&x[2])
            && (-1.0..3.0).contains(&x[3])
            && (5.0..300.0).contains(&x[4])
            && (0.01..45.0).contains(&x[5])
            && (-1.0..2.0).contains(&x[6])
            && (0.0..5.0).contains(&x[7])
            && (0.0..5.0).contains(&x[8])
            && (-3.0..3.0).contains(&x[9])
            && (0.0..=0.5).contains(&x[10]);
        ok.then_some(Self {
            shear_angle_offset_deg: x[0],
            stick_gain: x[1],
            shear_limit_mm: x[2],
            slip_load_exponent: x[3],
            slip_profile_mm: x[4],
            shear_limit_deg: x[5],
            stick_share: x[6],
            edge_gain_in: x[7],
            edge_gain_out: x[8],
            edge_bite: x[9],
            slip_poisson: x[10],
        })
    }
}

/// Outcome of [`fit_slip`]: the parameters and the per-coordinate RMS
/// pin misfit (px) over the samples at the start and at the end.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SlipFit {
    pub params: SlipParams,
    pub rms_start_px: f64,
    pub rms_px: f64,
    pub frames: usize,
}

/// Field misfit of a model over measured samples: per-coordinate RMS of
/// the pin differences (px) and the mean per-frame cosine between the
/// stacked simulated and measured fields.
pub fn field_misfit(model: &TacTipModel, samples: &[FitSample]) -> (f64, f64) {
    let [sq, count, cos] = misfit_sums(model, samples);
    (
        (sq / count.max(1.0)).sqrt(),
        cos / samples.len().max(1) as f64,
    )
}

/// [sum of squared pin differences (px^2), coordinates, sum of per-frame
/// cosines] of the model's fields against the samples (eqs. S4-S8a).
pub(crate) fn misfit_sums(model: &TacTipModel, samples: &[FitSample]) -> [f64; 3] {
    let mut a = [0.0; 3];
    for s in samples {
        let sim = displacement(model, &model.edge_tap_pins(&s.tap));
        let f = compare(&sim, &s.disp);
        a[0] += f[0];
        a[1] += f[1];
        a[2] += f[2] / (f[3].sqrt() * f[4].sqrt()).max(1e-12);
    }
    a
}

/// Fit psi, kappa, L_ref, beta, S_T, Theta, alpha, rho_in, rho_out,
/// gamma and nu (eq. S7) to the samples,
/// starting from `cfg`, with the rest of `cfg` held; `rest_px` are the
/// rest pins the displacements are measured from. `rounds` restarts of
/// `iterations` Nelder-Mead steps each, with halving first steps.
pub fn fit_slip(
    cfg: &TacTipConfig,
    rest_px: Vec<[f64; 2]>,
    samples: &[FitSample],
    rounds: usize,
    iterations: usize,
) -> Result<SlipFit, SensorError> {
    let model = TacTipModel::with_rest_pins(cfg.clone(), rest_px)?;
    let states: Vec<ContactField> = samples.iter().map(|s| model.edge_contact(&s.tap)).collect();
    let objective = |x: &[f64]| -> f64 {
        let Some(p) = SlipParams::from_vec(x) else {
            return f64::INFINITY;
        };
        let mut c = cfg.clone();
        p.apply(&mut c);
        sum_squares(&model, &c, samples, &states)
    };
    let count: usize = samples
        .iter()
        .map(|s| s.disp.iter().flatten().count())
        .sum();
    let rms = |sse: f64| (sse / (2 * count.max(1)) as f64).sqrt();
    let mut x = SlipParams::of(cfg).to_vec();
    let start = objective(&x);
    let step = [5.0, 0.3, 0.5, 0.3, 10.0, 2.0, 0.3, 0.3, 0.3, 0.3, -0.1];
    for round in 0..rounds {
        let s: Vec<f64> = step.iter().map(|v| v * 0.5f64.powi(round as i32)).collect();
        x = minimise(&objective, &x, &s, iterations).0;
    }
    let params = SlipParams::from_vec(&x).unwrap_or_else(|| SlipParams::of(cfg));
    Ok(SlipFit {
        params,
        rms_start_px: rms(start),
        rms_px: rms(objective(&x)),
        frames: samples.len(),
    })
}

/// Sum of squared pin differences (px^2) with the slip law of `cfg`.
fn sum_squares(
    model: &TacTipModel,
    cfg: &TacTipConfig,
    samples: &[FitSample],
    states: &[ContactField],
) -> f64 {
    samples
        .iter()
        .zip(states)
        .map(|(s, state)| {
            let shear = s.tap.sensor_shear_with(&cfg.calibration);
            let pins = model.compose(state, &cfg.mechanics, shear);
            compare(&displacement(model, &pins), &s.disp)[0]
        })
        .sum()
}

pub(crate) fn displacement(model: &TacTipModel, pins: &[[f64; 2]]) -> Vec<[f64; 2]> {
    pins.iter()
        .zip(model.rest_pins())
        .map(|(p, r)| [p[0] - r[0], p[1] - r[1]])
        .collect()
}

/// [squared difference, coordinates, dot, |sim|^2, |real|^2] over the
/// tracked pins.
pub(crate) fn compare(sim: &[[f64; 2]], real: &[Option<[f64; 2]>]) -> [f64; 5] {
    let mut a = [0.0; 5];
    for (e, d) in sim.iter().zip(real) {
        if let Some(d) = d {
            a[0] += (e[0] - d[0]).powi(2) + (e[1] - d[1]).powi(2);
            a[1] += 2.0;
            a[2] += e[0] * d[0] + e[1] * d[1];
            a[3] += e[0] * e[0] + e[1] * e[1];
            a[4] += d[0] * d[0] + d[1] * d[1];
        }
    }
    a
}
