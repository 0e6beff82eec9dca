//! Multi-threshold blob detection with the semantics of OpenCV's
//! `SimpleBlobDetector` (report ch. 4.1: the pins are found as white blobs
//! with the appendix's parameters). Per threshold: binarise, trace borders,
//! filter each contour by area, circularity, inertia, convexity and colour;
//! then merge centres across thresholds and keep the repeatable ones.

use serde::{Deserialize, Serialize};

use crate::binary::{detect_unchanging, same_at_levels};
use crate::chain::{border_len, chain_border, chain_moments};
use crate::components::label_components;
use crate::contour::ContourScanner;
use crate::grouping::{Centre, Grouper};
use crate::params::BlobParams;
use crate::runs::Run;
use crate::shape::{
    circularity, hull_area_upper_bound, hull_area_with, median_radius, perimeter,
    perimeter_of_steps, HullScratch, MedianScratch, Moments, Octagon,
};

/// An 8-bit grey camera frame.
pub type Frame = image::GrayImage;

/// A detected blob: centre (x right, y down) and diameter, all in pixels
/// (OpenCV's `KeyPoint.size` convention).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KeyPoint {
    pub x: f64,
    pub y: f64,
    pub size: f64,
}

/// Detects blobs as OpenCV's `SimpleBlobDetector::detect` does.
///
/// Thresholds run from `min_threshold` by `threshold_step` while below
/// `max_threshold`. A centre joins the first existing group whose
/// representative lies closer than `min_dist_between_blobs` or either
/// radius; groups with at least `min_repeatability` members become
/// keypoints at their confidence-weighted mean centre (confidence = inertia
/// ratio squared when filtering by inertia, else 1), size twice the
/// representative's radius. Parameters are used as given: call
/// [`BlobParams::validate`] first.
///
/// Same result as binarising and tracing the whole frame per threshold, but
/// traced per component of the lowest threshold (see `components.rs`); a
/// component is re-traced only when some of its pixels change side, and the
/// blobs are put back in OpenCV's contour order (reverse raster order of the
/// pixel that started each border).
///
/// A frame with no grey level between the first and the last threshold
/// (a binary frame, as the real and simulated TacTip frames are) gives the
/// same image at every threshold and takes a shorter, equivalent path
/// (`binary.rs`): its white pixels read as runs and joined into components
/// in one pass, the components the area filter surely rejects dropped from
/// their runs, each other hole-free component measured from its runs
/// where it has one run a row (`chain.rs`), else its outer border walked
/// from its first pixel, only components with holes traced in a window
/// (`runs.rs`). The same keypoints, bit for bit, as
/// [`detect_blobs_by_threshold`] (tested on synthetic frames and every
/// frame of the shared 127-pin set).
pub fn detect_blobs(img: &Frame, p: &BlobParams) -> Vec<KeyPoint> {
    detect_with(img, p, Radius::Median)
}

/// The keypoints of [`detect_blobs`] with their centres only: the same
/// `x` and `y`, bit for bit, and `size` NaN (not measured) wherever the
/// sizes were not needed to group the blobs: on binary frames whose blobs
/// lie apart (`binary.rs`). What the pin tracker reads (it reads no
/// size), without the median radius of every blob.
pub(crate) fn detect_blob_centres(img: &Frame, p: &BlobParams) -> Vec<KeyPoint> {
    detect_with(img, p, Radius::Bound)
}

/// [`detect_blobs`] with the radii of a binary frame's blobs as `radius`
/// says (the threshold-by-threshold path measures them always).
fn detect_with(img: &Frame, p: &BlobParams, radius: Radius) -> Vec<KeyPoint> {
    let (width, height) = (img.width() as usize, img.height() as usize);
    let levels: Vec<i16> = p.thresholds().into_iter().map(level_of).collect();
    let (Some(&lo), Some(&hi)) = (levels.iter().min(), levels.iter().max()) else {
        return Vec::new();
    };
    if width == 0 || height == 0 {
        return Vec::new();
    }
    if same_at_levels(img.as_raw(), lo, hi) {
        return detect_unchanging(img.as_raw(), [width, height], &levels, p, radius);
    }
    detect_blobs_by_threshold(img, p)
}

/// The grey level a threshold binarises at: white where the pixel value
/// exceeds it (OpenCV's `THRESH_BINARY` on 8-bit images).
fn level_of(t: f64) -> i16 {
    t.floor().clamp(-1.0, 255.0) as i16
}

/// [`detect_blobs`] threshold by threshold, the general path, which it
/// takes for frames with grey levels between the thresholds: binarised
/// and traced per component of the lowest threshold, a component re-traced
/// only when some of its pixels change side. On binary frames, the
/// reference [`detect_blobs`]'s shorter path is checked against.
pub fn detect_blobs_by_threshold(img: &Frame, p: &BlobParams) -> Vec<KeyPoint> {
    let (width, height) = (img.width() as usize, img.height() as usize);
    let thresholds = p.thresholds();
    if width == 0 || height == 0 || thresholds.is_empty() {
        return Vec::new();
    }
    let pixels = img.as_raw();
    // Thresholds increase, so the first one has the largest white set.
    let components = label_components(pixels, width, height, level_of(thresholds[0]));
    let mut cache: Vec<Vec<Measured>> = (0..components.len()).map(|_| Vec::new()).collect();
    let mut counts: Vec<Option<usize>> = vec![None; components.len()];
    let mut scanner = ContourScanner::new(0, 0);
    let mut scratch = Scratch::default();
    let mut keyed: Vec<(usize, Centre)> = Vec::new();
    let mut found: Vec<Centre> = Vec::new();
    let mut grouper = Grouper::new(width, height, thresholds.len());
    for threshold in thresholds {
        let level = level_of(threshold);
        keyed.clear();
        for k in 0..components.len() {
            let white = components.count_above(k, level);
            if counts[k] != Some(white) {
                counts[k] = Some(white);
                cache[k].clear();
                if white > 0 {
                    components.trace(k, &mut scanner, level);
                    for (trigger, contour) in scanner.contours_with_trigger() {
                        if let Some(centre) = measure_shape(contour, p, &mut scratch) {
                            let key = trigger[1] as usize * width + trigger[0] as usize;
                            let colour_pixel = pixel_index(centre.x, centre.y, width, height);
                            cache[k].push(Measured {
                                key,
                                centre,
                                colour_pixel,
                            });
                        }
                    }
                }
            }
            for m in &cache[k] {
                if colour_matches(m.colour_pixel, pixels, level, p) {
                    keyed.push((m.key, m.centre));
                }
            }
        }
        // OpenCV lists contours in reverse order of discovery.
        keyed.sort_unstable_by_key(|&(key, _)| std::cmp::Reverse(key));
        found.clear();
        found.extend(keyed.iter().map(|&(_, c)| c));
        grouper.add(&found, f64::from(p.min_dist_between_blobs));
    }
    grouper.keypoints(p.min_repeatability)
}

/// A contour that passed every filter but colour: its raster key (of the
/// pixel that started it), centre, and the pixel that decides its colour.
struct Measured {
    key: usize,
    centre: Centre,
    colour_pixel: Option<usize>,
}

/// Whether the blob whose colour is decided at `colour_pixel` passes the
/// colour filter in the image binarised at `level`.
fn colour_matches(colour_pixel: Option<usize>, pixels: &[u8], level: i16, p: &BlobParams) -> bool {
    let colour = match colour_pixel {
        Some(i) if i16::from(pixels[i]) > level => 255,
        _ => 0,
    };
    !p.filter_by_color || colour == p.blob_color
}

/// [`colour_matches`] for a blob centred at `c` in a `width` x `height` frame.
pub(crate) fn colour_passes(
    c: &Centre,
    pixels: &[u8],
    width: usize,
    height: usize,
    level: i16,
    p: &BlobParams,
) -> bool {
    colour_matches(pixel_index(c.x, c.y, width, height), pixels, level, p)
}

/// Reusable buffers for the shape measures.
#[derive(Default)]
pub(crate) struct Scratch {
    radii: MedianScratch,
    hull: HullScratch,
    /// A chain's border points, when a test needs them.
    border: Vec<[i32; 2]>,
}

/// Row-major index of the pixel nearest to (x, y) (ties to even), if inside.
fn pixel_index(x: f64, y: f64, width: usize, height: usize) -> Option<usize> {
    let (col, row) = (x.round_ties_even(), y.round_ties_even());
    if col < 0.0 || row < 0.0 {
        return None;
    }
    let (col, row) = (col as usize, row as usize);
    (col < width && row < height).then_some(row * width + col)
}

/// Whether one contour of the current binary image passes all filters.
pub(crate) fn passes_filters(
    contour: &[[i32; 2]],
    scanner: &ContourScanner,
    p: &BlobParams,
) -> bool {
    measure_shape(contour, p, &mut Scratch::default())
        .is_some_and(|c| !p.filter_by_color || colour_at(scanner, c.x, c.y) == p.blob_color)
}

/// Applies the area, circularity, inertia and convexity filters to one
/// contour in OpenCV's order; `None` if rejected. The colour filter (which
/// OpenCV applies next) is left to the caller.
pub(crate) fn measure_shape(
    contour: &[[i32; 2]],
    p: &BlobParams,
    scratch: &mut Scratch,
) -> Option<Centre> {
    measure_shape_in(Contour::Points(contour), Known::default(), p, scratch)
}

/// What is known of a contour before it is measured, from the runs and
/// the walk that found it, and how its radius is wanted.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Known<'a> {
    /// The extremes of x, y, x + y and x - y over its points.
    pub octagon: Option<&'a Octagon>,
    /// How many of its steps are diagonal (every step one pixel).
    pub diagonal_steps: Option<usize>,
    /// The radius measured, or only bounded.
    pub radius: Radius,
}

/// What a blob's radius is taken as.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Radius {
    /// OpenCV's: the median distance of the border's points from the
    /// centre (`shape::median_radius`).
    #[default]
    Median,
    /// A bound at or above the median, from the points' box alone
    /// ([`radius_bound`]): enough to tell that no two blobs group
    /// together, for a caller that reads the centres only.
    Bound,
}

/// A contour to measure: its points in order, or the runs of a
/// component with one run a row, whose border's points
/// ([`chain_border`]) are written only for a test that needs them.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Contour<'a> {
    Points(&'a [[i32; 2]]),
    Chain(&'a [Run]),
}

impl<'a> Contour<'a> {
    /// The points, in the border's order (a chain's written into
    /// `buffer`).
    fn points<'b>(self, buffer: &'b mut Vec<[i32; 2]>) -> &'b [[i32; 2]]
    where
        'a: 'b,
    {
        match self {
            Self::Points(points) => points,
            Self::Chain(runs) => {
                chain_border(runs, buffer);
                buffer
            }
        }
    }

    /// How many points.
    fn len(self) -> usize {
        match self {
            Self::Points(points) => points.len(),
            Self::Chain(runs) => border_len(runs).max(1),
        }
    }

    /// The polygon moments ([`Moments::of_polygon`] of the points).
    fn moments(self, buffer: &mut Vec<[i32; 2]>) -> Moments {
        match self {
            Self::Points(points) => Moments::of_polygon(points),
            Self::Chain(runs) => {
                chain_moments(runs).unwrap_or_else(|| Moments::of_polygon(self.points(buffer)))
            }
        }
    }
}

/// [`measure_shape`] with what is `known` of the contour already.
pub(crate) fn measure_shape_in(
    contour: Contour,
    known: Known,
    p: &BlobParams,
    scratch: &mut Scratch,
) -> Option<Centre> {
    let moments = contour.moments(&mut scratch.border);
    let area = moments.m00;
    if p.filter_by_area && !within(area, p.min_area, p.max_area) {
        return None;
    }
    if p.filter_by_circularity
        && !circularity_passes(contour, known.diagonal_steps, area, p, scratch)
    {
        return None;
    }
    let mut confidence = 1.0;
    if p.filter_by_inertia {
        let ratio = moments.inertia_ratio();
        if !within(ratio, p.min_inertia_ratio, p.max_inertia_ratio) {
            return None;
        }
        confidence = ratio * ratio;
    }
    if p.filter_by_convexity
        && !surely_convex_enough(contour, known.octagon, area, p, &mut scratch.border)
    {
        let points = contour.points(&mut scratch.border);
        let hull = hull_area_with(points, &mut scratch.hull);
        if hull.abs() < f64::EPSILON || !within(area / hull, p.min_convexity, p.max_convexity) {
            return None;
        }
    }
    if area == 0.0 {
        return None;
    }
    let (x, y) = (moments.m10 / area, moments.m01 / area);
    let radius = match known.radius {
        Radius::Median => {
            let points = contour.points(&mut scratch.border);
            median_radius(points, [x, y], &mut scratch.radii)
        }
        Radius::Bound => radius_bound(contour, known.octagon, [x, y], &mut scratch.border),
    };
    Some(Centre {
        x,
        y,
        radius,
        confidence,
    })
}

/// The circularity filter, `4 pi A / P^2` (report ch. 4.1) in `[min,
/// max)`. With the border's `diagonal_steps` known, decided from the
/// perimeter of the step counts ([`perimeter_of_steps`]) wherever that
/// circularity lies farther than 1e-9 (relative) from both bounds: the
/// two perimeters differ by at most `(n + 2) u` relatively (n points, u =
/// 2^-53), so the two circularities by at most `2 (n + 4) u`, under 1e-9
/// / 4 for n < 2^20, and both fall on the same side of each bound. Else,
/// or near a bound, from the sum step by step ([`perimeter`]), as OpenCV.
fn circularity_passes(
    contour: Contour,
    diagonal_steps: Option<usize>,
    area: f64,
    p: &BlobParams,
    scratch: &mut Scratch,
) -> bool {
    let (min, max) = (p.min_circularity, p.max_circularity);
    let n = contour.len();
    if let Some(diagonal) = diagonal_steps.filter(|_| n < 1 << 20) {
        let c = circularity(area, perimeter_of_steps(n, diagonal));
        let clear = |bound: f32| (c - f64::from(bound)).abs() > 1e-9 * c.abs();
        if c.is_finite() && clear(min) && clear(max) {
            return within(c, min, max);
        }
    }
    let points = contour.points(&mut scratch.border);
    within(circularity(area, perimeter(points)), min, max)
}

/// True when the convexity test `area / hull` in `[min, max)` passes
/// whatever the exact hull: with U >= hull the octagon bound,
/// `area / hull >= area / U >= min` (division rounds monotonically), and a
/// non-degenerate lattice hull has area >= 1/2, so `area / hull <= 2 area`.
/// (area > 0 rules out a degenerate hull: collinear points enclose nothing.)
/// Saves the exact hull for most pins.
fn surely_convex_enough(
    contour: Contour,
    octagon: Option<&Octagon>,
    area: f64,
    p: &BlobParams,
    buffer: &mut Vec<[i32; 2]>,
) -> bool {
    let (min, max) = (f64::from(p.min_convexity), f64::from(p.max_convexity));
    let mut bound = || {
        octagon.map_or_else(
            || hull_area_upper_bound(contour.points(buffer)),
            Octagon::area,
        )
    };
    min > 0.0 && area > 0.0 && 2.0 * area < max && area / bound() >= min
}

/// A bound at or above the median radius of `contour` about `centre`
/// (finite): every point lies in the box of the points (the `octagon`'s
/// when known), so no distance exceeds that to the box's farthest corner,
/// and the median of two distances (their mean) exceeds neither. The
/// bound is enlarged by a millionth, far beyond any rounding of the
/// median's `hypot` and mean or of this square root.
fn radius_bound(
    contour: Contour,
    octagon: Option<&Octagon>,
    centre: [f64; 2],
    buffer: &mut Vec<[i32; 2]>,
) -> f64 {
    let ([x0, x1], [y0, y1]) = match octagon {
        Some(o) => (o.x, o.y),
        None => contour.points(buffer).iter().fold(
            ([i64::MAX, i64::MIN], [i64::MAX, i64::MIN]),
            |([a, b], [c, d]), &[x, y]| {
                let (x, y) = (i64::from(x), i64::from(y));
                ([a.min(x), b.max(x)], [c.min(y), d.max(y)])
            },
        ),
    };
    let far = |lo: i64, hi: i64, at: f64| (at - lo as f64).abs().max((hi as f64 - at).abs());
    let (dx, dy) = (far(x0, x1, centre[0]), far(y0, y1, centre[1]));
    (dx * dx + dy * dy).sqrt() * (1.0 + 1e-6)
}

/// OpenCV's range test: NaN-tolerant `!(v < min || v >= max)`.
fn within(value: f64, min: f32, max: f32) -> bool {
    !(value < f64::from(min) || value >= f64::from(max))
}

/// Binary value (0 or 255) at the pixel nearest to (x, y), ties to even.
fn colour_at(scanner: &ContourScanner, x: f64, y: f64) -> u8 {
    let (col, row) = (x.round_ties_even(), y.round_ties_even());
    if col < 0.0 || row < 0.0 {
        return 0;
    }
    if scanner.is_white(col as usize, row as usize) {
        255
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc_frame(centres: &[(f64, f64, f64)], size: u32) -> Frame {
        Frame::from_fn(size, size, |x, y| {
            let inside = centres
                .iter()
                .any(|&(cx, cy, r)| (f64::from(x) - cx).hypot(f64::from(y) - cy) <= r);
            image::Luma([if inside { 255 } else { 0 }])
        })
    }

    /// OpenCV defaults for white blobs; convexity relaxed because small
    /// digital discs have polygon/hull area ratios near 0.9 (cv2 agrees).
    fn white_blobs() -> BlobParams {
        BlobParams {
            blob_color: 255,
            min_convexity: 0.8,
            ..BlobParams::default()
        }
    }

    #[test]
    fn finds_each_disc_at_its_centre() {
        let discs = [(20.0, 20.0, 5.0), (50.0, 30.0, 6.0), (30.0, 50.0, 4.0)];
        let keypoints = detect_blobs(&disc_frame(&discs, 64), &white_blobs());
        assert_eq!(keypoints.len(), 3);
        for &(cx, cy, r) in &discs {
            let k = keypoints
                .iter()
                .find(|k| (k.x - cx).hypot(k.y - cy) < 0.5)
                .expect("disc found");
            assert!(
                (k.size / 2.0 - r).abs() < 1.0,
                "radius {} vs {r}",
                k.size / 2.0
            );
        }
    }

    #[test]
    fn dark_blob_colour_rejects_white_discs() {
        let frame = disc_frame(&[(20.0, 20.0, 5.0)], 40);
        assert!(detect_blobs(&frame, &BlobParams::default()).is_empty());
    }

    #[test]
    fn area_filter_rejects_small_and_large() {
        let frame = disc_frame(&[(15.0, 15.0, 2.0), (40.0, 40.0, 12.0)], 64);
        let p = BlobParams {
            min_area: 30.0,
            max_area: 200.0,
            ..white_blobs()
        };
        assert!(detect_blobs(&frame, &p).is_empty());
    }

    #[test]
    fn blank_and_empty_frames_give_no_blobs() {
        assert!(detect_blobs(&Frame::new(32, 32), &white_blobs()).is_empty());
        assert!(detect_blobs(&Frame::new(0, 0), &white_blobs()).is_empty());
    }

    /// The circularity filter decided from the walk's step counts is the
    /// one decided from the sum step by step ([`perimeter`]), on the
    /// borders of random discs and ellipses with bounds at the f32 values
    /// on either side of each border's own circularity, at 0 and at
    /// f32::MAX.
    #[test]
    fn circularity_from_step_counts_decides_as_the_sum() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
        let mut checked = 0;
        for _ in 0..400 {
            let (cx, cy) = (rng.random_range(10.0..22.0), rng.random_range(10.0..22.0));
            let (r, sx) = (rng.random_range(0.3..8.0), rng.random_range(0.4..1.6));
            let frame = Frame::from_fn(32, 32, |x, y| {
                let d = ((f64::from(x) - cx) * sx).hypot(f64::from(y) - cy);
                image::Luma([if d <= r { 255 } else { 0 }])
            });
            let Some(first) = frame.as_raw().iter().position(|&v| v > 127) else {
                continue;
            };
            let mut scanner = ContourScanner::new(32, 32);
            scanner.binarise_above(frame.as_raw(), 127);
            let (contour, diagonal) = scanner.outer_border_at(first % 32, first / 32);
            let area = Moments::of_polygon(contour).m00;
            let exact = circularity(area, perimeter(contour)) as f32;
            let around = [
                0.0,
                exact,
                f32::from_bits(exact.to_bits().saturating_sub(1)),
                f32::from_bits(exact.to_bits() + 1),
                f32::MAX,
            ];
            for &min in &around {
                for &max in &around {
                    let p = BlobParams {
                        min_circularity: min,
                        max_circularity: max,
                        ..white_blobs()
                    };
                    let want = within(circularity(area, perimeter(contour)), min, max);
                    let (points, mut scratch) = (Contour::Points(contour), Scratch::default());
                    let got = circularity_passes(points, Some(diagonal), area, &p, &mut scratch);
                    assert_eq!(got, want, "{contour:?} [{min}, {max})");
                    checked += 1;
                }
            }
        }
        assert!(checked > 5000, "{checked} decisions");
    }

    #[test]
    fn repeatability_above_threshold_count_gives_nothing() {
        let frame = disc_frame(&[(20.0, 20.0, 5.0)], 40);
        let p = BlobParams {
            min_repeatability: 100,
            ..white_blobs()
        };
        assert!(detect_blobs(&frame, &p).is_empty());
    }
}
