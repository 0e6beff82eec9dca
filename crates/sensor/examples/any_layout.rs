//! Which pin layout fits a real TacTip, measured: inspect a few frames of
//! the fitting part (frame number N % 5 != 0), estimate the rest layout
//! from its taps (`tactrace_vision::estimate_rest`, for sets without an
//! undeformed frame) or take the pins of an undeformed frame, then fit
//! the simulator's two layouts to those rest pins
//! (`tactrace_sensor::fit_layouts`) and print each one's residual, the
//! choice, the fitted camera and ring phases, and the vision crate's own
//! judgement of the layout (`layout_of`) beside it.
//!
//! `cargo run --release -p tactrace-sensor --example any_layout -- \
//!     --fit DIR [--inspect K] [--rest-frames K] [--reference PNG]`
//!
//! DIR holds frames named `image_N.png` or `frame_N_0.png`; `--inspect`
//! frames (default 20) and at most `--rest-frames` (default 1000) of the
//! fitting part are used, spread evenly. Nothing is written.

use std::path::{Path, PathBuf};
use std::time::Instant;

use tactrace_sensor::{fit_layouts, KindFit, PinLayout, TacTipConfig, TacTipModel};
use tactrace_vision::{
    estimate_rest, inspect, layout_of, Detection, Frame, FrameDetector, RestParams, SightParams,
};

type Error = Box<dyn std::error::Error>;

struct Args {
    fit: PathBuf,
    inspect: usize,
    rest_frames: usize,
    reference: Option<PathBuf>,
}

fn parse() -> Result<Args, Error> {
    let usage = "usage: any_layout --fit DIR [--inspect K] [--rest-frames K] [--reference PNG]";
    let mut args = std::env::args().skip(1);
    let mut a = Args {
        fit: PathBuf::new(),
        inspect: 20,
        rest_frames: 1000,
        reference: None,
    };
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or(usage);
        match arg.as_str() {
            "--fit" => a.fit = value()?.into(),
            "--inspect" => a.inspect = value()?.parse()?,
            "--rest-frames" => a.rest_frames = value()?.parse()?,
            "--reference" => a.reference = Some(value()?.into()),
            _ => return Err(usage.into()),
        }
    }
    if a.fit.as_os_str().is_empty() {
        return Err(usage.into());
    }
    Ok(a)
}

/// The fitting part's frames (N % 5 != 0), sorted by N.
fn fitting_part(dir: &Path) -> Result<Vec<PathBuf>, Error> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        let Some(rest) = stem
            .strip_prefix("image_")
            .or_else(|| stem.strip_prefix("frame_"))
        else {
            continue;
        };
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        if let Ok(n) = digits.parse::<u32>() {
            if !n.is_multiple_of(5) {
                out.push((n, path));
            }
        }
    }
    out.sort();
    Ok(out.into_iter().map(|(_, p)| p).collect())
}

/// Every `len / k`-th item, at most `k`.
fn spread(items: &[PathBuf], k: usize) -> Vec<PathBuf> {
    let step = items.len().div_ceil(k.max(1)).max(1);
    items.iter().step_by(step).cloned().collect()
}

fn load(path: &Path) -> Result<image::DynamicImage, Error> {
    Ok(image::open(path)?)
}

/// The detector proposed by inspecting `k` frames, and the pin count.
fn sight(fit: &[PathBuf], k: usize) -> Result<(FrameDetector, usize), Error> {
    let frames: Vec<Frame> = spread(fit, k)
        .iter()
        .map(|p| load(p).map(|i| i.to_luma8()))
        .collect::<Result<_, _>>()?;
    let found = inspect(&frames, None)?;
    println!(
        "inspection of {} frames: {} pins, {:?} (lattice order {:.2}, polar {:.2}), spacing {:.2} px",
        frames.len(),
        found.pins,
        found.layout.kind,
        found.layout.lattice_order,
        found.layout.polar_order,
        found.spacing
    );
    let (w, h) = (frames[0].width(), frames[0].height());
    let params = SightParams {
        preprocess: found.preprocess,
        detect: found.detect,
    };
    Ok((params.check(w, h)?, found.pins))
}

/// Rest pins: the undeformed frame's, or estimated from the taps.
fn rest_pins(a: &Args, fit: &[PathBuf]) -> Result<Vec<[f64; 2]>, Error> {
    let (detector, pins) = sight(fit, a.inspect)?;
    if let Some(path) = &a.reference {
        let d = detector.detect(&load(path)?)?;
        println!("rest pins: {} pins of {}", d.points.len(), path.display());
        return Ok(d.points.iter().map(|k| [k.x, k.y]).collect());
    }
    let detections: Vec<Detection> = spread(fit, a.rest_frames)
        .iter()
        .map(|p| detector.detect(&load(p)?).map_err(Into::into))
        .collect::<Result<_, Error>>()?;
    let est = estimate_rest(&detections, pins, &RestParams::default())?;
    println!(
        "rest pins: estimated from {} taps, {} pins, residual {:.3} px (kept {} of {} usable)",
        detections.len(),
        est.pins.len(),
        est.residual,
        est.frames_kept,
        est.frames_usable
    );
    Ok(est.pins)
}

fn describe(kind: PinLayout, fit: &KindFit) {
    let c = &fit.config.camera;
    println!(
        "  {:<17} residual {:.3} px, every pin paired: {}, kept as given: {}; centre ({:.2}, {:.2}) \
         px, focal {:.2} px, height {:.2} mm, rotation {:.2} deg, mirror {}, spacing {:.3} mm",
        kind.describe(),
        fit.residual_px,
        fit.matched,
        fit.kept,
        c.centre_px[0],
        c.centre_px[1],
        c.focal_px,
        c.height_mm,
        c.rotation_deg,
        c.mirror,
        fit.config.geometry.pin_spacing_mm,
    );
    let phases = &fit.config.geometry.ring_phase_deg;
    if !phases.is_empty() {
        let text: Vec<String> = phases.iter().map(|p| format!("{p:.2}")).collect();
        println!("    ring phases, deg: {}", text.join(", "));
    }
}

fn main() -> Result<(), Error> {
    let a = parse()?;
    let fit = fitting_part(&a.fit)?;
    if fit.is_empty() {
        return Err(format!("no numbered frames in {}", a.fit.display()).into());
    }
    let frame = load(&fit[0])?;
    let pins = rest_pins(&a, &fit)?;
    let seen = layout_of(&pins);
    println!(
        "vision's judgement of the rest pins: {:?} (lattice order {:.2}, polar {:.2}), rings {:?}",
        seen.kind, seen.lattice_order, seen.polar_order, seen.rings
    );
    let start = Instant::now();
    let got = fit_layouts(
        &TacTipConfig::default(),
        &pins,
        (frame.width(), frame.height()),
    )?;
    println!(
        "layout fit ({:.2} s): {} chosen",
        start.elapsed().as_secs_f64(),
        got.layout().describe()
    );
    for kind in [PinLayout::Hex, PinLayout::Rings] {
        describe(kind, got.of(kind));
    }
    let model = TacTipModel::with_rest_pins(got.config.clone(), pins.clone())?;
    let rest = TacTipModel::new(got.config)?;
    let d: Vec<f64> = model
        .rest_pins()
        .iter()
        .map(|p| {
            rest.rest_pins()
                .iter()
                .map(|q| (p[0] - q[0]).hypot(p[1] - q[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    println!(
        "the simulator takes the {} pins as its rest layout; nearest model pin: mean {:.3} px, max {:.3} px",
        d.len(),
        d.iter().sum::<f64>() / d.len() as f64,
        d.iter().copied().fold(0.0, f64::max)
    );
    Ok(())
}
