//! Set-ups shared by the ordering tests on the shared real sets
//! (`speed.rs`, `cut_field.rs`): frames read from a folder, the largest pin
//! difference between two orderings, the 127-pin edge set's extractor
//! beside one whose tracker is changed, and the 331-pin shear set read as the
//! inspection proposes; and the 331-pin ring layout of the synthetic
//! ordering tests (`cut_field.rs`, `nn_start.rs`, `speed_cuts.rs`) and their
//! synthetic taps' merged and missed pins. Not every file that shares
//! it uses every set-up.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use tactrace_vision::{
    estimate_rest, inspect, BlobParams, Detection, Frame, PinExtractor, PinTracker, RestParams,
    SightParams, Tracked,
};

/// The image at `path`, or a panic naming it.
pub fn load(path: &Path) -> image::DynamicImage {
    image::open(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// The `.png` files of `dir` whose names start with `prefix`, sorted.
pub fn pngs(dir: &Path, prefix: &str) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("frames folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            name.starts_with(prefix) && name.ends_with(".png")
        })
        .collect();
    out.sort();
    out
}

/// Largest coordinate difference between two orderings, px (infinite when
/// their pin counts or matched flags differ).
pub fn difference(a: &Tracked, b: &Tracked) -> f64 {
    if a.pins.len() != b.pins.len() || a.matched != b.matched {
        return f64::INFINITY;
    }
    a.pins
        .iter()
        .zip(&b.pins)
        .flat_map(|(p, q)| [(p[0] - q[0]).abs(), (p[1] - q[1]).abs()])
        .fold(0.0, f64::max)
}

/// About `k` of `paths`, evenly spaced.
fn every(paths: &[PathBuf], k: usize) -> Vec<PathBuf> {
    let step = paths.len().div_ceil(k).max(1);
    paths.iter().step_by(step).cloned().collect()
}

/// The 331-pin shear set `set` read as the inspection of 20 train frames
/// proposes: the detections of 600 held-out val frames and the rest layout
/// estimated from 150 train taps.
pub fn shear_set_331(set: &Path) -> (Vec<(PathBuf, Detection)>, Vec<[f64; 2]>) {
    let train = pngs(&set.join("train/frames"), "image_");
    let val = pngs(&set.join("val/frames"), "image_");
    let sample: Vec<Frame> = every(&train, 20)
        .iter()
        .map(|p| load(p).to_luma8())
        .collect();
    let found = inspect(&sample, None).expect("inspection");
    let first = load(&train[0]);
    let detector = SightParams {
        preprocess: found.preprocess.clone(),
        detect: found.detect.clone(),
    }
    .check(first.width(), first.height())
    .expect("proposal");
    let detect = |p: &PathBuf| detector.detect(&load(p)).expect("detect");
    let fitting: Vec<Detection> = every(&train, 150).iter().map(detect).collect();
    let rest = estimate_rest(&fitting, found.pins, &RestParams::default()).expect("rest");
    let held = every(&val, 600)
        .into_iter()
        .map(|p| {
            let d = detect(&p);
            (p, d)
        })
        .collect();
    (held, rest.pins)
}

/// The 331-pin ring layout: a centre pin and ten rings of 6k pins, 5 px
/// apart, centred at (64, 64) (`cut_field.rs`, `nn_start.rs`).
pub fn rings() -> Vec<[f64; 2]> {
    let mut pins = vec![[64.0, 64.0]];
    for k in 1..=10 {
        let count = 6 * k;
        for m in 0..count {
            let a = std::f64::consts::TAU * f64::from(m) / f64::from(count);
            let r = 5.0 * f64::from(k);
            pins.push([64.0 + r * a.cos(), 64.0 + r * a.sin()]);
        }
    }
    pins
}

/// A synthetic tap's keypoints from its pin `points`: up to `max_merges`
/// neighbouring pairs merged into one blob (touching pins), each other pin
/// kept with probability `keep` (missed pins), in a scrambled order.
pub fn merged_dropped_shuffled(
    mut points: Vec<[f64; 2]>,
    max_merges: usize,
    keep: f64,
    rng: &mut impl rand::Rng,
) -> Vec<tactrace_vision::KeyPoint> {
    for _ in 0..rng.random_range(0..max_merges) {
        let i = rng.random_range(0..points.len() - 1);
        let (a, b) = (points[i], points[i + 1]);
        points[i] = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        points[i + 1] = [f64::NAN, f64::NAN];
    }
    let mut keypoints: Vec<tactrace_vision::KeyPoint> = points
        .iter()
        .filter(|p| p[0].is_finite() && rng.random_bool(keep))
        .map(|p| tactrace_vision::KeyPoint {
            x: p[0],
            y: p[1],
            size: 2.5,
        })
        .collect();
    keypoints.sort_by_key(|k| (k.x * 7919.0) as i64 % 331);
    keypoints
}

/// The shared 127-pin edge set read as `PinExtractor::extract` reads it
/// (the real256 preset over its rest frame `init_0.png`), a second
/// extractor over the same reference whose tracker `change` makes, and
/// the set's tap frames (more than 3700); `None` where the set is absent
/// (said by `tactrace_testdata::real_edge_set`).
pub fn real_127_extractors(
    change: impl FnOnce(PinTracker) -> PinTracker,
) -> Option<(PinExtractor, PinExtractor, Vec<PathBuf>)> {
    let dir = tactrace_testdata::real_edge_set()?.join("frames");
    let params = BlobParams::preset("real256").expect("preset");
    let reference = load(&dir.join("init_0.png")).to_luma8();
    let usual = PinExtractor::from_reference_frame(&reference, params.clone()).expect("reference");
    let mut changed = PinExtractor::from_reference_frame(&reference, params).expect("reference");
    changed.tracker = change(changed.tracker);
    let frames = pngs(&dir, "frame_");
    assert!(frames.len() > 3700, "{} frames", frames.len());
    Some((usual, changed, frames))
}
