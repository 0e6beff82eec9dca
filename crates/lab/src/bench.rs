//! Throughput and latency figures (`tactrace bench`): simulated taps per
//! second (render + detect + order) and the control-loop latency from frame
//! to command (detect, order, PCA, both nets, controller), as the mean and
//! the per-frame median and 95th percentile. Timings are
//! measured here, never asserted in tests.
use crate::error::Result;
use serde::Serialize;
use std::time::Instant;
use tactrace_control::{PbtsConfig, PbtsController, SensedPose};
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_learn::PoseModel;
use tactrace_sensor::{LabelConvention, TacTipModel};
use tactrace_servo::{pose_at_edge, RigConfig};
use tactrace_store::SensorFolder;
use tactrace_vision::PinExtractor;

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
}

impl Latency {
    /// Statistics of the per-frame times `samples` (any order), with the
    /// loop's mean given; all zero without samples.
    pub fn from_samples(mean_us: f64, mut samples: Vec<f64>) -> Self {
        samples.sort_unstable_by(f64::total_cmp);
        let n = samples.len();
        if n == 0 {
            return Self {
                mean_us,
                median_us: 0.0,
                p95_us: 0.0,
            };
        }
        let rank = (0.95 * n as f64).ceil() as usize;
        Self {
            mean_us,
            median_us: (samples[(n - 1) / 2] + samples[n / 2]) / 2.0,
            p95_us: samples[rank.clamp(1, n) - 1],
        }
    }
}

/// Time `taps` simulated taps on the disk edge, and the control loop when a
/// model is given.
pub fn bench(rig: &RigConfig, taps: usize, model: Option<&PoseModel>) -> Result<BenchFigures> {
    let sensor = TacTipModel::new(rig.sensor.clone())?;
    let reference = sensor.render(sensor.rest_pins(), None);
    let extractor = PinExtractor::from_reference_frame(&reference, rig.blob.clone())?;
    bench_with(&sensor, &extractor, None, rig, taps, model)
}

/// As [`bench()`] with a calibrated sensor (`--sensor`): its taps, seen
/// against its real reference frame with its blob detector, over its own
/// label range.
pub fn bench_calibrated(
    folder: &SensorFolder,
    rig: &RigConfig,
    taps: usize,
    model: Option<&PoseModel>,
) -> Result<BenchFigures> {
    let spec = &folder.spec;
    let extractor = PinExtractor::from_reference_frame(&folder.reference, spec.blob.clone())?;
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
    extractor: &PinExtractor,
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
        let tracked = extractor.extract(f)?;
        disps.push(tracked.displacement(extractor.tracker.reference()));
    }
    let extract = t1.elapsed().as_secs_f64();
    let latency = model
        .map(|m| control_loop(extractor, m, &frames))
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
    let extractor = PinExtractor::from_reference_frame(&reference, blob.clone())?;
    let mut paths: Vec<_> = std::fs::read_dir(frames)
        .map_err(tactrace_store::read_err(frames))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "png") && !p.ends_with("init_0.png"))
        .collect();
    paths.sort();
    paths.truncate(limit.max(1));
    let images = paths
        .iter()
        .map(|p| tactrace_sensor::read_frame(p))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    control_loop(&extractor, model, &images)
}

/// Time from frame to command over `frames`, microseconds: extract and
/// order the pins, predict (r, theta), one controller step. Every frame is
/// timed on its own (for the median and 95th percentile) as well as the
/// whole loop (for the mean).
fn control_loop(
    extractor: &PinExtractor,
    model: &PoseModel,
    frames: &[tactrace_sensor::Frame],
) -> Result<Latency> {
    let mut ctl = PbtsController::new(PbtsConfig::default());
    let mut per_frame = Vec::with_capacity(frames.len());
    let t0 = Instant::now();
    for f in frames {
        let t = Instant::now();
        let tracked = extractor.extract(f)?;
        let [r, theta] = model.predict(&tracked.displacement(extractor.tracker.reference()))?;
        std::hint::black_box(ctl.step(SensedPose {
            r_mm: r,
            theta_deg: theta,
        }));
        per_frame.push(t.elapsed().as_secs_f64() * 1e6);
    }
    let mean = t0.elapsed().as_secs_f64() * 1e6 / frames.len().max(1) as f64;
    Ok(Latency::from_samples(mean, per_frame))
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
    }
}
