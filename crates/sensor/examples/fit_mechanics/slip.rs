//! `FIT=slip`: the stick-slip law (eq. S7) fitted frame by frame on the
//! fit part (frame number N % 5 in 2..=4) with each frame's label shear;
//! the field misfit reported on the select (N % 5 = 1) and score
//! (N % 5 = 0) parts before and after.
use crate::support::RealTap;
use tactrace_sensor::{
    field_misfit, fit_joint, fit_slip, FitSample, TacTipConfig, TacTipModel, JOINT_PARAMS,
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

fn misfit(label: &str, cfg: &TacTipConfig, rest: &[[f64; 2]], parts: &[(&str, &[FitSample])]) {
    let model = TacTipModel::with_rest_pins(cfg.clone(), rest.to_vec()).expect("model");
    for (name, s) in parts {
        let (rms, cos) = field_misfit(&model, s);
        println!("{label:<7} {name:<6} ({} frames): RMS {rms:.3} px per coordinate, mean cosine {cos:.3}", s.len());
    }
}

/// Fit from `cfg` and return the fitted configuration.
pub fn run(cfg: &TacTipConfig, rest: &[[f64; 2]], taps: &[RealTap]) -> TacTipConfig {
    let fit = samples(taps, &|k| k >= 2);
    let select = samples(taps, &|k| k == 1);
    let score = samples(taps, &|k| k == 0);
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
    out
}

/// `FIT=joint`: all fifteen parameters on every `STRIDE`-th fit-part frame
/// (default 2), then the misfit on all three parts.
pub fn run_joint(cfg: &TacTipConfig, rest: &[[f64; 2]], taps: &[RealTap]) -> TacTipConfig {
    let fit = samples(taps, &|k| k >= 2);
    let select = samples(taps, &|k| k == 1);
    let score = samples(taps, &|k| k == 0);
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
