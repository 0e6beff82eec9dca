//! Blob detection on frames that binarise to the same image at every
//! threshold (report ch. 4.1). The real TacTip frames and tactrace's
//! simulated ones are already binary (0 or 255), so every threshold of the
//! sweep sees the same white set, traces the same contours and finds the
//! same centres. The contours are then found and measured once, from the
//! frame's pixel runs (`runs.rs`), and the grouping across thresholds is built directly when
//! it is trivial: when no two centres are close enough to join each other's
//! group, OpenCV's rule gives every centre a group of its own holding one
//! copy of it per threshold. Otherwise the general grouping runs on the one
//! list of centres. Same keypoints, bit for bit, as the threshold-by-threshold
//! path (see the tests here and `detect_blobs`).

use crate::blob::{KeyPoint, Radius};
use crate::grouping::{joins, keypoint_of, Centre, Grouper};
use crate::params::BlobParams;
use crate::row_bits::any_in_span;
use crate::runs::RunDetector;

/// Whether every level in `lo..=hi` binarises `pixels` (white above the
/// level) to the same image: no pixel value lies in `(lo, hi]`.
pub(crate) fn same_at_levels(pixels: &[u8], lo: i16, hi: i16) -> bool {
    if hi <= lo {
        return true;
    }
    if hi - lo > 255 {
        return pixels.is_empty();
    }
    // v in (lo, hi] <=> v - (lo + 1) < hi - lo, wrapping in u8 (lo >= -1).
    let (base, span) = ((lo + 1) as u8, (hi - lo) as u8);
    !any_in_span(pixels, base, span)
}

/// [`crate::detect_blobs`] for a frame of `size` (width, height) that
/// binarises the same at all `levels` (the floors of the thresholds, see
/// [`same_at_levels`]): the contours found from the pixel runs and measured
/// once at `levels[0]` (`runs.rs`; the same list as tracing the whole
/// binarised frame), then the grouping of `levels.len()` identical lists.
///
/// With `radius` [`Radius::Bound`] (`crate::blob::detect_blob_centres`)
/// the blobs' radii are bounded, not measured, and when with those bounds
/// no two blobs join each other's group (a positive
/// `min_dist_between_blobs` makes each join its own), OpenCV's grouping is
/// the trivial one whatever the exact radii (each at or under its bound),
/// so the keypoints are the same but for their sizes, left NaN. Otherwise
/// the sizes are measured and the grouping runs as with
/// [`Radius::Median`].
pub(crate) fn detect_unchanging(
    pixels: &[u8],
    size: [usize; 2],
    levels: &[i16],
    p: &BlobParams,
    radius: Radius,
) -> Vec<KeyPoint> {
    let Some(&level) = levels.first() else {
        return Vec::new();
    };
    let found = found_centres(pixels, size, level, p, radius);
    let (n, min_dist) = (levels.len(), f64::from(p.min_dist_between_blobs));
    let trivial = apart(&found, min_dist);
    match radius {
        _ if trivial && n < p.min_repeatability => Vec::new(),
        Radius::Median if trivial => one_group_each(&found, n, |c| c.radius),
        Radius::Bound if trivial && min_dist > 0.0 => one_group_each(&found, n, |_| f64::NAN),
        Radius::Bound => detect_unchanging(pixels, size, levels, p, Radius::Median),
        Radius::Median => {
            let mut grouper = Grouper::new(size[0], size[1], n);
            for _ in 0..n {
                grouper.add(&found, min_dist);
            }
            grouper.keypoints(p.min_repeatability)
        }
    }
}

/// The keypoints of `found` when each centre is a group of its own `n`
/// copies, with the representative radius `radius` gives.
fn one_group_each(found: &[Centre], n: usize, radius: impl Fn(&Centre) -> f64) -> Vec<KeyPoint> {
    found
        .iter()
        .map(|c| keypoint_of(std::iter::repeat_n(*c, n), radius(c)))
        .collect()
}

/// The centres of the blobs that pass every filter at `level`, in
/// OpenCV's contour order (the reverse of discovery in raster order).
fn found_centres(
    pixels: &[u8],
    size: [usize; 2],
    level: i16,
    p: &BlobParams,
    radius: Radius,
) -> Vec<Centre> {
    RUNS.with_borrow_mut(|runs| runs.centres(pixels, size, level, p, radius))
}

thread_local! {
    /// The run-based contour finder's buffers (its binary frame, runs and
    /// points), kept between frames.
    static RUNS: std::cell::RefCell<RunDetector> = std::cell::RefCell::new(RunDetector::default());
}

/// True when the grouping of the same `found` list at every threshold is
/// trivial: all centres finite, each would join a group it represents
/// (distance 0 below `min_dist` or its radius), and no two would join each
/// other's group. Then, threshold after threshold, centre `i`'s first
/// joining group is group `i` (every earlier group still has copies of its
/// own centre only, so its representative is that centre).
fn apart(found: &[Centre], min_dist: f64) -> bool {
    let finite = |c: &Centre| c.x.is_finite() && c.y.is_finite() && c.radius.is_finite();
    if !found
        .iter()
        .all(|c| finite(c) && joins(c, c, min_dist, 0.0))
    {
        return false;
    }
    // Any pair farther apart than this on one axis cannot join.
    let reach = found.iter().map(|c| c.radius).fold(min_dist, f64::max);
    let mut by_x: Vec<&Centre> = found.iter().collect();
    by_x.sort_unstable_by(|a, b| a.x.total_cmp(&b.x));
    for (i, a) in by_x.iter().enumerate() {
        for b in &by_x[i + 1..] {
            if b.x - a.x > reach {
                break;
            }
            if joins(a, b, min_dist, reach) {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blob::detect_blobs_by_threshold;
    use crate::Frame;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn levels_test_finds_values_in_the_open_closed_range() {
        let pixels = [0u8, 10, 200, 255];
        assert!(same_at_levels(&pixels, 10, 199));
        assert!(!same_at_levels(&pixels, 9, 199));
        assert!(!same_at_levels(&pixels, 10, 200));
        assert!(same_at_levels(&pixels, 200, 254));
        assert!(!same_at_levels(&pixels, -1, 255));
        assert!(same_at_levels(&pixels, 5, 5));
        assert!(!same_at_levels(&pixels, -1, 0));
    }

    /// The test by 64-value blocks (vector compares) is the value-by-value
    /// definition for every pair of levels, on frames of any length.
    #[test]
    fn levels_test_by_blocks_equals_value_by_value() {
        let mut rng = ChaCha8Rng::seed_from_u64(64);
        for _ in 0..3000 {
            let n = rng.random_range(0..300);
            let common: u8 = rng.random();
            let mut pixels: Vec<u8> = (0..n)
                .map(|_| {
                    if rng.random_bool(0.9) {
                        common
                    } else {
                        255 - common
                    }
                })
                .collect();
            if n > 0 && rng.random_bool(0.5) {
                let at = rng.random_range(0..n);
                pixels[at] = rng.random();
            }
            let lo = rng.random_range(-1..256i16);
            let hi = rng.random_range(lo..256i16);
            let want = pixels
                .iter()
                .all(|&v| !(i16::from(v) > lo && i16::from(v) <= hi));
            assert_eq!(same_at_levels(&pixels, lo, hi), want, "{lo} {hi}");
        }
    }

    /// Random binary frames of discs (some touching, some at the border,
    /// some with holes): the direct path gives exactly the keypoints of
    /// the threshold-by-threshold one, for several merge distances.
    #[test]
    fn binary_frames_match_the_threshold_loop() {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let (mut branches, mut unmeasured) = ([0; 2], [0; 2]);
        for case in 0..100 {
            let size = rng.random_range(20..90u32);
            let discs: Vec<(f64, f64, f64, f64)> = (0..rng.random_range(0..25))
                .map(|_| {
                    let r = rng.random_range(1.0..7.0);
                    let hole = if rng.random_bool(0.2) { r * 0.4 } else { -1.0 };
                    let at = |rng: &mut ChaCha8Rng| rng.random_range(-3.0..f64::from(size) + 3.0);
                    (at(&mut rng), at(&mut rng), r, hole)
                })
                .collect();
            let frame = Frame::from_fn(size, size, |x, y| {
                let white = discs.iter().any(|&(cx, cy, r, hole)| {
                    let d = (f64::from(x) - cx).hypot(f64::from(y) - cy);
                    d <= r && d > hole
                });
                image::Luma([if white { 255 } else { 0 }])
            });
            // Dark blobs too: a ring's outer and hole borders then both
            // pass, with nearly the same centre (the fallback grouping).
            let p = BlobParams {
                blob_color: if rng.random_bool(0.3) { 0 } else { 255 },
                min_area: 2.0,
                min_convexity: 0.5,
                min_circularity: 0.3,
                min_dist_between_blobs: rng.random_range(0.0..20.0),
                ..BlobParams::preset("real256").expect("preset")
            };
            let levels: Vec<i16> = p.thresholds().iter().map(|t| t.floor() as i16).collect();
            let want = detect_blobs_by_threshold(&frame, &p);
            let at = [size as usize; 2];
            let got = detect_unchanging(frame.as_raw(), at, &levels, &p, Radius::Median);
            assert_eq!(got, want, "case {case}");
            let at = [size as usize; 2];
            let found = found_centres(frame.as_raw(), at, levels[0], &p, Radius::Median);
            let min_dist = f64::from(p.min_dist_between_blobs);
            branches[usize::from(apart(&found, min_dist))] += usize::from(!found.is_empty());
            check_centres_only(&frame, &p, &want, &mut unmeasured);
        }
        // Both the direct grouping and the fallback were exercised, and
        // the centres-only path both skipped sizes and measured them.
        assert!(branches.iter().all(|&b| b >= 10), "{branches:?}");
        assert!(unmeasured.iter().all(|&b| b >= 10), "{unmeasured:?}");
    }

    /// `detect_blob_centres` gives `want`'s centres bit for bit, in order,
    /// with every size NaN or all of them `want`'s; counts which in
    /// `unmeasured` ([measured, NaN]).
    fn check_centres_only(
        frame: &Frame,
        p: &BlobParams,
        want: &[KeyPoint],
        unmeasured: &mut [usize; 2],
    ) {
        let got = crate::blob::detect_blob_centres(frame, p);
        let bits = |k: &KeyPoint| (k.x.to_bits(), k.y.to_bits());
        assert_eq!(
            got.iter().map(bits).collect::<Vec<_>>(),
            want.iter().map(bits).collect::<Vec<_>>()
        );
        if got.iter().all(|k| k.size.is_nan()) && !got.is_empty() {
            unmeasured[1] += 1;
        } else {
            assert_eq!(got, want, "measured sizes");
            unmeasured[0] += usize::from(!got.is_empty());
        }
    }

    /// The radius bound of the centres-only path is at or above OpenCV's
    /// median radius, on every blob of random frames (holes, specks,
    /// strokes and all).
    #[test]
    fn the_radius_bound_is_never_under_the_median() {
        let mut rng = ChaCha8Rng::seed_from_u64(2211);
        let p = BlobParams {
            filter_by_area: false,
            filter_by_circularity: false,
            filter_by_convexity: false,
            filter_by_inertia: false,
            ..BlobParams::preset("real256").expect("preset")
        };
        let mut blobs = 0;
        for _ in 0..1000 {
            let (w, h) = (rng.random_range(1..40usize), rng.random_range(1..40usize));
            let px: Vec<u8> = (0..w * h)
                .map(|_| if rng.random_bool(0.2) { 255 } else { 0 })
                .collect();
            let exact = found_centres(&px, [w, h], 127, &p, Radius::Median);
            let bound = found_centres(&px, [w, h], 127, &p, Radius::Bound);
            assert_eq!(exact.len(), bound.len());
            for (e, b) in exact.iter().zip(&bound) {
                assert_eq!((e.x, e.y, e.confidence), (b.x, b.y, b.confidence));
                assert!(b.radius >= e.radius, "{} < {}", b.radius, e.radius);
            }
            blobs += exact.len();
        }
        assert!(blobs > 3000, "{blobs} blobs");
    }
}
