//! Throughput and latency figures (`tactrace bench`): simulated taps per
//! second (render + detect + order), the control-loop latency from frame
//! to command (detect, order, PCA, both nets, controller), as the mean and
//! the per-frame median and 95th percentile with the median of each part,
//! and the prediction's time against its multiply-adds at the machine's
//! measured fused multiply-add rate (`Prediction`). On real frames each
//! frame's thread CPU time is taken too: on a shared machine the wall
//! clock's tail is other processes' time slices, the CPU time's is the
//! code's. Timings are measured here, never asserted in tests.
use crate::error::Result;
use serde::Serialize;
use std::time::Instant;
use tactrace_control::{PbtsConfig, PbtsController, SensedPose};
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_learn::{measure_fma_peak, PoseModel};
use tactrace_sensor::{LabelConvention, TacTipModel};
use tactrace_servo::{pose_at_edge, RigConfig};
use tactrace_store::SensorFolder;
use tactrace_vision::{DetectorParams, PinReader};

/// Figures from one benchmark run (single thread).
#[derive(Debug, Clone, Serialize)]
pub struct BenchFigures {
    pub taps: usize,
    /// Pin model + rendering, microseconds per tap.
    pub simulate_us: f64,
    /// Blob detection + ordering + displacement, microseconds per frame.
    pub extract_us: f64,
    /// Simulated taps per second, render + detect + order.
    pub taps_per_second: f64,
    /// Frame -> command (extract, model, controller), microseconds; None without a model.
    pub control_latency_us: Option<f64>,
    /// Median over frames of the frame -> command time, microseconds
    /// (each frame timed alone; robust to the noise spikes of a shared machine).
    pub control_latency_median_us: Option<f64>,
    /// 95th percentile (nearest rank) of the per-frame time, microseconds.
    pub control_latency_p95_us: Option<f64>,
    /// The model's prediction on the taps' displacements; None without a
    /// model.
    pub prediction: Option<Prediction>,
}

/// A model's prediction time against its bound, microseconds a sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Prediction {
    /// One sample a call (`PoseModel::predict`), best of five passes.
    pub one_us: f64,
    /// A batch of all samples (`PoseModel::predict_rows`), per sample,
    /// best of five passes.
    pub batch_us: f64,
    /// Multiply-adds of one prediction in f64 (the projections) and f32
    /// (the nets' layers).
    pub multiply_adds_f64: usize,
    pub multiply_adds_f32: usize,
    /// The time of those multiply-adds at the measured peak rate (best of
    /// 20 runs): no prediction can be faster.
    pub fma_bound_us: f64,
}

impl Prediction {
    /// Times `model` on `rows` (row-major, the model's input length).
    pub fn measure(model: &PoseModel, rows: &[f32]) -> Result<Self> {
        let dim = model.input_dim();
        let n = (rows.len() / dim.max(1)).max(1) as f64;
        let best = |f: &mut dyn FnMut() -> Result<()>| -> Result<f64> {
            let mut best = f64::INFINITY;
            for _ in 0..5 {
                let t = Instant::now();
                f()?;
                best = best.min(t.elapsed().as_secs_f64() * 1e6 / n);
            }
            Ok(best)
        };
        let one_us = best(&mut || {
            for row in rows.chunks_exact(dim) {
                std::hint::black_box(model.predict(row)?);
            }
            Ok(())
        })?;
        let batch_us = best(&mut || {
            std::hint::black_box(model.predict_rows(rows)?);
            Ok(())
        })?;
        let ops = model.multiply_adds();
        Ok(Self {
            one_us,
            batch_us,
            multiply_adds_f64: ops.0,
            multiply_adds_f32: ops.1,
            fma_bound_us: measure_fma_peak(20).seconds(ops) * 1e6,
        })
    }
}

/// Frame -> command latency over a set of frames, microseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Latency {
    /// Whole loop time over the number of frames.
    pub mean_us: f64,
    /// Median of the per-frame times (mean of the two middle ones for an
    /// even count).
    pub median_us: f64,
    /// 95th percentile of the per-frame times, nearest rank.
    pub p95_us: f64,
    /// Median over frames of blob detection alone (timed in a pass of its
    /// own).
    pub detect_median_us: f64,
    /// Median over frames of the prediction (both nets) alone.
    pub predict_median_us: f64,
    /// Median and 95th percentile (nearest rank) of the per-frame thread
    /// CPU time, microseconds: the frame's time on a core, without the
    /// time it waited for one (0 where the clock is not available).
    pub cpu_median_us: f64,
    pub cpu_p95_us: f64,
}

impl Latency {
    /// Statistics of the per-frame times `samples` (any order), with the
    /// loop's mean given; all zero without samples. The parts' medians are
    /// zero (see [`tactrace_calib::median`]).
    pub fn from_samples(mean_us: f64, samples: Vec<f64>) -> Self {
        Self {
            mean_us,
            median_us: median(&samples),
            p95_us: p95(samples),
            detect_median_us: 0.0,
            predict_median_us: 0.0,
            cpu_median_us: 0.0,
            cpu_p95_us: 0.0,
        }
    }
}

/// 95th percentile of `samples` (any order), nearest rank; 0 without
/// samples.
pub fn p95(mut samples: Vec<f64>) -> f64 {
    samples.sort_unstable_by(f64::total_cmp);
    let n = samples.len();
    let rank = (0.95 * n as f64).ceil() as usize;
    if n == 0 {
        0.0
    } else {
        samples[rank.clamp(1, n) - 1]
    }
}

/// This thread's CPU time so far, microseconds (its CPU-time clock,
/// `CLOCK_THREAD_CPUTIME_ID`); `None` where there is none.
pub fn thread_cpu_us() -> Option<f64> {
    #[cfg(unix)]
    {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes one timespec into `t`, which lives
        // here for the call.
        let read = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
        (read == 0).then_some(t.tv_sec as f64 * 1e6 + t.tv_nsec as f64 * 1e-3)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Median of `samples` (any order; mean of the two middle ones for an even
/// count, [`tactrace_calib::median`]), 0 without samples.
fn median(samples: &[f64]) -> f64 {
    tactrace_calib::median(samples).unwrap_or(0.0)
}

/// Time `taps` simulated taps on the disk edge, and the control loop when a
/// model is given.
pub fn bench(rig: &RigConfig, taps: usize, model: Option<&PoseModel>) -> Result<BenchFigures> {
    let sensor = TacTipModel::new(rig.sensor.clone())?;
    let reference = sensor.render(sensor.rest_pins(), None);
    let extractor = PinReader::from_reference_frame(
        DetectorParams::Blobs(rig.blob.clone()).check()?,
        &reference,
    )?;
    bench_with(&sensor, &extractor, None, rig, taps, model)
}

/// As [`bench()`] with a calibrated sensor (`--sensor`): its taps, seen
/// against its own reference pins with its detector (blob or small-pin:
/// [`crate::sim_sight::of_sensor`]), over its own label range.
pub fn bench_calibrated(
    folder: &SensorFolder,
    rig: &RigConfig,
    taps: usize,
    model: Option<&PoseModel>,
) -> Result<BenchFigures> {
    let extractor = crate::sim_sight::of_sensor(folder)?.reader;
    // The sensor's own pose (no mount): the labels' tip pose.
    let convention = LabelConvention {
        mount_yaw_deg: 0.0,
        ..folder.label_convention()
    };
    bench_with(
        &folder.model()?,
        &extractor,
        Some(&convention),
        rig,
        taps,
        model,
    )
}

fn bench_with(
    sensor: &TacTipModel,
    extractor: &PinReader,
    labels: Option<&LabelConvention>,
    rig: &RigConfig,
    taps: usize,
    model: Option<&PoseModel>,
) -> Result<BenchFigures> {
    let disk = builtin_shape(BuiltinShape::Disk);
    let (edge, normal) = disk.at_arc_length(0.0);
    let poses: Vec<_> = (0..taps)
        .map(|i| {
            let u = i as f64 / taps.max(1) as f64;
            let (r, theta) = (-5.0 + 10.0 * u, -45.0 + 90.0 * ((u * 7.0) % 1.0));
            let at = LabelConvention::edge_pose_of(labels, r, theta);
            pose_at_edge(edge, normal, at.0, at.1, -rig.tap.nominal_indentation_mm())
        })
        .collect();
    let t0 = Instant::now();
    let frames: Vec<_> = poses
        .iter()
        .map(|p| sensor.render(&sensor.pins(&disk, *p, None), None))
        .collect();
    let simulate = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let mut disps = Vec::with_capacity(taps);
    for f in &frames {
        let tracked = extractor.read_grey(f)?;
        disps.push(tracked.displacement(extractor.tracker().reference()));
    }
    let extract = t1.elapsed().as_secs_f64();
    let latency = model
        .map(|m| control_loop(extractor, m, &frames))
        .transpose()?;
    let prediction = model
        .map(|m| Prediction::measure(m, &disps.concat()))
        .transpose()?;
    let n = taps.max(1) as f64;
    Ok(BenchFigures {
        taps,
        simulate_us: simulate * 1e6 / n,
        extract_us: extract * 1e6 / n,
        taps_per_second: n / (simulate + extract),
        control_latency_us: latency.map(|l| l.mean_us),
        control_latency_median_us: latency.map(|l| l.median_us),
        control_latency_p95_us: latency.map(|l| l.p95_us),
        prediction,
    })
}

/// Frame -> command latency on real frames: the `.png` frames of `frames`
/// (Bristol layout, reference `init_0.png`), up to `limit` of them, through
/// the `blob` preset's detection, ordering, `model` and the controller:
/// mean, median and 95th percentile of the per-frame times, microseconds;
/// frames are read before the clock starts.
pub fn real_control_latency_stats(
    frames: &std::path::Path,
    blob: &tactrace_vision::BlobParams,
    model: &PoseModel,
    limit: usize,
) -> Result<Latency> {
    let reference = tactrace_sensor::read_frame(&frames.join("init_0.png"))?;
    let reader =
        PinReader::from_reference_frame(DetectorParams::Blobs(blob.clone()).check()?, &reference)?;
    control_loop(&reader, model, &real_frames(frames, limit)?)
}

/// As [`real_control_latency_stats`] for a sensor of any kind: its frames
/// read through the sensor settings `sight` (preprocessing and detector,
/// as `import` reads them) against the rest pins `rest` (the model's
/// reference pins), timed from the grey frame.
pub fn real_control_latency_sight(
    frames: &std::path::Path,
    sight: tactrace_vision::SightParams,
    rest: Vec<[f64; 2]>,
    model: &PoseModel,
    limit: usize,
) -> Result<Latency> {
    let images = real_frames(frames, limit)?;
    let (w, h) = images.first().map_or((0, 0), |f| f.dimensions());
    let reader = PinReader::new(sight.check(w, h)?, rest)?;
    control_loop(&reader, model, &images)
}

/// Up to `limit` `.png` frames of `frames` in name order (not the
/// undeformed `init_0.png`), grey.
fn real_frames(frames: &std::path::Path, limit: usize) -> Result<Vec<tactrace_sensor::Frame>> {
    let mut paths: Vec<_> = std::fs::read_dir(frames)
        .map_err(tactrace_store::read_err(frames))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "png") && !p.ends_with("init_0.png"))
        .collect();
    paths.sort();
    paths.truncate(limit.max(1));
    Ok(paths
        .iter()
        .map(|p| tactrace_sensor::read_frame(p))
        .collect::<std::result::Result<Vec<_>, _>>()?)
}

/// Time from frame to command over `frames`, microseconds: extract and
/// order the pins, predict (r, theta), one controller step. Every frame is
/// timed on its own (for the median and 95th percentile) as well as the
/// whole loop (for the mean); the prediction within it, and blob detection
/// in a pass of its own (its median; ordering is the rest).
fn control_loop(
    extractor: &PinReader,
    model: &PoseModel,
    frames: &[tactrace_sensor::Frame],
) -> Result<Latency> {
    let mut ctl = PbtsController::new(PbtsConfig::default());
    let mut per_frame = Vec::with_capacity(frames.len());
    let mut cpu = Vec::with_capacity(frames.len());
    let mut predict = Vec::with_capacity(frames.len());
    let t0 = Instant::now();
    for f in frames {
        let c = thread_cpu_us();
        let t = Instant::now();
        let tracked = extractor.read_grey(f)?;
        let displacement = tracked.displacement(extractor.tracker().reference());
        let tp = Instant::now();
        let [r, theta] = model.predict(&displacement)?;
        predict.push(tp.elapsed().as_secs_f64() * 1e6);
        std::hint::black_box(ctl.step(SensedPose {
            r_mm: r,
            theta_deg: theta,
        }));
        per_frame.push(t.elapsed().as_secs_f64() * 1e6);
        if let (Some(a), Some(b)) = (c, thread_cpu_us()) {
            cpu.push(b - a);
        }
    }
    let mean = t0.elapsed().as_secs_f64() * 1e6 / frames.len().max(1) as f64;
    let detect: Vec<f64> = frames
        .iter()
        .map(|f| {
            let t = Instant::now();
            std::hint::black_box(extractor.detect_grey(f).ok());
            t.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    Ok(Latency {
        detect_median_us: median(&detect),
        predict_median_us: median(&predict),
        cpu_median_us: median(&cpu),
        cpu_p95_us: p95(cpu),
        ..Latency::from_samples(mean, per_frame)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_nearest_rank_p95() {
        let l = Latency::from_samples(9.0, vec![5.0, 1.0, 4.0, 2.0, 3.0]);
        assert_eq!((l.median_us, l.p95_us), (3.0, 5.0));
        let samples: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        let l = Latency::from_samples(0.0, samples);
        assert_eq!((l.median_us, l.p95_us), (50.5, 95.0));
        let l = Latency::from_samples(0.0, Vec::new());
        assert_eq!((l.median_us, l.p95_us), (0.0, 0.0));
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(p95(vec![3.0, 1.0, 2.0]), 3.0);
    }

    /// The thread's CPU clock runs while the thread works: a busy loop
    /// moves it by a millisecond within ten seconds of wall time, never
    /// backwards, and a sleep moves it by far less than it sleeps.
    #[cfg(unix)]
    #[test]
    fn thread_cpu_time_counts_work_not_waiting() {
        let start = thread_cpu_us().expect("a thread CPU clock on unix");
        let wall = Instant::now();
        let (mut last, mut spins) = (start, 0u64);
        while last - start < 1000.0 && wall.elapsed().as_secs() < 10 {
            spins = std::hint::black_box(spins.wrapping_add(1));
            let now = thread_cpu_us().expect("clock");
            assert!(now >= last, "the clock went back: {last} -> {now}");
            last = now;
        }
        assert!(last - start >= 1000.0, "{} us of CPU in 10 s", last - start);
        let before = thread_cpu_us().expect("clock");
        std::thread::sleep(std::time::Duration::from_millis(50));
        let slept = thread_cpu_us().expect("clock") - before;
        assert!(slept < 25_000.0, "{slept} us of CPU while asleep 50 ms");
    }

    /// A PDenNN (two nets on one 35-component projection of 254 inputs,
    /// 50 hidden units) on a few random rows.
    fn small_pdennn() -> PoseModel {
        use rand::{Rng, SeedableRng};
        use tactrace_learn::{Dataset, ModelConfig, ModelKind, Preset};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        let (n, dim) = (200, 254);
        let x = (0..n * dim).map(|_| rng.random_range(-1.0..1.0)).collect();
        let y = (0..2 * n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let data = Dataset::new(x, y, n, dim, 2).expect("data");
        let mut cfg = ModelConfig::preset(ModelKind::PDenNN, Preset::Default);
        cfg.set_epochs(1);
        for net in [&mut cfg.position, &mut cfg.angle].into_iter().flatten() {
            net.hidden = vec![50];
            net.n_components = Some(35);
        }
        PoseModel::fit(&cfg, &data, &mut |_| {}).expect("fit").0
    }

    /// `bench` with a model times its prediction against the multiply-adds
    /// it counts: the projection once (both nets share it), every layer of
    /// both nets.
    #[test]
    fn bench_times_the_prediction_against_its_multiply_adds() {
        let model = small_pdennn();
        let f = bench(&RigConfig::default(), 3, Some(&model)).expect("bench");
        let p = f.prediction.expect("prediction figures with a model");
        assert_eq!(p.multiply_adds_f64, 35 * 254);
        assert_eq!(p.multiply_adds_f32, 2 * (35 * 50 + 50));
        for t in [p.one_us, p.batch_us, p.fma_bound_us] {
            assert!(t.is_finite() && t > 0.0, "{p:?}");
        }
        assert!(bench(&RigConfig::default(), 3, None)
            .expect("bench")
            .prediction
            .is_none());
    }
}
