//! The fast paths of pin ordering give the results of the slow ones on the
//! shared real sets (issue 21, item 6): the tracker's nearest-neighbour
//! start (`tracker/grid.rs`) against every coarse-to-fine stage from the
//! centroid shift. Fails when the data is absent unless
//! TACTRACE_SKIP_REAL_DATA=1 (see `tactrace_testdata`).

use std::path::{Path, PathBuf};

use tactrace_vision::{
    estimate_rest, inspect, BlobParams, Detection, Frame, PinExtractor, PinTracker, RestParams,
    SightParams, Tracked,
};

fn load(path: &Path) -> image::DynamicImage {
    image::open(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// The `.png` files of `dir` whose names start with `prefix`, sorted.
fn pngs(dir: &Path, prefix: &str) -> Vec<PathBuf> {
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
fn difference(a: &Tracked, b: &Tracked) -> f64 {
    if a.pins.len() != b.pins.len() || a.matched != b.matched {
        return f64::INFINITY;
    }
    a.pins
        .iter()
        .zip(&b.pins)
        .flat_map(|(p, q)| [(p[0] - q[0]).abs(), (p[1] - q[1]).abs()])
        .fold(0.0, f64::max)
}

/// Every frame of the shared 127-pin set, detected and ordered as
/// `PinExtractor::extract` does (with the touching-pin split): the same
/// pins, within 1e-6 px, with the nearest-neighbour start as without.
#[test]
fn issue21_nearest_start_orders_every_shared_127_pin_frame_as_before() {
    let Some(set) = tactrace_testdata::real_edge_set() else {
        return;
    };
    let dir = set.join("frames");
    let params = BlobParams::preset("real256").expect("preset");
    let reference = load(&dir.join("init_0.png")).to_luma8();
    let fast = PinExtractor::from_reference_frame(&reference, params.clone()).expect("reference");
    let mut slow = PinExtractor::from_reference_frame(&reference, params).expect("reference");
    slow.tracker = slow.tracker.with_nearest_start(false);
    let frames = pngs(&dir, "frame_");
    assert!(frames.len() > 3700, "{} frames", frames.len());
    for path in &frames {
        let frame: Frame = load(path).to_luma8();
        let (a, b) = (fast.extract(&frame), slow.extract(&frame));
        match (a, b) {
            (Ok(a), Ok(b)) => {
                let d = difference(&a, &b);
                assert!(d <= 1e-6, "{}: pins differ by {d} px", path.display());
            }
            (a, b) => assert_eq!(a.is_ok(), b.is_ok(), "{}", path.display()),
        }
    }
}

/// 600 held-out frames of the 331-pin shear set (val part), read as the
/// inspection proposes against the rest layout estimated from 150 taps of
/// the train part: the same pins with the nearest-neighbour start as
/// without.
#[test]
fn issue21_nearest_start_orders_331_pin_frames_as_before() {
    let Some(set) = tactrace_testdata::shared_set("tactip331-edge2d-shear", "README.md") else {
        return;
    };
    let train = pngs(&set.join("train/frames"), "image_");
    let val = pngs(&set.join("val/frames"), "image_");
    let every = |paths: &[PathBuf], k: usize| -> Vec<PathBuf> {
        let step = paths.len().div_ceil(k).max(1);
        paths.iter().step_by(step).cloned().collect()
    };
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
    let fast = PinTracker::new(rest.pins.clone()).expect("tracker");
    let slow = PinTracker::new(rest.pins)
        .expect("tracker")
        .with_nearest_start(false);
    for path in every(&val, 600) {
        let detection = detect(&path);
        let d = difference(&fast.track(&detection), &slow.track(&detection));
        assert!(d <= 1e-6, "{}: pins differ by {d} px", path.display());
    }
}
