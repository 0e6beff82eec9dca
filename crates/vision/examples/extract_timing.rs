//! Timing of pin extraction (report ch. 4.1), stage by stage, on frames read
//! from PNG files (no criterion; one thread):
//!
//! `cargo run --release -p tactrace-vision --example extract_timing -- \
//!     <preset|file.toml> <reference.png> [--reps N] [--dump out.txt] [--once] <png>...`
//!
//! Prints mean microseconds per frame (thread CPU time, and wall time) for blob detection, ordering (tracker)
//! and the whole `PinExtractor::extract` (detect + order + cluster split when
//! pins are missing), and `threshold` the same detection threshold by
//! threshold (`detect_blobs_by_threshold`, the reference); `--only` times
//! one of them. `--dump` writes every keypoint and ordered pin with
//! full precision, to check that a change leaves the results bit-identical.
//! `--once` orders without the second nearest-neighbour start
//! (`PinTracker::with_second_start(false)`), the ordering before it.
//! `--windows R` sets the matchings' window radius (spacings), `--windows
//! none` turns the windows off (`PinTracker::with_windows`). `--per-frame F` writes, per frame, the thread CPU time of each rep's
//! `extract` (`CLOCK_THREAD_CPUTIME_ID`, microseconds), after its keypoint
//! count and the pins its first pass leaves missing, with `--only detect|order` the time of
//! that stage instead; `--cold MB` writes a buffer of MB megabytes before
//! each frame, so that it starts with cold caches: the reps of a frame
//! tell its own cost (their least) from what the machine added to it, and
//! each time is followed by `/` and the thread's context switches during it.

use std::fmt::Write as _;
use std::time::Instant;

use tactrace_vision::{
    detect_blobs, detect_blobs_by_threshold, BlobParams, Frame, PinExtractor, PinTracker,
};

struct Args {
    params: BlobParams,
    reference: Frame,
    reps: usize,
    dump: Option<String>,
    only: Option<String>,
    once: bool,
    per_frame: Option<String>,
    windows: Option<Option<f64>>,
    cold_mb: usize,
    frames: Vec<(String, Frame)>,
}

fn parse() -> Result<Args, Box<dyn std::error::Error>> {
    let usage =
        "usage: extract_timing <preset|file.toml> <reference.png> [--reps N] [--dump F] [--only detect|threshold|order|extract] [--once] [--per-frame F] [--windows R|none] [--cold MB] <png>...";
    let mut args = std::env::args().skip(1);
    let which = args.next().ok_or(usage)?;
    let params = if which.ends_with(".toml") {
        BlobParams::from_toml(&std::fs::read_to_string(&which)?)?
    } else {
        BlobParams::preset(&which)?
    };
    let reference = image::open(args.next().ok_or(usage)?)?.to_luma8();
    let (mut reps, mut dump, mut only, mut once, mut frames) = (3, None, None, false, Vec::new());
    let (mut per_frame, mut windows, mut cold_mb) = (None, None, 0);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--reps" => reps = args.next().ok_or(usage)?.parse()?,
            "--dump" => dump = Some(args.next().ok_or(usage)?),
            "--only" => only = Some(args.next().ok_or(usage)?),
            "--once" => once = true,
            "--per-frame" => per_frame = Some(args.next().ok_or(usage)?),
            "--cold" => cold_mb = args.next().ok_or(usage)?.parse()?,
            "--windows" => {
                let reach = args.next().ok_or(usage)?;
                windows = Some((reach != "none").then(|| reach.parse()).transpose()?);
            }
            _ => {
                let frame = image::open(&a)?.to_luma8();
                frames.push((a, frame));
            }
        }
    }
    if frames.is_empty() {
        return Err(usage.into());
    }
    Ok(Args {
        params,
        reference,
        reps: reps.max(1),
        dump,
        only,
        once,
        per_frame,
        windows,
        cold_mb,
        frames,
    })
}

/// Seconds this thread has run on a CPU (Linux `/proc/thread-self/schedstat`),
/// so that time spent waiting for a shared core is not counted.
fn cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// Mean (CPU, wall) microseconds per call of `f` over every frame, `reps`
/// times; CPU time is NaN where the kernel does not report it.
fn time_per_frame(frames: &[(String, Frame)], reps: usize, mut f: impl FnMut(usize)) -> (f64, f64) {
    let (cpu0, start) = (cpu_seconds(), Instant::now());
    for _ in 0..reps {
        for i in 0..frames.len() {
            f(i);
        }
    }
    let n = (reps * frames.len()) as f64;
    let wall = start.elapsed().as_secs_f64();
    let cpu = match (cpu0, cpu_seconds()) {
        (Some(a), Some(b)) => b - a,
        _ => f64::NAN,
    };
    (cpu * 1e6 / n, wall * 1e6 / n)
}

/// This thread's CPU time, microseconds (`CLOCK_THREAD_CPUTIME_ID`).
fn thread_cpu_us() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec into `t`, which lives here
    // for the call.
    let read = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    if read == 0 {
        t.tv_sec as f64 * 1e6 + t.tv_nsec as f64 * 1e-3
    } else {
        f64::NAN
    }
}

/// Context switches of this thread so far, voluntary plus involuntary
/// (`getrusage(RUSAGE_THREAD)`).
fn switches() -> i64 {
    // SAFETY: an all-zero rusage is a valid value, which getrusage
    // overwrites.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: getrusage writes one rusage into `u`, which lives here for
    // the call.
    let read = unsafe { libc::getrusage(libc::RUSAGE_THREAD, &mut u) };
    if read == 0 {
        u.ru_nvcsw + u.ru_nivcsw
    } else {
        -1
    }
}

/// Per frame, its name and the thread CPU time of `extract` in each of
/// `reps` passes over all the frames (frames in order within a pass, as
/// `bench` runs them) with the context switches during it, one line a
/// frame.
fn per_frame_cpu(a: &Args, extractor: &PinExtractor) -> String {
    let mut times = vec![Vec::with_capacity(a.reps); a.frames.len()];
    let mut flush = vec![0u8; a.cold_mb << 20];
    let keypoints: Vec<_> = a
        .frames
        .iter()
        .map(|(_, f)| detect_blobs(f, &a.params))
        .collect();
    for rep in 0..a.reps {
        for (i, (_, frame)) in a.frames.iter().enumerate() {
            // Every cache line of the buffer written: the caches then hold
            // none of the frame's data, as after another process ran.
            for line in flush.chunks_mut(64) {
                line[0] = line[0].wrapping_add(rep as u8 | 1);
            }
            std::hint::black_box(&mut flush);
            let (s, c) = (switches(), thread_cpu_us());
            match a.only.as_deref() {
                Some("detect") => drop(std::hint::black_box(detect_blobs(frame, &a.params))),
                Some("order") => drop(std::hint::black_box(extractor.tracker.order(&keypoints[i]))),
                _ => drop(std::hint::black_box(extractor.extract(frame).ok())),
            }
            let cpu = thread_cpu_us() - c;
            times[i].push((cpu, switches() - s));
        }
    }
    let mut out = String::new();
    for ((name, frame), t) in a.frames.iter().zip(&times) {
        let keypoints = detect_blobs(frame, &a.params);
        let first = extractor.tracker.first_pass(&keypoints);
        let cells: Vec<String> = t.iter().map(|(v, s)| format!("{v:.2}/{s}")).collect();
        let (n, missing) = (keypoints.len(), first.tracked().missing);
        let _ = writeln!(out, "{name} {n} {missing} {}", cells.join(" "));
    }
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a = parse()?;
    let mut extractor = PinExtractor::from_reference_frame(&a.reference, a.params.clone())?;
    if a.once {
        let reference = extractor.tracker.reference().to_vec();
        extractor.tracker = PinTracker::new(reference)?.with_second_start(false);
    }
    if let Some(reach) = a.windows {
        let reference = extractor.tracker.reference().to_vec();
        extractor.tracker = PinTracker::new(reference)?.with_windows(reach);
    }
    let keypoints: Vec<_> = a
        .frames
        .iter()
        .map(|(_, f)| detect_blobs(f, &a.params))
        .collect();
    let runs = |stage: &str| !matches!(a.only.as_deref(), Some(o) if o != stage);
    let reps = |stage: &str| if runs(stage) { a.reps } else { 0 };
    let detect_us = time_per_frame(&a.frames, reps("detect"), |i| {
        std::hint::black_box(detect_blobs(&a.frames[i].1, &a.params));
    });
    let threshold_us = time_per_frame(&a.frames, reps("threshold"), |i| {
        std::hint::black_box(detect_blobs_by_threshold(&a.frames[i].1, &a.params));
    });
    let order_us = time_per_frame(&a.frames, reps("order"), |i| {
        std::hint::black_box(extractor.tracker.order(&keypoints[i]));
    });
    let mut failed = 0;
    let extract_us = time_per_frame(&a.frames, reps("extract"), |i| {
        failed += usize::from(extractor.extract(&a.frames[i].1).is_err());
    });
    println!(
        "{} frames x {} reps, {} reference pins",
        a.frames.len(),
        a.reps,
        extractor.tracker.reference().len()
    );
    println!("per frame: CPU us (wall us)");
    println!("detect:  {:.1} ({:.1})", detect_us.0, detect_us.1);
    println!(
        "threshold: {:.1} ({:.1}) the same blobs threshold by threshold",
        threshold_us.0, threshold_us.1
    );
    println!("order:   {:.1} ({:.1})", order_us.0, order_us.1);
    println!(
        "extract: {:.1} ({:.1}) detect + order + split; {} failures",
        extract_us.0,
        extract_us.1,
        failed / a.reps.max(1)
    );
    if let Some(path) = &a.per_frame {
        std::fs::write(path, per_frame_cpu(&a, &extractor))?;
    }
    if let Some(path) = a.dump {
        let mut out = String::new();
        for ((name, frame), kps) in a.frames.iter().zip(&keypoints) {
            for k in kps {
                writeln!(out, "{name} kp {:?} {:?} {:?}", k.x, k.y, k.size)?;
            }
            match extractor.extract(frame) {
                Ok(t) => {
                    for (p, m) in t.pins.iter().zip(&t.matched) {
                        writeln!(out, "{name} pin {:?} {:?} {m}", p[0], p[1])?;
                    }
                }
                Err(e) => writeln!(out, "{name} error {e}")?,
            }
        }
        std::fs::write(path, out)?;
    }
    Ok(())
}
