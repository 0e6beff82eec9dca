//! Speed of the convolutional models (issue 22, item 4), fixed seeds,
//! best of several repeats:
//! 1. training samples/s of `conv-dennn` and `conv-mlp` (default
//!    configuration, 64 x 64 frames), one thread and every thread;
//! 2. the convolution layers against the GEMM they are built on: each conv
//!    layer's forward (im2col, product, then bias, potentials and rates in
//!    one pass), down pass (product with `W^T`, then col2im and slope in
//!    one pass; none into the input) and weight term
//!    (`e cols^T`) on one chunk, against the bare products of the same
//!    shapes, and against a large square product (this machine's GEMM
//!    peak, same library, one thread);
//! 3. inference per frame at 64 x 64, one frame at a time, one thread.
//!
//! Times are CPU time (64-bit Linux `clock_gettime`: the thread's for one thread,
//! the process's for several), so other work on the machine inflates them
//! less than wall-clock time; the training section gives both.
//!
//! Run with `cargo bench -p tactrace-convnet --bench convnet`; an argument
//! keeps only the sections whose name contains it (`-- inference`).
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;
use tactrace_convnet::kernels::{
    add_product_nt, col2im_times_slope, im2col, product, product_tn, settle, Errors, Settle,
};
use tactrace_convnet::{
    Activation, ConvConfig, ConvModel, Frames, LayerShape, Layout, ModelKind, Targets,
};

const SIDE: usize = 64;

/// Binary frames of random bright dots (a TacTip's pins, roughly), with
/// two targets.
fn frames(count: usize, seed: u64) -> (Vec<u8>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pixels = vec![0u8; count * SIDE * SIDE];
    for p in pixels.iter_mut() {
        if rng.random_range(0..10) == 0 {
            *p = 255;
        }
    }
    let targets = (0..count * 2)
        .map(|_| rng.random_range(-5.0..5.0))
        .collect();
    (pixels, targets)
}

/// CPU seconds of this thread (`process`: of the whole process).
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
fn cpu_seconds(process: bool) -> f64 {
    #[repr(C)]
    struct Timespec {
        sec: i64,
        nsec: i64,
    }
    extern "C" {
        fn clock_gettime(clock: i32, t: *mut Timespec) -> i32;
    }
    // CLOCK_PROCESS_CPUTIME_ID = 2, CLOCK_THREAD_CPUTIME_ID = 3.
    let mut t = Timespec { sec: 0, nsec: 0 };
    // SAFETY: clock_gettime writes one timespec into `t`, which lives here.
    let ok = unsafe { clock_gettime(if process { 2 } else { 3 }, &mut t) } == 0;
    if ok {
        t.sec as f64 + t.nsec as f64 * 1e-9
    } else {
        f64::NAN
    }
}

/// Elsewhere: wall-clock time from the first call.
#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
fn cpu_seconds(_process: bool) -> f64 {
    use std::sync::OnceLock;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// Best of `repeats` thread CPU seconds of `f`.
fn best(repeats: usize, mut f: impl FnMut()) -> f64 {
    (0..repeats)
        .map(|_| {
            let t = cpu_seconds(false);
            f();
            cpu_seconds(false) - t
        })
        .fold(f64::INFINITY, f64::min)
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

fn training() {
    let (count, epochs) = (512, 2);
    let (pixels, targets) = frames(count, 1);
    let f = Frames::new(&pixels, count, SIDE, SIDE).expect("frames");
    let t = Targets::new(&targets, count, 2).expect("targets");
    let all = rayon::current_num_threads();
    for kind in [ModelKind::ConvDennn, ModelKind::ConvMlp] {
        let mut cfg = ConvConfig::new(kind);
        cfg.epochs = epochs;
        for threads in [1, all] {
            let (mut wall, mut cpu) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..3 {
                let (w, c) = (Instant::now(), cpu_seconds(true));
                pool(threads).install(|| {
                    ConvModel::fit(&f, &t, &cfg, 7).expect("fit");
                });
                wall = wall.min(w.elapsed().as_secs_f64());
                cpu = cpu.min(cpu_seconds(true) - c);
            }
            let samples = (count * epochs) as f64;
            println!(
                "training {:<10} {threads} thread(s): {:7.0} samples/s wall-clock, {:6.0} us CPU a sample",
                kind.name(),
                samples / wall,
                1e6 * cpu / samples
            );
        }
    }
}

/// GFLOP/s of `flops` done in `secs`.
fn gflops(flops: f64, secs: f64) -> f64 {
    flops / secs / 1e9
}

fn peak() -> f64 {
    let n = 1024;
    let a: Vec<f32> = (0..n * n).map(|i| (i % 7) as f32 * 0.1).collect();
    let mut c = vec![0.0f32; n * n];
    let secs = best(15, || product(&mut c, &a, &a, n, n, n));
    gflops(2.0 * (n * n * n) as f64, secs)
}

/// Seconds of one conv layer's passes on an `nb`-frame chunk, each
/// beside the bare product inside it.
struct LayerTimes {
    /// im2col, product, then bias, potentials and rates; and the product
    /// alone.
    forward: (f64, f64),
    /// Product with `W^T`, then col2im and the slope; and the product
    /// alone.
    down: (f64, f64),
    /// The weight term `e cols^T` (a bare product).
    weights: f64,
}

/// Times of one conv layer's three passes, and the flops of one product.
fn layer_times(s: &LayerShape, nb: usize, act: Activation) -> (LayerTimes, f64) {
    let (m, k, n) = (s.cout, s.fan_in(), nb * s.positions());
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut r =
        |len: usize| -> Vec<f32> { (0..len).map(|_| rng.random_range(-1.0..1.0)).collect() };
    let (input, w, bias, e) = (r(s.in_len() * nb), r(m * k), r(m), r(m * n));
    let rate = r(s.in_len() * nb);
    let (mut cols, mut out, mut down) = (
        vec![0.0; k * n],
        vec![0.0; m * n],
        vec![0.0; s.in_len() * nb],
    );
    let (mut rate_out, mut errors, mut soma) =
        (vec![0.0; m * n], vec![0.0; m * n], vec![0.0; m * n]);
    let reps = ((2e8 / (2.0 * (m * k * n) as f64)) as usize).clamp(3, 200);
    let time = |f: &mut dyn FnMut()| best(9, || (0..reps).for_each(|_| f())) / reps as f64;
    let forward = time(&mut || {
        im2col(s, nb, &input, &mut cols);
        product(&mut out, &w, &cols, m, k, n);
        settle(Settle {
            activation: act,
            bias: Some(&bias),
            errors: Errors::Zero,
            p: &mut out,
            e: &mut errors,
            s: &mut soma,
            a: Some(&mut rate_out),
        });
    });
    let forward_gemm = time(&mut || product(&mut out, &w, &cols, m, k, n));
    let back = time(&mut || {
        product_tn(&mut cols, &w, &e, m, k, n);
        col2im_times_slope(s, nb, &cols, &mut down, act, &rate);
    });
    let back_gemm = time(&mut || product_tn(&mut cols, &w, &e, m, k, n));
    let mut grad = vec![0.0; m * k];
    let weights = time(&mut || add_product_nt(&mut grad, 1.0, &e, &cols, m, k, n));
    let times = LayerTimes {
        forward: (forward, forward_gemm),
        down: (back, back_gemm),
        weights,
    };
    (times, 2.0 * (m * k * n) as f64)
}

/// The conv layers' passes as training runs them (forward, down except
/// into the input, which is held, and the weight term), against the same
/// products alone and against the large square product.
fn conv_layers() {
    let cfg = ConvConfig::new(ModelKind::ConvDennn);
    let layout = Layout::new(SIDE, SIDE, &cfg.conv, &cfg.dense, 2).expect("layout");
    let nb = cfg.chunk_size;
    let peak = peak();
    println!("GEMM peak (1024 x 1024 x 1024, faer, one thread): {peak:.1} GFLOP/s");
    let act = match cfg.activation {
        Activation::Tanh => "tanh",
        Activation::Sigmoid => "sigmoid",
        Activation::Relu => "relu",
    };
    println!("conv layers of the default configuration ({act} rates), thread CPU time:");
    let (mut layer_total, mut gemm_total, mut flops_total) = (0.0, 0.0, 0.0);
    for (l, s) in layout
        .layers()
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.is_dense())
    {
        let (t, flops) = layer_times(s, nb, cfg.activation);
        let (fwd, fwd_g) = t.forward;
        let (back, back_g) = t.down;
        let down = if l == 0 {
            "no down pass (the input is held)".to_string()
        } else {
            format!(
                "down {:.1} GFLOP/s = {:.0} % of its GEMM ({:.1})",
                gflops(flops, back),
                100.0 * back_g / back,
                gflops(flops, back_g)
            )
        };
        println!(
            "conv {} ({} x {} x {} -> {} x {} x {}, chunk {nb}): forward {:.1} GFLOP/s = {:.0} % of \
             its GEMM ({:.1}), {:.0} % of peak; {down}; weights {:.1} GFLOP/s",
            l + 1,
            s.cin,
            s.hin,
            s.win,
            s.cout,
            s.hout,
            s.wout,
            gflops(flops, fwd),
            100.0 * fwd_g / fwd,
            gflops(flops, fwd_g),
            100.0 * gflops(flops, fwd) / peak,
            gflops(flops, t.weights),
        );
        let passes = if l == 0 { 2.0 } else { 3.0 };
        let (layer, gemm) = if l == 0 {
            (fwd + t.weights, fwd_g + t.weights)
        } else {
            (fwd + back + t.weights, fwd_g + back_g + t.weights)
        };
        layer_total += layer;
        gemm_total += gemm;
        flops_total += passes * flops;
    }
    println!(
        "conv layers together (a training step's passes): {:.1} GFLOP/s = {:.0} % of the same \
         GEMMs ({:.1} GFLOP/s), {:.0} % of peak",
        gflops(flops_total, layer_total),
        100.0 * gemm_total / layer_total,
        gflops(flops_total, gemm_total),
        100.0 * gflops(flops_total, layer_total) / peak
    );
}

fn inference() {
    let count = 64;
    let (pixels, targets) = frames(count, 2);
    let f = Frames::new(&pixels, count, SIDE, SIDE).expect("frames");
    let t = Targets::new(&targets, count, 2).expect("targets");
    let mut cfg = ConvConfig::new(ModelKind::ConvDennn);
    cfg.epochs = 1;
    let (model, _) = pool(1).install(|| ConvModel::fit(&f, &t, &cfg, 7).expect("fit"));
    let mut predictor = model.predictor();
    let mut out = [0.0; 2];
    let frames_timed = 500;
    let secs = best(5, || {
        for i in 0..frames_timed {
            model
                .predict_with(&mut predictor, f.frame(i % count), &mut out)
                .expect("predict");
        }
    });
    println!(
        "inference at {SIDE} x {SIDE}, one frame at a time, one thread: {:.0} us a frame ({} MMAC)",
        1e6 * secs / frames_timed as f64,
        model.network().layout().forward_macs() as f64 / 1e6
    );
}

fn main() {
    let filter = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .unwrap_or_default();
    let sections: [(&str, fn()); 3] = [
        ("training", training),
        ("conv-layers", conv_layers),
        ("inference", inference),
    ];
    for (name, run) in sections {
        if name.contains(filter.as_str()) {
            run();
        }
    }
}
