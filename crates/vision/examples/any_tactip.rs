//! Any TacTip from its frames alone, measured: inspect a few frames of the
//! fitting part, estimate the rest layout from the fitting part's taps,
//! then read every frame of the sets given and count the frames fully
//! tracked (no pin filled in), split by the frame number N: the fitting
//! part is N % 5 != 0 of `--fit`, everything else is held out.
//!
//! `cargo run --release -p tactrace-vision --example any_tactip -- \
//!     --fit DIR [--inspect K] [--rest-frames K] [--reference PNG] [--params TOML] \
//!     [--pins N] [--undeformed PNG] SET_DIR...`
//!
//! Each DIR holds frames named with a number (`image_N.png`,
//! `frame_N_0.png`); `--inspect` frames (default 20) and at most
//! `--rest-frames` (default all) of the fitting part are used, spread evenly.
//! `--reference PNG` takes the rest pins from an undeformed frame instead
//! of estimating them (`--undeformed PNG` only compares the estimate with
//! its pins); `--params` reads the sight parameters
//! (`[preprocess]`, `[detect]`) from a file instead of inspecting; `--pins`
//! overrides the pin count the rest estimate starts from.
//! Prints the proposal, the rest estimate and, per set and part, the share
//! of frames fully tracked, the pins split from clusters and filled in,
//! frames with a turned-over neighbour triangle, and the thread CPU time
//! per frame of reading (preprocessing, detection, ordering; not decoding;
//! each hundred frames timed together, shared out evenly between parts).

use std::path::{Path, PathBuf};
use std::time::Instant;

use tactrace_vision::{
    estimate_rest, inspect, layout_of, Detection, Frame, FrameDetector, PinReader, RestParams,
    SightParams,
};

struct Args {
    fit: PathBuf,
    inspect: usize,
    rest_frames: usize,
    reference: Option<PathBuf>,
    params: Option<PathBuf>,
    pins: Option<usize>,
    undeformed: Option<PathBuf>,
    sets: Vec<PathBuf>,
}

fn parse() -> Result<Args, Box<dyn std::error::Error>> {
    let usage = "usage: any_tactip --fit DIR [--inspect K] [--rest-frames K] [--reference PNG] \
                 [--params TOML] [--pins N] [--undeformed PNG] SET_DIR...";
    let mut args = std::env::args().skip(1);
    let mut a = Args {
        fit: PathBuf::new(),
        inspect: 20,
        rest_frames: usize::MAX,
        reference: None,
        params: None,
        pins: None,
        undeformed: None,
        sets: Vec::new(),
    };
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or(usage);
        match arg.as_str() {
            "--fit" => a.fit = value()?.into(),
            "--inspect" => a.inspect = value()?.parse()?,
            "--rest-frames" => a.rest_frames = value()?.parse()?,
            "--reference" => a.reference = Some(value()?.into()),
            "--params" => a.params = Some(value()?.into()),
            "--pins" => a.pins = Some(value()?.parse()?),
            "--undeformed" => a.undeformed = Some(value()?.into()),
            _ => a.sets.push(arg.into()),
        }
    }
    if a.fit.as_os_str().is_empty() {
        return Err(usage.into());
    }
    Ok(a)
}

/// Frames of a folder with the number in their name, sorted by it (a
/// name without a number, such as `init_0.png`, counts as its digits).
fn numbered(dir: &Path) -> Result<Vec<(u32, PathBuf)>, Box<dyn std::error::Error>> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        if !stem.starts_with("image_") && !stem.starts_with("frame_") {
            continue;
        }
        let digits: String = stem
            .chars()
            .skip_while(|c| !c.is_ascii_digit())
            .take_while(|c| c.is_ascii_digit())
            .collect();
        if let Ok(n) = digits.parse() {
            out.push((n, path));
        }
    }
    out.sort();
    Ok(out)
}

fn load(path: &Path) -> Result<image::DynamicImage, Box<dyn std::error::Error>> {
    Ok(image::open(path)?)
}

/// Every `len / k`-th item, at most `k`.
fn spread<T: Clone>(items: &[T], k: usize) -> Vec<T> {
    let step = items.len().div_ceil(k.max(1)).max(1);
    items.iter().step_by(step).cloned().collect()
}

fn sight(a: &Args, fit: &[(u32, PathBuf)]) -> Result<SightParams, Box<dyn std::error::Error>> {
    if let Some(path) = &a.params {
        return Ok(toml::from_str(&std::fs::read_to_string(path)?)?);
    }
    let chosen = spread(fit, a.inspect);
    let frames: Vec<Frame> = chosen
        .iter()
        .map(|(_, p)| load(p).map(|i| i.to_luma8()))
        .collect::<Result<_, _>>()?;
    let start = Instant::now();
    let found = inspect(&frames, None)?;
    println!(
        "inspect {} frames ({:.0} ms): {} pins, layout {:?} (lattice order {:.2}, polar {:.2}), \
         spacing {:.2} px, pin {:.0} px, rim {:?}",
        frames.len(),
        start.elapsed().as_secs_f64() * 1e3,
        found.pins,
        found.layout.kind,
        found.layout.lattice_order,
        found.layout.polar_order,
        found.spacing,
        found.pin_pixels,
        found.rim.map(|r| (r.centre, r.radius)),
    );
    if !found.layout.rings.is_empty() {
        println!("  rings {:?}", found.layout.rings);
    }
    let params = SightParams {
        preprocess: found.preprocess,
        detect: found.detect,
    };
    println!("{}", toml::to_string(&params)?);
    Ok(params)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a = parse()?;
    let fit: Vec<(u32, PathBuf)> = numbered(&a.fit)?
        .into_iter()
        .filter(|(n, _)| n % 5 != 0)
        .collect();
    let params = sight(&a, &fit)?;
    let size = load(&fit[0].1)?;
    let frames: FrameDetector = params.check(size.width(), size.height())?;
    let rest = match &a.reference {
        Some(path) => {
            let d = frames.detect(&load(path)?)?;
            println!("reference {}: {} pins", path.display(), d.points.len());
            d.points.iter().map(|k| [k.x, k.y]).collect()
        }
        None => {
            let chosen = spread(&fit, a.rest_frames);
            let detections: Vec<Detection> = chosen
                .iter()
                .map(|(_, p)| frames.detect(&load(p)?).map_err(Into::into))
                .collect::<Result<_, Box<dyn std::error::Error>>>()?;
            let pins = match (a.pins, &a.params) {
                (Some(pins), _) => pins,
                (None, Some(_)) => mode(detections.iter().map(|d| d.points.len())),
                (None, None) => inspect_pins(&a, &fit)?,
            };
            let start = Instant::now();
            let est = estimate_rest(&detections, pins, &RestParams::default())?;
            println!(
                "rest from {} frames ({:.1} s): {} pins, residual {:.3} px, kept displacement \
                 {:.3} px, kept {} of {} usable, {} rounds, last shift {:.4} px",
                detections.len(),
                start.elapsed().as_secs_f64(),
                est.pins.len(),
                est.residual,
                est.kept_displacement,
                est.frames_kept,
                est.frames_usable,
                est.rounds,
                est.last_shift
            );
            let layout = layout_of(&est.pins);
            println!(
                "  rest layout {:?} (lattice order {:.2}, polar {:.2}), rings {:?}",
                layout.kind, layout.lattice_order, layout.polar_order, layout.rings
            );
            if !est.dropped.is_empty() {
                println!("  dropped as no pins: {:?}", est.dropped);
            }
            if let Some(path) = &a.undeformed {
                compare(&frames, path, &est.pins)?;
            }
            est.pins
        }
    };
    let reader = PinReader::new(frames, rest)?;
    for set in &a.sets {
        report(&reader, set)?;
    }
    Ok(())
}

/// How far the estimate lies from the pins of an undeformed frame.
fn compare(
    frames: &FrameDetector,
    path: &Path,
    rest: &[[f64; 2]],
) -> Result<(), Box<dyn std::error::Error>> {
    let seen = frames.detect(&load(path)?)?;
    let d: Vec<f64> = seen
        .points
        .iter()
        .map(|k| {
            rest.iter()
                .map(|e| (e[0] - k.x).hypot(e[1] - k.y))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    println!(
        "  against {} ({} pins): nearest estimated pin mean {:.2} px, max {:.2} px",
        path.display(),
        d.len(),
        d.iter().sum::<f64>() / d.len().max(1) as f64,
        d.iter().copied().fold(0.0, f64::max)
    );
    Ok(())
}

fn inspect_pins(a: &Args, fit: &[(u32, PathBuf)]) -> Result<usize, Box<dyn std::error::Error>> {
    let frames: Vec<Frame> = spread(fit, a.inspect)
        .iter()
        .map(|(_, p)| load(p).map(|i| i.to_luma8()))
        .collect::<Result<_, _>>()?;
    Ok(inspect(&frames, None)?.pins)
}

fn mode(values: impl Iterator<Item = usize>) -> usize {
    let mut counts = std::collections::BTreeMap::new();
    for v in values {
        *counts.entry(v).or_insert(0usize) += 1;
    }
    counts
        .into_iter()
        .max_by_key(|&(_, c)| c)
        .map_or(0, |(v, _)| v)
}

/// Seconds this thread has run on a CPU (Linux; 0 elsewhere), so that
/// time spent waiting for a shared core is not counted.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}

/// Adds one frame's reading to `part`.
fn tally(
    part: &mut Tally,
    reader: &PinReader,
    path: &Path,
    result: Result<tactrace_vision::Reading, tactrace_vision::VisionError>,
) {
    part.frames += 1;
    match result {
        Ok(r) => {
            if !r.counts.fully_tracked() && std::env::var_os("ANY_TACTIP_VERBOSE").is_some() {
                let filled: Vec<String> = r
                    .tracked
                    .pins
                    .iter()
                    .zip(reader.tracker().reference())
                    .zip(&r.tracked.matched)
                    .enumerate()
                    .filter(|(_, (_, m))| !**m)
                    .map(|(i, ((p, q), _))| {
                        format!(
                            "pin {i} at ({:.1}, {:.1}) rest ({:.1}, {:.1})",
                            p[0], p[1], q[0], q[1]
                        )
                    })
                    .collect();
                eprintln!("{}: {}", path.display(), filled.join("; "));
            }
            part.full += usize::from(r.counts.fully_tracked());
            part.split += r.counts.split;
            part.filled += r.counts.filled;
            part.turned += usize::from(reader.tracker().turned_triangles(&r.tracked) > 0);
        }
        Err(_) => part.failed += 1,
    }
}

/// Tallies of one part of a set.
#[derive(Default)]
struct Tally {
    frames: usize,
    full: usize,
    failed: usize,
    split: usize,
    filled: usize,
    turned: usize,
    seconds: f64,
}

fn report(reader: &PinReader, set: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let mut parts = [Tally::default(), Tally::default()];
    let frames = numbered(set)?;
    // Decoded a hundred at a time, each hundred read in one timed pass
    // (the kernel's CPU clock is too coarse for one frame).
    for chunk in frames.chunks(100) {
        let images: Vec<image::DynamicImage> = chunk
            .iter()
            .map(|(_, p)| load(p))
            .collect::<Result<_, _>>()?;
        let start = cpu_seconds();
        let results: Vec<_> = images.iter().map(|i| reader.read(i)).collect();
        let seconds = cpu_seconds() - start;
        for ((n, path), result) in chunk.iter().zip(results) {
            let part = &mut parts[usize::from(n % 5 == 0)];
            part.seconds += seconds / chunk.len() as f64;
            tally(part, reader, path, result);
        }
    }
    for (name, t) in ["N % 5 != 0", "N % 5 == 0"].iter().zip(&parts) {
        if t.frames == 0 {
            continue;
        }
        println!(
            "{} [{name}]: {} frames, fully tracked {} ({:.2} %), failed {}, pins split {}, \
             filled {}, frames with a turned triangle {}, {:.0} us CPU/frame",
            set.display(),
            t.frames,
            t.full,
            100.0 * t.full as f64 / t.frames as f64,
            t.failed,
            t.split,
            t.filled,
            t.turned,
            1e6 * t.seconds / t.frames as f64
        );
    }
    Ok(())
}
