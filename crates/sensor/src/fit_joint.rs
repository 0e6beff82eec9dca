//! Joint per-frame fit of the label calibration, the contact mechanics
//! (eqs. S4-S8a) and the stick-slip law (eq. S7) to measured fields, each
//! frame simulated with its labelled slide (docs/sensor-model.md, "Joint
//! fit"). Pure, like [`crate::fit_slip`].
use crate::fit::{misfit_sums, FitSample};
use crate::nelder_mead::minimise;
use crate::{SensorError, TacTipConfig, TacTipModel};

/// A fitted parameter: name, getter, setter, first step, allowed range.
type Param = (
    &'static str,
    fn(&TacTipConfig) -> f64,
    fn(&mut TacTipConfig, f64),
    f64,
    [f64; 2],
);

/// The parameters [`fit_joint`] moves, with their first steps and ranges.
pub const JOINT_PARAMS: [&str; 17] = [
    "calibration.angle_scale",
    "calibration.edge_scale",
    "calibration.angle_offset_deg",
    "calibration.edge_offset_mm",
    "calibration.tap_depth_mm",
    "calibration.depth_per_offset",
    "calibration.shear_angle_offset_deg",
    "mechanics.flow_core_mm",
    "mechanics.kernel_width_mm",
    "mechanics.layer_thickness_mm",
    "mechanics.lift_gain",
    "mechanics.rim_clamp_mm",
    "mechanics.stick_gain",
    "mechanics.shear_limit_mm",
    "mechanics.slip_load_exponent",
    "mechanics.slip_profile_mm",
    "mechanics.shear_limit_deg",
];

fn params() -> [Param; 17] {
    [
        (
            "angle_scale",
            |c| c.calibration.angle_scale,
            |c, v| c.calibration.angle_scale = v,
            0.1,
            [-2.0, 2.0],
        ),
        (
            "edge_scale",
            |c| c.calibration.edge_scale,
            |c, v| c.calibration.edge_scale = v,
            0.1,
            [-3.0, 3.0],
        ),
        (
            "angle",
            |c| c.calibration.angle_offset_deg,
            |c, v| c.calibration.angle_offset_deg = v,
            3.0,
            [-360.0, 360.0],
        ),
        (
            "edge",
            |c| c.calibration.edge_offset_mm,
            |c, v| c.calibration.edge_offset_mm = v,
            0.5,
            [-8.0, 8.0],
        ),
        (
            "depth",
            |c| c.calibration.tap_depth_mm,
            |c, v| c.calibration.tap_depth_mm = v,
            0.5,
            [0.5, 7.5],
        ),
        (
            "per_offset",
            |c| c.calibration.depth_per_offset,
            |c, v| c.calibration.depth_per_offset = v,
            0.3,
            [-3.0, 0.0],
        ),
        (
            "psi",
            |c| c.calibration.shear_angle_offset_deg,
            |c, v| c.calibration.shear_angle_offset_deg = v,
            3.0,
            [-60.0, 60.0],
        ),
        (
            "core",
            |c| c.mechanics.flow_core_mm,
            |c, v| c.mechanics.flow_core_mm = v,
            0.3,
            [0.1, 10.0],
        ),
        (
            "kernel",
            |c| c.mechanics.kernel_width_mm,
            |c, v| c.mechanics.kernel_width_mm = v,
            1.0,
            [0.5, 15.0],
        ),
        (
            "layer",
            |c| c.mechanics.layer_thickness_mm,
            |c, v| c.mechanics.layer_thickness_mm = v,
            2.0,
            [0.5, 500.0],
        ),
        (
            "lift",
            |c| c.mechanics.lift_gain,
            |c, v| c.mechanics.lift_gain = v,
            0.1,
            [0.0, 6.0],
        ),
        (
            "rim",
            |c| c.mechanics.rim_clamp_mm,
            |c, v| c.mechanics.rim_clamp_mm = v,
            3.0,
            [12.0, 1e4],
        ),
        (
            "kappa",
            |c| c.mechanics.stick_gain,
            |c, v| c.mechanics.stick_gain = v,
            0.2,
            [0.01, 5.0],
        ),
        (
            "slip",
            |c| c.mechanics.shear_limit_mm,
            |c, v| c.mechanics.shear_limit_mm = v,
            0.2,
            [0.05, 15.0],
        ),
        (
            "beta",
            |c| c.mechanics.slip_load_exponent,
            |c, v| c.mechanics.slip_load_exponent = v,
            0.2,
            [-1.0, 3.0],
        ),
        (
            "reach",
            |c| c.mechanics.slip_profile_mm,
            |c, v| c.mechanics.slip_profile_mm = v,
            3.0,
            [5.0, 300.0],
        ),
        (
            "twist",
            |c| c.mechanics.shear_limit_deg,
            |c, v| c.mechanics.shear_limit_deg = v,
            1.0,
            [0.01, 45.0],
        ),
    ]
}

/// Outcome of [`fit_joint`]: the fitted configuration and the
/// per-coordinate RMS pin misfit (px) at the start and at the end.
#[derive(Debug, Clone)]
pub struct JointFit {
    pub config: TacTipConfig,
    pub rms_start_px: f64,
    pub rms_px: f64,
    pub frames: usize,
}

/// Fit the seventeen [`JOINT_PARAMS`] from `cfg` to the samples (each with
/// its labelled slide), `rounds` Nelder-Mead restarts of `iterations`
/// steps with halving first steps. Simulation runs on `threads` threads.
pub fn fit_joint(
    cfg: &TacTipConfig,
    rest_px: &[[f64; 2]],
    samples: &[FitSample],
    (rounds, iterations, threads): (usize, usize, usize),
) -> Result<JointFit, SensorError> {
    TacTipModel::with_rest_pins(cfg.clone(), rest_px.to_vec())?;
    let table = params();
    let build = |x: &[f64]| -> Option<TacTipConfig> {
        let mut c = cfg.clone();
        for ((_, _, set, _, range), v) in table.iter().zip(x) {
            if !(range[0]..=range[1]).contains(v) {
                return None;
            }
            set(&mut c, *v);
        }
        Some(c)
    };
    let objective = |x: &[f64]| -> f64 {
        let Some(c) = build(x) else {
            return f64::INFINITY;
        };
        let Ok(model) = TacTipModel::with_rest_pins(c, rest_px.to_vec()) else {
            return f64::INFINITY;
        };
        parallel_sse(&model, samples, threads.max(1))
    };
    let count: usize = samples
        .iter()
        .map(|s| s.disp.iter().flatten().count())
        .sum();
    let rms = |sse: f64| (sse / (2 * count.max(1)) as f64).sqrt();
    let mut x: Vec<f64> = table.iter().map(|p| (p.1)(cfg)).collect();
    let start = objective(&x);
    for round in 0..rounds {
        let step: Vec<f64> = table
            .iter()
            .map(|p| p.3 * 0.5f64.powi(round as i32))
            .collect();
        x = minimise(&objective, &x, &step, iterations).0;
    }
    let end = objective(&x);
    Ok(JointFit {
        config: build(&x).unwrap_or_else(|| cfg.clone()),
        rms_start_px: rms(start),
        rms_px: rms(end),
        frames: samples.len(),
    })
}

/// Sum of squared pin differences over the samples, split over threads.
fn parallel_sse(model: &TacTipModel, samples: &[FitSample], threads: usize) -> f64 {
    let chunk = samples.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        let handles: Vec<_> = samples
            .chunks(chunk)
            .map(|part| scope.spawn(move || misfit_sums(model, part)[0]))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or(f64::INFINITY))
            .sum()
    })
}
