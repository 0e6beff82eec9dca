//! Timing and checking of the pin ordering on any TacTip's frames (issue
//! 21, item 6): the sensor proposed from 20 frames of the fitting part, the
//! rest layout estimated from `--rest-frames` of its taps (as
//! `tests/speed.rs` does), then every frame of `--frames` detected once
//! and ordered `--reps` times: the mean thread CPU time a frame (the time a
//! loaded machine makes the thread wait is not counted) and the median and
//! p95 of each frame's best wall time. With `--compare`,
//! each frame is also ordered with the exact (uncut) smooth field and the
//! two are compared: fully tracked frames, pins' largest and mean change.
//! With `--full`, the other tracker is instead the full coarse-to-fine path
//! (no nearest-neighbour start); `--margin M|none` sets the default
//! tracker's margin for keeping a nearest-neighbour start with pins missing
//! (`PinTracker::with_nearest_margin`; `none`: never kept).
//!
//! `cargo run --release -p tactrace-vision --example order_timing -- \
//!     --fit DIR --frames DIR [--rest-frames K] [--limit N] [--reps R] [--compare]
//!     [--full] [--margin M|none]`

use std::path::{Path, PathBuf};
use std::time::Instant;

use tactrace_vision::{
    estimate_rest, inspect, Detection, Frame, PinTracker, RestParams, SightParams, Tracked,
};

struct Args {
    fit: PathBuf,
    frames: PathBuf,
    rest_frames: usize,
    limit: usize,
    reps: usize,
    compare: bool,
    full: bool,
    margin: Option<f64>,
}

fn parse() -> Result<Args, Box<dyn std::error::Error>> {
    let usage = "usage: order_timing --fit DIR --frames DIR [--rest-frames K] [--limit N] \
                 [--reps R] [--compare] [--full] [--margin M|none]";
    let mut args = std::env::args().skip(1);
    let mut a = Args {
        fit: PathBuf::new(),
        frames: PathBuf::new(),
        rest_frames: 150,
        limit: usize::MAX,
        reps: 3,
        compare: false,
        full: false,
        margin: Some(0.25),
    };
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or(usage);
        match arg.as_str() {
            "--fit" => a.fit = value()?.into(),
            "--frames" => a.frames = value()?.into(),
            "--rest-frames" => a.rest_frames = value()?.parse()?,
            "--limit" => a.limit = value()?.parse()?,
            "--reps" => a.reps = value()?.parse::<usize>()?.max(1),
            "--compare" => a.compare = true,
            "--full" => a.full = true,
            "--margin" => {
                a.margin = match value()?.as_str() {
                    "none" => None,
                    m => Some(m.parse()?),
                }
            }
            _ => return Err(usage.into()),
        }
    }
    if a.fit.as_os_str().is_empty() || a.frames.as_os_str().is_empty() {
        return Err(usage.into());
    }
    Ok(a)
}

/// The `.png` files of `dir`, sorted by name.
fn pngs(dir: &Path) -> Result<Vec<PathBuf>, Box<dyn std::error::Error>> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    out.sort();
    Ok(out)
}

/// Every `len / k`-th item, at most `k`.
fn spread(items: &[PathBuf], k: usize) -> Vec<PathBuf> {
    let step = items.len().div_ceil(k.max(1)).max(1);
    items.iter().step_by(step).cloned().collect()
}

/// Seconds this thread has run on a CPU (Linux; 0 elsewhere).
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}

/// Largest and summed absolute pin coordinate change, px, and whether the
/// matched flags agree.
fn change(a: &Tracked, b: &Tracked) -> (f64, f64, bool) {
    let (mut most, mut sum) = (0.0f64, 0.0);
    for (p, q) in a.pins.iter().zip(&b.pins) {
        for k in 0..2 {
            let d = (p[k] - q[k]).abs();
            most = most.max(d);
            sum += d;
        }
    }
    (most, sum, a.matched == b.matched)
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a = parse()?;
    let load = |p: &PathBuf| image::open(p).map_err(Box::<dyn std::error::Error>::from);
    let train = pngs(&a.fit)?;
    let sample: Vec<Frame> = spread(&train, 20)
        .iter()
        .map(|p| load(p).map(|i| i.to_luma8()))
        .collect::<Result<_, _>>()?;
    let found = inspect(&sample, None)?;
    let first = load(&train[0])?;
    let detector = SightParams {
        preprocess: found.preprocess.clone(),
        detect: found.detect.clone(),
    }
    .check(first.width(), first.height())?;
    let fitting: Vec<Detection> = spread(&train, a.rest_frames)
        .iter()
        .map(|p| Ok(detector.detect(&load(p)?)?))
        .collect::<Result<_, Box<dyn std::error::Error>>>()?;
    let rest = estimate_rest(&fitting, found.pins, &RestParams::default())?;
    let tracker = PinTracker::new(rest.pins.clone())?.with_nearest_margin(a.margin);
    let exact = if a.full {
        PinTracker::new(rest.pins)?.with_nearest_start(false)
    } else {
        PinTracker::new(rest.pins)?.with_exact_field(true)
    };
    let other = if a.full { "full" } else { "exact" };
    let paths: Vec<PathBuf> = pngs(&a.frames)?.into_iter().take(a.limit).collect();
    let detections: Vec<Detection> = paths
        .iter()
        .map(|p| Ok(detector.detect(&load(p)?)?))
        .collect::<Result<_, Box<dyn std::error::Error>>>()?;
    println!(
        "{} pins, {} frames of {}",
        tracker.reference().len(),
        detections.len(),
        a.frames.display()
    );
    for (name, t) in [("cut", &tracker), (other, &exact)] {
        let mut each = Vec::with_capacity(detections.len());
        let cpu = cpu_seconds();
        for d in &detections {
            let mut best = f64::INFINITY;
            for _ in 0..a.reps {
                let start = Instant::now();
                std::hint::black_box(t.track(std::hint::black_box(d)));
                best = best.min(start.elapsed().as_secs_f64());
            }
            each.push(best * 1e6);
        }
        let cpu = (cpu_seconds() - cpu) * 1e6 / (a.reps * detections.len()) as f64;
        each.sort_by(f64::total_cmp);
        println!(
            "{name:>7}: ordering a frame: thread CPU mean {cpu:.1} us; wall (best of {}) \
             median {:.1} us, p95 {:.1} us",
            a.reps,
            percentile(&each, 0.5),
            percentile(&each, 0.95)
        );
    }
    if a.compare {
        let (mut most, mut sum, mut flags, mut moved, mut full) = (0.0f64, 0.0, 0, 0, [0, 0]);
        for d in &detections {
            let (x, y) = (tracker.track(d), exact.track(d));
            let (m, s, same) = change(&x, &y);
            most = most.max(m);
            sum += s;
            flags += usize::from(!same);
            moved += usize::from(m > 1e-6);
            full[0] += usize::from(x.missing == 0);
            full[1] += usize::from(y.missing == 0);
        }
        let coords = 2 * detections.len() * tracker.reference().len();
        println!(
            "default vs {other}: fully tracked {} / {} frames ({other} {}), matched flags differ on {} \
             frames, a pin moves more than 1e-6 px on {moved} frames, pins' largest change {most:.3e} px, mean {:.3e} px",
            full[0],
            detections.len(),
            full[1],
            flags,
            sum / coords as f64
        );
    }
    Ok(())
}
