//! The blob detector's path for binary frames (`detect_blobs`: contours
//! from pixel runs, `runs.rs`, and the grouping built once, `binary.rs`)
//! against the reference, the frame binarised and traced threshold by
//! threshold (`detect_blobs_by_threshold`): the same keypoints, bit for
//! bit, on synthetic frames and on every frame of the shared 127-pin set;
//! and the tracker's detection (the centres only, the sizes left
//! unmeasured) against it on every frame of both shared 127-pin sets.
//! The shared-set test fails when the data is absent unless
//! TACTRACE_SKIP_REAL_DATA=1 (see `tactrace_testdata`).

use crate::common;

use common::{load, pngs};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_vision::{
    detect_blobs, detect_blobs_by_threshold, BlobParams, Detector, Frame, KeyPoint, PinReader,
};

/// Bit patterns of every keypoint, so that -0.0 / 0.0 or NaNs cannot hide
/// a difference.
fn bits(points: &[KeyPoint]) -> Vec<[u64; 3]> {
    points
        .iter()
        .map(|k| [k.x.to_bits(), k.y.to_bits(), k.size.to_bits()])
        .collect()
}

/// A binary frame of a hexagonal grid of small discs, sheared and with
/// touching pins, dropped pins, a rim arc with holes and specks.
fn pin_frame(rng: &mut ChaCha8Rng, size: u32) -> Frame {
    let spacing = rng.random_range(6.0..14.0);
    let shear = rng.random_range(-0.3..0.3);
    let mut discs = Vec::new();
    let n = (f64::from(size) / spacing) as i32 + 2;
    for j in -1..n {
        for i in -1..n {
            let x = (f64::from(i) + 0.5 * f64::from(j % 2)) * spacing;
            let y = f64::from(j) * spacing * 0.866;
            let r: f64 = rng.random_range(1.0..spacing * 0.55);
            if rng.random_bool(0.95) {
                discs.push((x + shear * y, y, r));
            }
        }
    }
    let centre = f64::from(size) / 2.0;
    let rim = (centre * 0.9, centre * 0.97);
    let mut frame = Frame::from_fn(size, size, |x, y| {
        let (fx, fy) = (f64::from(x), f64::from(y));
        let d = (fx - centre).hypot(fy - centre);
        let on_rim = d > rim.0 && d < rim.1 && (fx * 0.7 + fy).sin() > -0.5;
        let in_pin = discs
            .iter()
            .any(|&(cx, cy, r)| (fx - cx).hypot(fy - cy) <= r);
        image::Luma([if on_rim || (in_pin && d < rim.0) {
            255
        } else {
            0
        }])
    });
    for _ in 0..rng.random_range(0..60) {
        let (x, y) = (rng.random_range(0..size), rng.random_range(0..size));
        let v = frame.get_pixel(x, y).0[0];
        frame.put_pixel(x, y, image::Luma([255 - v]));
    }
    frame
}

/// Synthetic binary frames under several presets and merge distances
/// (white and dark blobs): the run-based path gives the threshold-by-
/// threshold tracer's keypoints exactly.
#[test]
fn run_detector_equals_the_traced_detector_on_synthetic_frames() {
    let mut rng = ChaCha8Rng::seed_from_u64(2121);
    let mut found = 0;
    for case in 0..60 {
        let size = rng.random_range(24..160);
        let frame = pin_frame(&mut rng, size);
        for preset in ["real256", "report", "opencv"] {
            let mut p = BlobParams::preset(preset).expect("preset");
            p.min_dist_between_blobs = rng.random_range(0.5..12.0);
            if rng.random_bool(0.3) {
                p.blob_color = 255 - p.blob_color;
            }
            let want = detect_blobs_by_threshold(&frame, &p);
            let got = detect_blobs(&frame, &p);
            assert_eq!(bits(&got), bits(&want), "case {case} preset {preset}");
            found += got.len();
        }
    }
    assert!(found > 1000, "{found} keypoints compared");
}

/// Every frame of the shared 127-pin set (binary 256 x 256, `real256`):
/// the same keypoints, bit for bit, in the same order.
#[test]
fn run_detector_equals_the_traced_detector_on_every_shared_127_pin_frame() {
    let Some(set) = tactrace_testdata::real_edge_set() else {
        return;
    };
    let dir = set.join("frames");
    let p = BlobParams::preset("real256").expect("preset");
    let frames = pngs(&dir, "");
    assert!(frames.len() > 3700, "{} frames", frames.len());
    let mut pins = 0;
    for path in &frames {
        let frame: Frame = load(path).to_luma8();
        let (got, want) = (
            detect_blobs(&frame, &p),
            detect_blobs_by_threshold(&frame, &p),
        );
        assert_eq!(bits(&got), bits(&want), "{}", path.display());
        pins += got.len();
    }
    eprintln!("{} frames, {pins} keypoints: identical", frames.len());
    assert!(pins > 100 * frames.len(), "{pins} keypoints");
}

/// The detection the pin tracker reads (`PinReader::detect_grey`, the
/// centres only) on every frame of the shared 127-pin edge and surface
/// sets: the keypoints' centres of `detect_blobs` bit for bit, in the same
/// order, and each frame's sizes either all left unmeasured (NaN) or all
/// the same.
#[test]
fn the_trackers_detection_has_the_detectors_centres_on_every_shared_127_pin_frame() {
    let (Some(edge), Some(surface)) = (
        tactrace_testdata::real_edge_set(),
        tactrace_testdata::shared_set("tactip127-surface2d", "targets.csv"),
    ) else {
        return;
    };
    let p = BlobParams::preset("real256").expect("preset");
    let reference: Frame = load(&edge.join("frames/init_0.png")).to_luma8();
    let reader =
        PinReader::from_reference_frame(Detector::Blobs(p.clone()), &reference).expect("reader");
    let mut frames = pngs(&edge.join("frames"), "");
    frames.extend(pngs(&surface.join("frames"), ""));
    let mut unmeasured = 0;
    for path in &frames {
        let frame: Frame = load(path).to_luma8();
        let want = detect_blobs(&frame, &p);
        let got = reader.detect_grey(&frame).expect("detection").points;
        let centre = |k: &KeyPoint| [k.x.to_bits(), k.y.to_bits()];
        let centres = |points: &[KeyPoint]| points.iter().map(centre).collect::<Vec<_>>();
        assert_eq!(centres(&got), centres(&want), "{}", path.display());
        if got.iter().all(|k| k.size.is_nan()) {
            unmeasured += 1;
        } else {
            assert_eq!(bits(&got), bits(&want), "{}", path.display());
        }
    }
    eprintln!(
        "{} frames, {unmeasured} with the sizes unmeasured",
        frames.len()
    );
    assert!(
        frames.len() > 7500 && unmeasured > 7500,
        "{unmeasured} of {}",
        frames.len()
    );
}
