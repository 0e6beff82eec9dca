//! Calibration of the simulated TacTip against the real 127-pin edge frames
//! (shared/data/tactip127-edge2d). Not part of the product: a throwaway
//! pin detector, a rest-layout fit of the camera (eqs. S1-S3, quoted in
//! docs/sensor-model.md), and an early mechanics fit now superseded by
//! `examples/fit_mechanics` (robust tracking, binned fields).
//!
//! Run: cargo run --release -p tactrace-sensor --example calibrate
use std::path::{Path, PathBuf};
use tactrace_sensor::{read_frame, EdgeTap, Frame, Shear, TacTipConfig, TacTipModel};

/// The Nelder-Mead minimiser shared with the mechanics fit.
#[allow(dead_code)]
#[path = "fit_mechanics/support.rs"]
mod support;
use support::FieldSums;
use tactrace_sensor::minimise as nelder_mead;

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tactip127-edge2d")
}

/// Centroids of 4-connected white components with area in [lo, hi] px.
fn blobs(img: &Frame, lo: usize, hi: usize) -> Vec<[f64; 2]> {
    let (w, h) = img.dimensions();
    let (w, h) = (w as i64, h as i64);
    let on = |x: i64, y: i64| img.get_pixel(x as u32, y as u32)[0] >= 128;
    let mut seen = vec![false; (w * h) as usize];
    let mut out = Vec::new();
    for y0 in 0..h {
        for x0 in 0..w {
            if seen[(y0 * w + x0) as usize] || !on(x0, y0) {
                continue;
            }
            seen[(y0 * w + x0) as usize] = true;
            let mut stack = vec![(x0, y0)];
            let (mut sx, mut sy, mut n) = (0.0, 0.0, 0usize);
            while let Some((x, y)) = stack.pop() {
                sx += x as f64;
                sy += y as f64;
                n += 1;
                for (nx, ny) in [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)] {
                    if nx < 0 || ny < 0 || nx >= w || ny >= h {
                        continue;
                    }
                    let j = (ny * w + nx) as usize;
                    if !seen[j] && on(nx, ny) {
                        seen[j] = true;
                        stack.push((nx, ny));
                    }
                }
            }
            if (lo..=hi).contains(&n) {
                out.push([sx / n as f64, sy / n as f64]);
            }
        }
    }
    out
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Greedy one-to-one nearest pairs between predicted and detected points.
fn greedy_match(pred: &[[f64; 2]], det: &[[f64; 2]], limit: &[f64]) -> Vec<Option<usize>> {
    let mut pairs = Vec::new();
    for (i, p) in pred.iter().enumerate() {
        for (k, q) in det.iter().enumerate() {
            let d = dist(*p, *q);
            if d < limit[i] {
                pairs.push((d, i, k));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut of = vec![None; pred.len()];
    let mut taken = vec![false; det.len()];
    for (_, i, k) in pairs {
        if of[i].is_none() && !taken[k] {
            of[i] = Some(k);
            taken[k] = true;
        }
    }
    of
}

/// Track rest pins into a deformed frame: match, then re-predict each pin
/// from its matched neighbours' mean displacement, three times.
fn track(rest: &[[f64; 2]], det: &[[f64; 2]], spacing: &[f64]) -> Vec<Option<[f64; 2]>> {
    let mut disp: Vec<Option<[f64; 2]>> = vec![None; rest.len()];
    for _ in 0..4 {
        let pred: Vec<[f64; 2]> = (0..rest.len())
            .map(|i| predict(rest, &disp, spacing, i))
            .collect();
        let limit: Vec<f64> = spacing.iter().map(|s| 0.5 * s).collect();
        let of = greedy_match(&pred, det, &limit);
        disp = of
            .iter()
            .enumerate()
            .map(|(i, k)| k.map(|k| [det[k][0] - rest[i][0], det[k][1] - rest[i][1]]))
            .collect();
    }
    disp
}

fn predict(rest: &[[f64; 2]], disp: &[Option<[f64; 2]>], spacing: &[f64], i: usize) -> [f64; 2] {
    if let Some(d) = disp[i] {
        return [rest[i][0] + d[0], rest[i][1] + d[1]];
    }
    let (mut s, mut n) = ([0.0; 2], 0.0);
    for (j, r) in rest.iter().enumerate() {
        if let (true, Some(d)) = (dist(*r, rest[i]) < 1.6 * spacing[i], disp[j]) {
            s[0] += d[0];
            s[1] += d[1];
            n += 1.0;
        }
    }
    if n > 0.0 {
        [rest[i][0] + s[0] / n, rest[i][1] + s[1] / n]
    } else {
        rest[i]
    }
}

fn local_spacing(rest: &[[f64; 2]]) -> Vec<f64> {
    rest.iter()
        .enumerate()
        .map(|(i, a)| {
            rest.iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, b)| dist(*a, *b))
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

fn camera_cfg(base: &TacTipConfig, x: &[f64]) -> TacTipConfig {
    let mut cfg = base.clone();
    cfg.camera.centre_px = [x[0], x[1]];
    cfg.camera.focal_px = x[2];
    cfg.camera.height_mm = x[3];
    cfg.geometry.pin_spacing_mm = x[4];
    cfg.camera.rotation_deg = x[5];
    cfg
}

/// RMS distance (px) from each real rest pin to its nearest model rest pin.
fn rest_misfit(cfg: &TacTipConfig, real: &[[f64; 2]]) -> f64 {
    let Ok(model) = TacTipModel::new(cfg.clone()) else {
        return 1e9;
    };
    let model_rest = model.rest_pins();
    let sum: f64 = real
        .iter()
        .map(|p| {
            model_rest
                .iter()
                .map(|q| dist(*p, *q).powi(2))
                .fold(f64::INFINITY, f64::min)
        })
        .sum();
    (sum / real.len() as f64).sqrt()
}

struct RealTap {
    name: String,
    tap: EdgeTap,
    disp: Vec<Option<[f64; 2]>>,
}

fn parse_targets(text: &str, max_shear: f64) -> Vec<(String, EdgeTap)> {
    let mut rows = Vec::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |k: usize| {
            f.get(k)
                .and_then(|s| s.parse::<f64>().ok())
                .unwrap_or(f64::NAN)
        };
        let shear = Shear {
            dx_mm: num(10),
            dy_mm: num(11),
            drz_deg: num(15),
        };
        if shear.dx_mm.abs() > max_shear
            || shear.dy_mm.abs() > max_shear
            || shear.drz_deg.abs() > 2.0 * max_shear
        {
            continue;
        }
        let tap = EdgeTap {
            r_mm: num(5),
            theta_deg: num(9),
            dz_mm: num(6),
            shear: Some(shear),
        };
        rows.push((f[0].to_string(), tap));
    }
    rows
}

#[derive(Default, Debug)]
struct Score {
    sq: f64,
    rms: f64,
    cosine: f64,
    ratio: f64,
    mean_real: f64,
    max_real: f64,
}

/// Compare real and simulated displacement fields over tracked pins.
fn score(model: &TacTipModel, taps: &[RealTap], use_shear: bool) -> Score {
    let rest = model.rest_pins();
    let mut s = Score::default();
    let n = taps.len() as f64;
    for t in taps {
        let mut tap = t.tap;
        if !use_shear {
            tap.shear = None;
        }
        let sim = model.edge_tap_pins(&tap);
        let mut f = FieldSums::default();
        for (i, d) in t.disp.iter().enumerate() {
            if let Some(d) = d {
                f.add(*d, [sim[i][0] - rest[i][0], sim[i][1] - rest[i][1]]);
            }
        }
        s.sq += f.diff_sq / n;
        s.rms += (f.diff_sq / f.count).sqrt() / n;
        s.cosine += f.cosine() / n;
        s.ratio += f.sim_abs / f.real_abs.max(1e-12) / n;
        s.mean_real += f.real_abs / f.count / n;
        s.max_real += f.real_max / n;
    }
    s
}

fn mech_cfg(base: &TacTipConfig, x: &[f64]) -> TacTipConfig {
    let mut cfg = base.clone();
    cfg.mechanics.kernel_width_mm = x[0];
    cfg.mechanics.layer_thickness_mm = 1.0 / x[1].max(1e-3);
    cfg.mechanics.lift_gain = x[5];
    cfg.mechanics.flow_core_mm = x[6];
    cfg.mechanics.shear_limit_mm = x[7];
    cfg.mechanics.shear_limit_deg = x[8];
    cfg.mechanics.contact_scale_mm = x[9];
    cfg.calibration.tap_depth_mm = x[2];
    cfg.calibration.angle_offset_deg = x[3];
    cfg.calibration.edge_offset_mm = x[4];
    cfg
}

fn main() {
    let dir = data_dir();
    let Ok(init) = read_frame(&dir.join("frames/init_0.png")) else {
        eprintln!(
            "real data not found under {}; nothing to calibrate",
            dir.display()
        );
        return;
    };
    let centre = [127.0, 129.0];
    let mut real_rest: Vec<[f64; 2]> = blobs(&init, 8, 90)
        .into_iter()
        .filter(|p| dist(*p, centre) < 112.0)
        .collect();
    real_rest.sort_by(|a, b| dist(*a, centre).total_cmp(&dist(*b, centre)));
    real_rest.truncate(127);
    println!("rest pins detected: {}", real_rest.len());

    let base = TacTipConfig::default();
    let x0 = [127.0, 128.65, 59.0, 15.0, 2.8, -5.0];
    let step = [1.0, 1.0, 5.0, 1.0, 0.2, 2.0];
    let (xc, fc) = nelder_mead(
        &|x| rest_misfit(&camera_cfg(&base, x), &real_rest),
        &x0,
        &step,
        600,
    );
    println!("camera fit: centre=({:.2},{:.2}) focal={:.2} height={:.3} spacing={:.4} rot={:.2}  rest RMS {fc:.3} px", xc[0], xc[1], xc[2], xc[3], xc[4], xc[5]);
    let cam = camera_cfg(&base, &xc);

    let text = std::fs::read_to_string(dir.join("targets.csv")).unwrap_or_default();
    let max_shear: f64 = std::env::var("MAX_SHEAR")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1.0);
    let spacing = local_spacing(&real_rest);
    let mut taps = Vec::new();
    let stride: usize = std::env::var("STRIDE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let offset: usize = std::env::var("OFFSET")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    for (name, tap) in parse_targets(&text, max_shear)
        .into_iter()
        .skip(offset)
        .step_by(stride)
    {
        let Ok(img) = read_frame(&dir.join("frames").join(&name)) else {
            continue;
        };
        let det: Vec<[f64; 2]> = blobs(&img, 6, 120)
            .into_iter()
            .filter(|p| dist(*p, centre) < 118.0)
            .collect();
        let disp = track(&real_rest, &det, &spacing);
        taps.push(RealTap { name, tap, disp });
    }
    let tracked: usize = taps.iter().map(|t| t.disp.iter().flatten().count()).sum();
    println!(
        "frames: {}, tracked pins per frame: {:.1}",
        taps.len(),
        tracked as f64 / taps.len().max(1) as f64
    );
    if let Ok(out) = std::env::var("DUMP") {
        let mut text = String::new();
        for t in &taps {
            let nums: Vec<String> = t
                .disp
                .iter()
                .map(|d| {
                    d.map_or("nan nan".to_string(), |d| {
                        format!("{:.3} {:.3}", d[0], d[1])
                    })
                })
                .collect();
            text.push_str(&format!("{} {}\n", t.name, nums.join(" ")));
        }
        let _ = std::fs::write(out, text);
        return;
    }
    if std::env::var("ANALYZE").is_ok() {
        for t in &taps {
            analyze(&real_rest, t);
        }
        return;
    }
    if let Ok(names) = std::env::var("VIZ") {
        let x: Vec<f64> = std::env::var("X")
            .unwrap_or_default()
            .split(',')
            .filter_map(|v| v.parse().ok())
            .collect();
        let mut cfg = cam.clone();
        cfg.camera.mirror = true;
        cfg.camera.rotation_deg = xc[5] + 180.0;
        cfg.calibration.object_side = -1.0;
        cfg.calibration.shear_sign = 1.0;
        let model = (x.len() == 10)
            .then(|| TacTipModel::with_rest_pins(mech_cfg(&cfg, &x), real_rest.clone()).ok())
            .flatten();
        for t in taps
            .iter()
            .filter(|t| names.split(',').any(|n| n == t.name))
        {
            let sim = model.as_ref().map(|m| m.edge_tap_pins(&t.tap));
            viz(
                &real_rest,
                t,
                sim.as_deref(),
                &format!("/tmp/viz_{}", t.name),
            );
        }
        return;
    }

    let fit = |cfg: &TacTipConfig, x: &[f64]| -> f64 {
        let bad = x[0] < 0.5 || x[0] > 15.0 || x[1] < 0.0 || x[2] < 0.2 || x[2] > 7.5;
        let bad = bad
            || x[3].abs() > 45.0
            || x[4].abs() > 2.0
            || !(0.0..=3.0).contains(&x[5])
            || !(0.3..=8.0).contains(&x[6]);
        if bad || x[7] < 0.02 || x[8] < 0.1 || x[9] < 0.01 {
            return 1e12;
        }
        match TacTipModel::with_rest_pins(mech_cfg(cfg, x), real_rest.clone()) {
            Ok(m) => score(&m, &taps, true).sq,
            Err(_) => 1e12,
        }
    };
    let x0 = [4.0, 0.1, 3.0, -22.0, 0.0, 1.0, 2.0, 0.5, 3.0, 0.3];
    let steps = [1.5, 0.1, 1.0, 3.0, 0.3, 0.4, 1.0, 0.3, 2.0, 0.2];
    let mut best: Option<(f64, TacTipConfig, Vec<f64>)> = None;
    for (turn, sign) in [(0.0, -1.0), (180.0, 1.0)] {
        for side in [1.0, -1.0] {
            let mut cfg = cam.clone();
            cfg.camera.mirror = true;
            cfg.camera.rotation_deg = xc[5] + turn;
            cfg.calibration.object_side = side;
            cfg.calibration.shear_sign = sign;
            cfg.calibration.depth_per_offset = -1.0;
            let (x, v) = nelder_mead(&|x| fit(&cfg, x), &x0, &steps, 150);
            println!("turn={turn} side={side}: misfit {v:.1} x={x:.3?}");
            if best.as_ref().is_none_or(|b| v < b.0) {
                best = Some((v, cfg, x));
            }
        }
    }
    let Some((_, cfg, x)) = best else { return };
    let (x, v) = nelder_mead(&|x| fit(&cfg, x), &x, &steps.map(|s| s * 0.3), 600);
    let cfg = mech_cfg(&cfg, &x);
    println!(
        "best: misfit {v:.2} rot={:.2} side={} x={x:.4?}",
        cfg.camera.rotation_deg, cfg.calibration.object_side
    );
    if let Ok(model) = TacTipModel::with_rest_pins(cfg.clone(), real_rest.clone()) {
        println!(
            "fit set, no shear in sim: {:?}",
            score(&model, &taps, false)
        );
        println!("fit set, label shear:     {:?}", score(&model, &taps, true));
    }
    if let Ok(model) = TacTipModel::new(cfg.clone()) {
        let own: Vec<[f64; 2]> = model.rest_pins().to_vec();
        if let Ok(m2) = TacTipModel::with_rest_pins(cfg.clone(), own) {
            let _ = m2;
        }
    }
    println!("{}", toml_like(&cfg));
}

fn toml_like(cfg: &TacTipConfig) -> String {
    format!("{cfg:#?}")
}

/// Debug picture: rest pins (red) and displacement x3 (green line).
fn viz(rest: &[[f64; 2]], t: &RealTap, sim: Option<&[[f64; 2]]>, path: &str) {
    let mut img = image::RgbImage::new(512, 512);
    for (i, r) in rest.iter().enumerate() {
        if let Some(sim) = sim {
            let d = [sim[i][0] - r[0], sim[i][1] - r[1]];
            for k in 0..=60 {
                let f = 3.0 * k as f64 / 60.0;
                let (x, y) = (2.0 * (r[0] + f * d[0]) + 1.0, 2.0 * (r[1] + f * d[1]) + 1.0);
                if x >= 0.0 && y >= 0.0 && x < 512.0 && y < 512.0 {
                    img.put_pixel(x as u32, y as u32, image::Rgb([80, 140, 255]));
                }
            }
        }
        if let Some(d) = t.disp[i] {
            for k in 0..=60 {
                let f = 3.0 * k as f64 / 60.0;
                let (x, y) = (2.0 * (r[0] + f * d[0]), 2.0 * (r[1] + f * d[1]));
                if x >= 0.0 && y >= 0.0 && x < 512.0 && y < 512.0 {
                    img.put_pixel(x as u32, y as u32, image::Rgb([0, 255, 0]));
                }
            }
        }
        let (x, y) = ((2.0 * r[0]) as u32, (2.0 * r[1]) as u32);
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            img.put_pixel(
                (x + dx).min(511),
                (y + dy).min(511),
                image::Rgb([255, 0, 0]),
            );
        }
    }
    println!(
        "{} r={:.2} th={:.1} dz={:.2} -> {path}",
        t.name, t.tap.r_mm, t.tap.theta_deg, t.tap.dz_mm
    );
    let _ = img.save(path);
}

/// Net displacement direction and magnitude-weighted centre of one field.
fn analyze(rest: &[[f64; 2]], t: &RealTap) {
    let c = rest[0];
    let (mut net, mut wc, mut wsum, mut mean, mut n) = ([0.0; 2], [0.0; 2], 0.0, 0.0, 0.0);
    let mut ring = [0.0f64; 7];
    let mut ring_n = [0.0f64; 7];
    for (i, d) in t.disp.iter().enumerate() {
        let Some(d) = d else { continue };
        let m = d[0].hypot(d[1]);
        net[0] += d[0];
        net[1] += d[1];
        wc[0] += m * (rest[i][0] - c[0]);
        wc[1] += m * (rest[i][1] - c[1]);
        wsum += m;
        mean += m;
        n += 1.0;
        let k = ring_of(i);
        ring[k] += m;
        ring_n[k] += 1.0;
    }
    let rings: Vec<String> = (0..7)
        .map(|k| format!("{:.1}", ring[k] / ring_n[k].max(1.0)))
        .collect();
    println!(
        "{:>16} r={:6.2} th={:6.1} dz={:5.2} | net ang {:7.1} |net|/n {:5.2} | wc ang {:7.1} wc r {:5.1} | mean {:5.2} | rings {}",
        t.name, t.tap.r_mm, t.tap.theta_deg, t.tap.dz_mm,
        net[1].atan2(net[0]).to_degrees(), net[0].hypot(net[1]) / n,
        wc[1].atan2(wc[0]).to_degrees(), wc[0].hypot(wc[1]) / wsum, mean / n, rings.join(" ")
    );
}

/// Ring index of pin i when pins are sorted by distance from the centre.
fn ring_of(i: usize) -> usize {
    (0..7).find(|&k| i < 1 + 3 * k * (k + 1)).unwrap_or(6)
}
