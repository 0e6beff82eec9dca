//! Fit of the contact mechanics (eqs. S4-S8) to real displacement fields
//! tracked by the vision crate (cache written by the `real_fields`
//! example), and the comparison quoted in docs/sensor-model.md: per-frame
//! figures on low-shear frames and on all frames with label shear, and on
//! AVERAGED fields (all frames binned by r, theta, depth; shear averages
//! out), with a PNG of simulated beside real fields. Not part of the product.
//!
//! Run: cargo run --release -p tactrace-sensor --example real_fields -- /tmp/real_fields.txt
//!      cargo run --release -p tactrace-sensor --example fit_mechanics
//! Env: REAL_FIELDS (cache path), FIT=1 (refit on binned means; else score
//! the defaults; FIT=frames: the old joint per-frame fit of eleven
//! parameters; FIT=slip: the stick-slip law, eq. S7, on the fit part;
//! FIT=joint: 17 calibration, mechanics and slip parameters on the fit
//! part, STRIDE/ROUNDS/ITERS/THREADS), FIGURE=path.png (draw matched
//! cases), DUMP=path (write the simulated fields, with and without shear).
use tactrace_sensor::{EdgeTap, TacTipConfig, TacTipModel};

mod slip;
mod support;
use support::{draw_figure, Bin, FieldSums, Pair, RealTap};
use tactrace_sensor::minimise as nelder_mead;

/// Per-field comparison: mean cosine, median cosine, RMS (px), ratio.
#[derive(Debug, Default, Clone, Copy)]
struct Score {
    cosine: f64,
    median_cosine: f64,
    rms: f64,
    ratio: f64,
    sse: f64,
    mean_real: f64,
    max_real: f64,
}

/// Compare pairs of (simulated, real) fields over the real field's pins.
fn compare(pairs: &[Pair]) -> Score {
    let mut s = Score::default();
    let mut cosines = Vec::new();
    let n = pairs.len().max(1) as f64;
    for (sim, real) in pairs {
        let mut f = FieldSums::default();
        for (e, d) in sim.iter().zip(real) {
            if let Some(d) = d {
                f.add(*d, *e);
            }
        }
        let cos = f.cosine();
        cosines.push(cos);
        s.cosine += cos / n;
        s.sse += f.diff_sq;
        s.rms += (f.diff_sq / f.count.max(1.0)).sqrt() / n;
        s.ratio += f.sim_abs / f.real_abs.max(1e-12) / n;
        s.mean_real += f.real_abs / f.count.max(1.0) / n;
        s.max_real += f.real_max / n;
    }
    cosines.sort_by(f64::total_cmp);
    s.median_cosine = cosines.get(cosines.len() / 2).copied().unwrap_or(0.0);
    s
}

/// Simulated image displacement (px) of one labelled tap.
fn sim_disp(model: &TacTipModel, tap: &EdgeTap) -> Vec<[f64; 2]> {
    let pins = model.edge_tap_pins(tap);
    model
        .rest_pins()
        .iter()
        .zip(&pins)
        .map(|(r, p)| [p[0] - r[0], p[1] - r[1]])
        .collect()
}

fn frame_pairs(model: &TacTipModel, taps: &[&RealTap], shear: bool) -> Vec<Pair> {
    taps.iter()
        .map(|t| {
            let mut tap = t.tap;
            if !shear {
                tap.shear = None;
            }
            (sim_disp(model, &tap), t.disp.clone())
        })
        .collect()
}

/// Bin means: the simulated field at the bin's mean labels (no shear)
/// against the real field averaged over the bin's frames.
fn bin_pairs(model: &TacTipModel, bins: &[Bin]) -> Vec<Pair> {
    bins.iter()
        .map(|b| {
            let tap = EdgeTap {
                r_mm: b.labels[0],
                theta_deg: b.labels[1],
                dz_mm: b.labels[2],
                shear: None,
            };
            (sim_disp(model, &tap), b.mean.clone())
        })
        .collect()
}

const NAMES: [&str; 8] = [
    "angle_offset_deg",
    "edge_offset_mm",
    "tap_depth_mm",
    "flow_core_mm",
    "kernel_width_mm",
    "1/layer_thickness",
    "lift_gain",
    "rim_clamp_mm",
];

fn with_params(base: &TacTipConfig, x: &[f64]) -> Option<TacTipConfig> {
    let ok = x[0].abs() < 60.0
        && x[1].abs() < 8.0
        && (0.5..7.5).contains(&x[2])
        && (0.1..10.0).contains(&x[3])
        && (0.5..15.0).contains(&x[4])
        && (0.002..2.0).contains(&x[5])
        && (0.0..6.0).contains(&x[6])
        && (12.0..1e4).contains(&x[7]);
    let mut c = base.clone();
    c.calibration.angle_offset_deg = x[0];
    c.calibration.edge_offset_mm = x[1];
    c.calibration.tap_depth_mm = x[2];
    c.mechanics.flow_core_mm = x[3];
    c.mechanics.kernel_width_mm = x[4];
    c.mechanics.layer_thickness_mm = 1.0 / x[5];
    c.mechanics.lift_gain = x[6];
    c.mechanics.rim_clamp_mm = x[7];
    ok.then_some(c)
}

fn params_of(c: &TacTipConfig) -> Vec<f64> {
    vec![
        c.calibration.angle_offset_deg,
        c.calibration.edge_offset_mm,
        c.calibration.tap_depth_mm,
        c.mechanics.flow_core_mm,
        c.mechanics.kernel_width_mm,
        1.0 / c.mechanics.layer_thickness_mm,
        c.mechanics.lift_gain,
        c.mechanics.rim_clamp_mm.min(60.0),
    ]
}

fn report(label: &str, s: Score) {
    println!(
        "{label:<44} cosine mean {:.3} median {:.3} | RMS diff {:.2} px | mean|d| sim/real {:.3} | real mean|d| {:.2} px, largest {:.2} px",
        s.cosine, s.median_cosine, s.rms, s.ratio, s.mean_real, s.max_real
    );
}

fn main() {
    let path = std::env::var("REAL_FIELDS").unwrap_or_else(|_| "/tmp/real_fields.txt".into());
    let Some((rest, taps)) = support::load(&path) else {
        eprintln!("no real-field cache at {path}: run the real_fields example first");
        return;
    };
    let bins = support::bins(&taps);
    let low: Vec<&RealTap> = taps.iter().filter(|t| t.low_shear()).collect();
    let all: Vec<&RealTap> = taps.iter().collect();
    let every10: Vec<&RealTap> = taps.iter().step_by(10).collect();
    println!(
        "frames {}, low-shear {}, bins {} (>= {} frames each)",
        taps.len(),
        low.len(),
        bins.len(),
        support::MIN_BIN
    );
    let mut cfg = TacTipConfig::default();
    if std::env::var("SPREAD").is_ok_and(|v| v == "cerruti") {
        cfg.mechanics.slip_spread = tactrace_sensor::SlipSpread::Cerruti;
        if let Some(c) = std::env::var("CORE").ok().and_then(|v| v.parse().ok()) {
            cfg.mechanics.slip_core_mm = c;
        }
    }
    if let Ok(out) = std::env::var("DUMP") {
        dump(&cfg, &rest, &taps, &out);
        return;
    }
    if std::env::var("FIT").is_ok_and(|v| v == "slip") {
        cfg = slip::run(&cfg, &rest, &taps);
    }
    if std::env::var("FIT").is_ok_and(|v| v == "joint") {
        cfg = slip::run_joint(&cfg, &rest, &taps);
    }
    if std::env::var("FIT").is_ok_and(|v| v == "brush") {
        cfg = slip::run_brush(&cfg, &rest, &taps);
    }
    let build = |c: &TacTipConfig| TacTipModel::with_rest_pins(c.clone(), rest.clone()).ok();
    if std::env::var("FIT").is_ok_and(|v| v == "frames") {
        // Joint fit of calibration, mechanics and shear on every tenth
        // frame with its label shear (per-frame misfit, not binned means).
        let objective = |x: &[f64]| -> f64 {
            let Some(mut c) = with_params(&cfg, &x[..8]) else {
                return 1e12;
            };
            if x[8..].iter().any(|v| *v <= 0.01) {
                return 1e12;
            }
            c.mechanics.shear_limit_mm = x[8];
            c.mechanics.shear_limit_deg = x[9];
            c.mechanics.contact_scale_mm = x[10];
            build(&c).map_or(1e12, |m| compare(&frame_pairs(&m, &every10, true)).sse)
        };
        let m = &cfg.mechanics;
        let mut x = params_of(&cfg);
        x.extend([m.shear_limit_mm, m.shear_limit_deg, m.contact_scale_mm]);
        let step = [3.0, 1.0, 0.7, 0.5, 1.5, 0.03, 0.5, -10.0, 0.3, 2.0, 0.2];
        println!("start: sse {:.1}", objective(&x));
        for round in 0..3 {
            let s: Vec<f64> = step.iter().map(|s| s * 0.5f64.powi(round)).collect();
            let (xr, v) = nelder_mead(&objective, &x, &s, 500);
            x = xr;
            println!("round {round}: sse {v:.1}");
        }
        for (n, v) in NAMES
            .iter()
            .chain(&["shear_limit_mm", "shear_limit_deg", "contact_scale_mm"])
            .zip(&x)
        {
            println!("  {n} = {v:.4}");
        }
        cfg = with_params(&cfg, &x[..8]).expect("fit stays in bounds");
        cfg.mechanics.shear_limit_mm = x[8];
        cfg.mechanics.shear_limit_deg = x[9];
        cfg.mechanics.contact_scale_mm = x[10];
    } else if std::env::var("FIT").is_ok_and(|v| !["slip", "joint", "brush"].contains(&v.as_str()))
    {
        let objective = |x: &[f64]| -> f64 {
            let Some(c) = with_params(&cfg, x) else {
                return 1e12;
            };
            build(&c).map_or(1e12, |m| compare(&bin_pairs(&m, &bins)).sse)
        };
        let x0 = params_of(&cfg);
        let step = [3.0, 1.0, 0.7, 0.5, 1.5, 0.03, 0.5, -10.0];
        let (mut x, _) = nelder_mead(&objective, &x0, &step, 400);
        for round in 0..2 {
            let s: Vec<f64> = step.iter().map(|s| s * 0.3).collect();
            let (xr, v) = nelder_mead(&objective, &x, &s, 300);
            x = xr;
            println!("round {round}: sse {v:.1}");
        }
        for (n, v) in NAMES.iter().zip(&x) {
            println!("  {n} = {v:.4}");
        }
        cfg = with_params(&cfg, &x).expect("fit stays in bounds");
        // Shear (eq. S7) on every tenth frame with its label shear.
        let shear_obj = |y: &[f64]| -> f64 {
            if y.iter().any(|v| *v <= 0.01) {
                return 1e12;
            }
            let mut c = cfg.clone();
            c.mechanics.shear_limit_mm = y[0];
            c.mechanics.shear_limit_deg = y[1];
            c.mechanics.contact_scale_mm = y[2];
            build(&c).map_or(1e12, |m| compare(&frame_pairs(&m, &every10, true)).sse)
        };
        let m = &cfg.mechanics;
        let y0 = [m.shear_limit_mm, m.shear_limit_deg, m.contact_scale_mm];
        let (y, _) = nelder_mead(&shear_obj, &y0, &[0.3, 2.0, 0.2], 200);
        cfg.mechanics.shear_limit_mm = y[0];
        cfg.mechanics.shear_limit_deg = y[1];
        cfg.mechanics.contact_scale_mm = y[2];
        println!(
            "  shear_limit_mm = {:.4}\n  shear_limit_deg = {:.4}\n  contact_scale_mm = {:.4}",
            y[0], y[1], y[2]
        );
    }
    let Some(model) = build(&cfg) else {
        eprintln!("model rejected the configuration");
        return;
    };
    report(
        "binned means (all frames), sim at mean labels",
        compare(&bin_pairs(&model, &bins)),
    );
    report(
        "low-shear frames, sim without shear",
        compare(&frame_pairs(&model, &low, false)),
    );
    report(
        "low-shear frames, sim with label shear",
        compare(&frame_pairs(&model, &low, true)),
    );
    report(
        "all frames, sim with label shear",
        compare(&frame_pairs(&model, &all, true)),
    );
    report(
        "all frames, sim without shear",
        compare(&frame_pairs(&model, &all, false)),
    );
    let rings = |pairs: &[Pair]| -> Vec<String> {
        support::ring_profile(model.rest_pins(), pairs)
            .iter()
            .map(|r| format!("{:.2}/{:.2}", r[0], r[1]))
            .collect()
    };
    println!(
        "mean |d| by hex ring 0..6, sim/real, low-shear frames: {}",
        rings(&frame_pairs(&model, &low, false)).join(" ")
    );
    println!(
        "mean |d| by hex ring 0..6, sim/real, all frames with shear: {}",
        rings(&frame_pairs(&model, &all, true)).join(" ")
    );
    if let Ok(out) = std::env::var("FIGURE") {
        let pairs = bin_pairs(&model, &bins);
        match draw_figure(&model, &bins, &pairs, &out) {
            Ok(()) => println!("figure -> {out}"),
            Err(e) => eprintln!("figure failed: {e}"),
        }
    }
}

/// Write the simulated fields (with, then without the label shear) of every
/// cached frame, one line each, for outside analysis.
fn dump(cfg: &TacTipConfig, rest: &[[f64; 2]], taps: &[RealTap], out: &str) {
    let model = TacTipModel::with_rest_pins(cfg.clone(), rest.to_vec()).expect("model");
    let mut text = String::new();
    for t in taps {
        for shear in [true, false] {
            let mut tap = t.tap;
            if !shear {
                tap.shear = None;
            }
            let v: Vec<String> = sim_disp(&model, &tap)
                .iter()
                .flat_map(|p| [format!("{:.4}", p[0]), format!("{:.4}", p[1])])
                .collect();
            text.push_str(&v.join(" "));
            text.push('\n');
        }
    }
    std::fs::write(out, text).expect("write dump");
}
