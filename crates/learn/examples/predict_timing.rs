//! Timing of a saved pose model's batch prediction (issue 21, item 6), the
//! figure `tactrace bench` reports as `batch_us`, without the rest of the
//! bench: thread CPU time and best wall time a sample over `--reps` runs
//! of `PoseModel::predict_rows` on `--rows` seeded rows, and the FMA
//! bound of a prediction at this machine's measured peak
//! (`measure_fma_peak`, best of 20 rounds).
//!
//! `cargo run --release -p tactrace-learn --example predict_timing -- \
//!     MODEL_DIR [--rows N] [--reps R]`

use std::time::Instant;

use tactrace_learn::{measure_fma_peak, PoseModel};

/// Seconds this thread has run on a CPU (Linux; 0 elsewhere).
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: predict_timing MODEL_DIR [--rows N] [--reps R]";
    let mut args = std::env::args().skip(1);
    let dir = std::path::PathBuf::from(args.next().ok_or(usage)?);
    let (mut rows, mut reps) = (2000usize, 50usize);
    while let Some(a) = args.next() {
        let value = args.next().ok_or(usage)?;
        match a.as_str() {
            "--rows" => rows = value.parse()?,
            "--reps" => reps = value.parse::<usize>()?.max(1),
            _ => return Err(usage.into()),
        }
    }
    let json = std::fs::read_to_string(dir.join("model.json"))?;
    let weights = std::fs::read(dir.join("weights.safetensors"))?;
    let model = PoseModel::from_bytes(&json, &weights)?;
    let dim = model.input_dim();
    let mut state = 2104u64;
    let flat: Vec<f32> = (0..rows * dim)
        .map(|_| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 4.0
        })
        .collect();
    let cpu = cpu_seconds();
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let start = Instant::now();
        std::hint::black_box(model.predict_rows(std::hint::black_box(&flat))?);
        best = best.min(start.elapsed().as_secs_f64());
    }
    let cpu = (cpu_seconds() - cpu) / (reps * rows) as f64 * 1e6;
    let wall = best / rows as f64 * 1e6;
    println!("{rows} rows x {reps} reps: thread CPU {cpu:.3} us a sample, best wall {wall:.3} us a sample");
    let peak = measure_fma_peak(20);
    let (f64_ops, f32_ops) = model.multiply_adds();
    let bound = peak.seconds((f64_ops, f32_ops)) * 1e6;
    println!(
        "FMA peak {:.1} G/s f32, {:.1} G/s f64; bound of a prediction ({f64_ops} f64 + {f32_ops} f32 \
         multiply-adds) {bound:.3} us; best wall / bound {:.2}",
        peak.f32_per_second / 1e9,
        peak.f64_per_second / 1e9,
        wall / bound
    );
    Ok(())
}
