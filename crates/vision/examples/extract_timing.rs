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
    frames: Vec<(String, Frame)>,
}

fn parse() -> Result<Args, Box<dyn std::error::Error>> {
    let usage =
        "usage: extract_timing <preset|file.toml> <reference.png> [--reps N] [--dump F] [--only detect|threshold|order|extract] [--once] <png>...";
    let mut args = std::env::args().skip(1);
    let which = args.next().ok_or(usage)?;
    let params = if which.ends_with(".toml") {
        BlobParams::from_toml(&std::fs::read_to_string(&which)?)?
    } else {
        BlobParams::preset(&which)?
    };
    let reference = image::open(args.next().ok_or(usage)?)?.to_luma8();
    let (mut reps, mut dump, mut only, mut once, mut frames) = (3, None, None, false, Vec::new());
    while let Some(a) = args.next() {
        match a.as_str() {
            "--reps" => reps = args.next().ok_or(usage)?.parse()?,
            "--dump" => dump = Some(args.next().ok_or(usage)?),
            "--only" => only = Some(args.next().ok_or(usage)?),
            "--once" => once = true,
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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a = parse()?;
    let mut extractor = PinExtractor::from_reference_frame(&a.reference, a.params.clone())?;
    if a.once {
        let reference = extractor.tracker.reference().to_vec();
        extractor.tracker = PinTracker::new(reference)?.with_second_start(false);
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
