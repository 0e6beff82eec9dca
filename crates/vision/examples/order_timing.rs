//! Timing and checking of the pin ordering on any TacTip's frames (issue
//! 21, item 6): the sensor proposed from 20 frames of the fitting part, the
//! rest layout estimated from `--rest-frames` of its taps (as
//! `tests/it/speed.rs` does), then every frame of `--frames` detected once
//! and ordered `--reps` times (0: not timed): the mean thread CPU time a frame (the time a
//! loaded machine makes the thread wait is not counted), the median and
//! p95 of each frame's least thread CPU time, and the median and p95 of
//! each frame's best wall time. With `--compare`,
//! each frame is also ordered (and timed) with the exact (uncut) smooth field and the
//! two are compared: fully tracked frames, pins' largest and mean change.
//! With `--full`, the other tracker is instead the full coarse-to-fine path
//! (no nearest-neighbour start); `--margin M|none` sets the default
//! tracker's margin for keeping a nearest-neighbour start with pins missing
//! (`PinTracker::with_nearest_margin`; `none`: never kept). With `--plain`,
//! the other tracker is the one without the speed cuts that change no pin
//! (`PinTracker::with_speed_cuts(false)`). With `--once`, the other tracker
//! is the one without the second nearest-neighbour start
//! (`PinTracker::with_second_start(false)`). With `--unseeded`, the other
//! tracker orders the split pass from scratch
//! (`PinTracker::with_seeded_split(false)`). With `--unpropagated`, the
//! other tracker is the one without the propagated start of the first
//! pass (`PinTracker::with_propagated_start(false)`). With `--unscaled`,
//! the other tracker starts from the reference only moved, not scaled
//! (`PinTracker::with_scaled_start(false)`). With `--unstalled`, the other
//! tracker sends a stalled propagated growth on to the nearest-neighbour
//! start instead of matching it again
//! (`PinTracker::with_stalled_growth(false)`). With `--reference FRAME`, the
//! rest layout is the pins detected in FRAME (an undeformed frame, as
//! `import --reference` and `bench`'s 127-pin frames take it) instead of
//! the one estimated from the taps. With `--dump
//! FILE`, every frame's pins from the default tracker are written to FILE
//! bit for bit (per pin x and y as little-endian f64 bits and the matched
//! flag; per frame the missing and extra counts), so two versions of the
//! tracker compare with `cmp`.
//!
//! Instruction counts of the ordering alone: `valgrind --tool=callgrind
//! --toggle-collect='*time_frames*' target/release/examples/order_timing ...`.
//!
//! `cargo run --release -p tactrace-vision --example order_timing -- \
//!     --fit DIR --frames DIR [--rest-frames K] [--limit N] [--reps R] [--compare]
//!     [--full] [--plain] [--once] [--unseeded] [--unpropagated] [--unscaled]
//!     [--unstalled]
//!     [--reference FRAME] [--margin M|none] [--dump FILE]`

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
    plain: bool,
    once: bool,
    unseeded: bool,
    unpropagated: bool,
    unscaled: bool,
    unstalled: bool,
    reference: Option<PathBuf>,
    margin: Option<f64>,
    dump: Option<PathBuf>,
}

fn parse() -> Result<Args, Box<dyn std::error::Error>> {
    let usage = "usage: order_timing --fit DIR --frames DIR [--rest-frames K] [--limit N] \
                 [--reps R] [--compare] [--full] [--plain] [--once] [--unseeded] [--unpropagated] \
                 [--unscaled] [--unstalled] [--reference FRAME] [--margin M|none] [--dump FILE]";
    let mut args = std::env::args().skip(1);
    let mut a = Args {
        fit: PathBuf::new(),
        frames: PathBuf::new(),
        rest_frames: 150,
        limit: usize::MAX,
        reps: 3,
        compare: false,
        full: false,
        plain: false,
        once: false,
        unseeded: false,
        unpropagated: false,
        unscaled: false,
        unstalled: false,
        reference: None,
        margin: Some(0.25),
        dump: None,
    };
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or(usage);
        match arg.as_str() {
            "--fit" => a.fit = value()?.into(),
            "--frames" => a.frames = value()?.into(),
            "--rest-frames" => a.rest_frames = value()?.parse()?,
            "--limit" => a.limit = value()?.parse()?,
            "--reps" => a.reps = value()?.parse()?,
            "--compare" => a.compare = true,
            "--full" => a.full = true,
            "--plain" => a.plain = true,
            "--once" => a.once = true,
            "--unseeded" => a.unseeded = true,
            "--unpropagated" => a.unpropagated = true,
            "--unscaled" => a.unscaled = true,
            "--unstalled" => a.unstalled = true,
            "--reference" => a.reference = Some(value()?.into()),
            "--dump" => a.dump = Some(value()?.into()),
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

/// Seconds this thread has run on a CPU (its CPU-time clock, to the
/// nanosecond, on 64-bit Linux; 0 elsewhere).
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
fn cpu_seconds() -> f64 {
    // `struct timespec` is two 64-bit integers here: seconds, nanoseconds.
    extern "C" {
        fn clock_gettime(clock: i32, t: *mut [i64; 2]) -> i32;
    }
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut t = [0i64; 2];
    // SAFETY: clock_gettime writes one timespec into `t`, which lives here.
    let read = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut t) };
    f64::from(u8::from(read == 0)) * (t[0] as f64 + t[1] as f64 * 1e-9)
}

/// Elsewhere: not measured.
#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
fn cpu_seconds() -> f64 {
    0.0
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

/// Every frame's pins, bit for bit (see the module docs).
fn dump(path: &Path, tracker: &PinTracker, detections: &[Detection]) -> std::io::Result<()> {
    let mut out = Vec::new();
    for d in detections {
        let t = tracker.track(d);
        for (p, &m) in t.pins.iter().zip(&t.matched) {
            out.extend_from_slice(&p[0].to_bits().to_le_bytes());
            out.extend_from_slice(&p[1].to_bits().to_le_bytes());
            out.push(u8::from(m));
        }
        out.extend_from_slice(&(t.missing as u32).to_le_bytes());
        out.extend_from_slice(&(t.extra as u32).to_le_bytes());
    }
    std::fs::write(path, out)
}

/// Each frame's best wall time and best thread CPU time of `reps`
/// orderings, us. Not inlined, so that callgrind can
/// count it alone (`--toggle-collect='*time_frames*'`).
#[inline(never)]
fn time_frames(
    tracker: &PinTracker,
    detections: &[Detection],
    reps: usize,
) -> (Vec<f64>, Vec<f64>) {
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    for d in detections {
        let (mut best, mut least) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..reps {
            let on_cpu = cpu_seconds();
            let start = Instant::now();
            std::hint::black_box(tracker.track(std::hint::black_box(d)));
            best = best.min(start.elapsed().as_secs_f64());
            least = least.min(cpu_seconds() - on_cpu);
        }
        wall.push(best * 1e6);
        cpu.push(least * 1e6);
    }
    (wall, cpu)
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
    let rest = match &a.reference {
        Some(frame) => detector
            .detect(&load(frame)?)?
            .points
            .iter()
            .map(|k| [k.x, k.y])
            .collect(),
        None => estimate_rest(&fitting, found.pins, &RestParams::default())?.pins,
    };
    let tracker = PinTracker::new(rest.clone())?.with_nearest_margin(a.margin);
    let (exact, other) = if a.full {
        (PinTracker::new(rest)?.with_nearest_start(false), "full")
    } else if a.plain {
        (PinTracker::new(rest)?.with_speed_cuts(false), "plain")
    } else if a.once {
        (PinTracker::new(rest)?.with_second_start(false), "once")
    } else if a.unpropagated {
        (
            PinTracker::new(rest)?.with_propagated_start(false),
            "unpropagated",
        )
    } else if a.unscaled {
        (PinTracker::new(rest)?.with_scaled_start(false), "unscaled")
    } else if a.unstalled {
        (
            PinTracker::new(rest)?.with_stalled_growth(false),
            "unstalled",
        )
    } else if a.unseeded {
        (PinTracker::new(rest)?.with_seeded_split(false), "unseeded")
    } else {
        (PinTracker::new(rest)?.with_exact_field(true), "exact")
    };
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
    if let Some(path) = &a.dump {
        dump(path, &tracker, &detections)?;
        println!("pins of every frame written to {}", path.display());
    }
    let timed = match (
        a.reps,
        a.compare
            || a.full
            || a.plain
            || a.once
            || a.unseeded
            || a.unpropagated
            || a.unscaled
            || a.unstalled,
    ) {
        (0, _) => 0,
        (_, false) => 1,
        (_, true) => 2,
    };
    for (name, t) in [("cut", &tracker), (other, &exact)].into_iter().take(timed) {
        let cpu = cpu_seconds();
        let (mut each, mut on_cpu) = time_frames(t, &detections, a.reps);
        let cpu = (cpu_seconds() - cpu) * 1e6 / (a.reps * detections.len()) as f64;
        each.sort_by(f64::total_cmp);
        on_cpu.sort_by(f64::total_cmp);
        println!(
            "{name:>7}: ordering a frame: thread CPU mean {cpu:.1} us (best of {r}: median \
             {:.1} us, p95 {:.1} us); wall (best of {r}) median {:.1} us, p95 {:.1} us",
            percentile(&on_cpu, 0.5),
            percentile(&on_cpu, 0.95),
            percentile(&each, 0.5),
            percentile(&each, 0.95),
            r = a.reps,
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
