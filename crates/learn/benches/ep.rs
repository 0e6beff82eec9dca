//! Per-sample training time of the report's networks (equilibrium
//! propagation and the backprop twin). Fixed seeds; plain `Instant` timing.
//! Run with `cargo bench -p tactrace-learn --bench ep`; an argument keeps
//! only the rows whose name contains it (`... --bench ep -- angle`).
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;
use tactrace_learn::{ClampedPhase, Dataset, DenNN, EpConfig, FreePhase, Mlp};

const SAMPLES: usize = 2000;
const REPEATS: usize = 5;

fn data(dim_x: usize, dim_y: usize, seed: u64) -> (Vec<f32>, Vec<f32>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let x = (0..SAMPLES * dim_x)
        .map(|_| rng.random_range(-1.0..1.0))
        .collect();
    let y = (0..SAMPLES * dim_y)
        .map(|_| rng.random_range(-1.0..1.0))
        .collect();
    (x, y)
}

/// Best-of-`REPEATS` microseconds per sample of one pass over the data.
fn time_per_sample(mut step: impl FnMut(usize)) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..REPEATS {
        let start = Instant::now();
        (0..SAMPLES).for_each(&mut step);
        best = best.min(start.elapsed().as_secs_f64() * 1e6 / SAMPLES as f64);
    }
    best
}

fn bench_ep(name: &str, sizes: &[usize], cfg: &EpConfig) {
    let (dx, dy) = (sizes[0], sizes[sizes.len() - 1]);
    let (x, y) = data(dx, dy, 1);
    let mut net = DenNN::new(sizes, 7).expect("valid sizes");
    let us = time_per_sample(|i| {
        let _ = net.train_sample(&x[i * dx..(i + 1) * dx], &y[i * dy..(i + 1) * dy], cfg);
    });
    println!("{name:<40} {us:8.2} us/sample");
}

fn bench_ep_sequence(name: &str, sizes: &[usize], cfg: &EpConfig) {
    let (dx, dy) = (sizes[0], sizes[sizes.len() - 1]);
    let (x, y) = data(dx, dy, 1);
    let ds = Dataset::new(x, y, SAMPLES, dx, dy).expect("finite data");
    let order: Vec<usize> = (0..SAMPLES).collect();
    let mut net = DenNN::new(sizes, 7).expect("valid sizes");
    let mut best = f64::INFINITY;
    for _ in 0..REPEATS {
        let start = Instant::now();
        let _ = net.train_sequence(&ds, &order, cfg);
        best = best.min(start.elapsed().as_secs_f64() * 1e6 / SAMPLES as f64);
    }
    println!("{name:<40} {best:8.2} us/sample");
}

fn bench_mlp(name: &str, sizes: &[usize]) {
    let (dx, dy) = (sizes[0], sizes[sizes.len() - 1]);
    let (x, y) = data(dx, dy, 1);
    let mut net = Mlp::new(sizes, 7).expect("valid sizes");
    let us = time_per_sample(|i| {
        let _ = net.train_sample(&x[i * dx..(i + 1) * dx], &y[i * dy..(i + 1) * dy], 0.001);
    });
    println!("{name:<40} {us:8.2} us/sample");
}

fn main() {
    let filter = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .unwrap_or_default();
    let wanted = |name: &str| name.contains(filter.as_str());
    let fast = EpConfig::default();
    let faithful = EpConfig {
        free_phase: FreePhase::Euler { n_i: 5, dt: 1.0 },
        clamped_phase: ClampedPhase::Euler { n_i: 5, dt: 1.0 },
        ..EpConfig::default()
    };
    for (label, sizes) in [
        ("PDenNN angle 35-1000-1", &[35, 1000, 1][..]),
        ("PDenNN position 30-500-1", &[30, 500, 1]),
        ("PCADenNN 35-1000-2", &[35, 1000, 2]),
        ("DisDenNN 254-500-2", &[254, 500, 2]),
    ] {
        let name = format!("EP ff+closed-form {label}");
        if wanted(&name) {
            bench_ep(&name, sizes, &fast);
        }
        let name = format!("EP ff+closed-form fused {label}");
        if wanted(&name) {
            bench_ep_sequence(&name, sizes, &fast);
        }
        let name = format!("EP Euler n_I=5 {label}");
        if wanted(&name) {
            bench_ep(&name, sizes, &faithful);
        }
        let name = format!("backprop {label}");
        if wanted(&name) {
            bench_mlp(&name, sizes);
        }
    }
}
