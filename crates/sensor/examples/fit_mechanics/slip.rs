//! `FIT=slip`: the stick-slip law (eq. S7) fitted frame by frame on the
//! fit part (frame number N % 5 in 2..=4) with each frame's label shear;
//! the field misfit reported on the select (N % 5 = 1) and score
//! (N % 5 = 0) parts before and after.
use crate::support::RealTap;
use tactrace_sensor::{
    field_misfit, fit_brush, fit_joint, fit_slip, FitSample, TacTipConfig, TacTipModel,
    JOINT_PARAMS,
};

fn samples(taps: &[RealTap], part: &dyn Fn(usize) -> bool) -> Vec<FitSample> {
    taps.iter()
        .filter(|t| part(t.number % 5))
        .map(|t| FitSample {
            tap: t.tap,
            disp: t.disp.clone(),
        })
        .collect()
}

/// The fit (N % 5 in 2..=4), select (1) and score (0) parts.
fn split(taps: &[RealTap]) -> [Vec<FitSample>; 3] {
    [
        samples(taps, &|k| k >= 2),
        samples(taps, &|k| k == 1),
        samples(taps, &|k| k == 0),
    ]
}

fn misfit(label: &str, cfg: &TacTipConfig, rest: &[[f64; 2]], parts: &[(&str, &[FitSample])]) {
    let model = TacTipModel::with_rest_pins(cfg.clone(), rest.to_vec()).expect("model");
    for (name, s) in parts {
        let (rms, cos) = field_misfit(&model, s);
        println!("{label:<7} {name:<6} ({} frames): RMS {rms:.3} px per coordinate, mean cosine {cos:.3}", s.len());
    }
}

/// Fit from `cfg` and return the fitted configuration.
pub fn run(cfg: &TacTipConfig, rest: &[[f64; 2]], taps: &[RealTap]) -> TacTipConfig {
    let [fit, select, score] = split(taps);
    let parts: [(&str, &[FitSample]); 3] = [("fit", &fit), ("select", &select), ("score", &score)];
    misfit("before", cfg, rest, &parts);
    let rounds = std::env::var("ROUNDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let result = fit_slip(cfg, rest.to_vec(), &fit, rounds, 300).expect("fit");
    println!(
        "fit on {} frames: RMS {:.3} -> {:.3} px\n{:#?}",
        result.frames, result.rms_start_px, result.rms_px, result.params
    );
    let mut out = cfg.clone();
    result.params.apply(&mut out);
    misfit("after", &out, rest, &parts);
    if let Ok(path) = std::env::var("OUT_TOML") {
        let (m, c) = (&out.mechanics, &out.calibration);
        let spread = format!("{:?}", m.slip_spread).to_lowercase();
        let table = format!(
            "[sensor.calibration]\nshear_angle_offset_deg = {}\n\n[sensor.mechanics]\nstick_gain = {}\nshear_limit_mm = {}\nslip_load_exponent = {}\nslip_profile_mm = {}\nshear_limit_deg = {}\nstick_share = {}\nedge_gain_in = {}\nedge_gain_out = {}\nedge_bite = {}\nslip_poisson = {}\nslip_spread = \"{spread}\"\nslip_core_mm = {}\n",
            c.shear_angle_offset_deg, m.stick_gain, m.shear_limit_mm, m.slip_load_exponent,
            m.slip_profile_mm, m.shear_limit_deg, m.stick_share, m.edge_gain_in,
            m.edge_gain_out, m.edge_bite, m.slip_poisson, m.slip_core_mm
        );
        std::fs::write(path, table).expect("write OUT_TOML");
    }
    out
}

/// `FIT=joint`: all fifteen parameters on every `STRIDE`-th fit-part frame
/// (default 2), then the misfit on all three parts.
pub fn run_joint(cfg: &TacTipConfig, rest: &[[f64; 2]], taps: &[RealTap]) -> TacTipConfig {
    let [fit, select, score] = split(taps);
    let parts: [(&str, &[FitSample]); 3] = [("fit", &fit), ("select", &select), ("score", &score)];
    misfit("before", cfg, rest, &parts);
    let env = |k: &str, d: usize| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let stride = env("STRIDE", 2);
    let sub: Vec<FitSample> = fit.iter().step_by(stride).cloned().collect();
    let plan = (env("ROUNDS", 2), env("ITERS", 250), env("THREADS", 2));
    let result = fit_joint(cfg, rest, &sub, plan).expect("joint fit");
    println!(
        "joint fit on {} frames: RMS {:.3} -> {:.3} px",
        result.frames, result.rms_start_px, result.rms_px
    );
    println!("{}", JOINT_PARAMS.join(" "));
    misfit("after", &result.config, rest, &parts);
    println!("{:#?}", result.config.calibration);
    println!("{:#?}", result.config.mechanics);
    result.config
}

/// `FIT=brush`: the brush slip law (eqs. B1-B3) on every `STRIDE`-th
/// fit-part frame (default 1), then the misfit on all three parts; with
/// `OUT_TOML=path`, the fitted brush parameters as a rig-file table.
pub fn run_brush(cfg: &TacTipConfig, rest: &[[f64; 2]], taps: &[RealTap]) -> TacTipConfig {
    let [fit, select, score] = split(taps);
    let parts: [(&str, &[FitSample]); 3] = [("fit", &fit), ("select", &select), ("score", &score)];
    misfit("before", cfg, rest, &parts);
    let env = |k: &str, d: usize| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let sub: Vec<FitSample> = fit.iter().step_by(env("STRIDE", 1)).cloned().collect();
    let plan = (env("ROUNDS", 2), env("ITERS", 200), env("THREADS", 2));
    let result = fit_brush(cfg, rest.to_vec(), &sub, plan).expect("brush fit");
    println!(
        "brush fit on {} frames: RMS {:.3} -> {:.3} px",
        result.frames, result.rms_start_px, result.rms_px
    );
    misfit("after", &result.config, rest, &parts);
    let m = &result.config.mechanics;
    let table = format!(
        "[sensor.mechanics]\nslip_law = \"brush\"\nbrush_slip_ratio = {}\nbrush_local_gain = {}\nbrush_skin_gain = {}\nslip_profile_mm = {}\nbrush_steps = {}\n",
        m.brush_slip_ratio, m.brush_local_gain, m.brush_skin_gain, m.slip_profile_mm, m.brush_steps
    );
    print!("{table}");
    if let Ok(path) = std::env::var("OUT_TOML") {
        std::fs::write(path, table).expect("write OUT_TOML");
    }
    result.config
}
