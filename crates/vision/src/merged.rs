//! Touching pins. Under strong compression two neighbouring pin tips touch
//! in the binarised image and form one dumbbell-shaped component, which the
//! blob filters (rightly) reject or report as one blob. This module lists
//! the white components of pin-cluster size so the tracker can split one
//! into as many pins as its prediction says it holds (an extension beyond
//! OpenCV's detector; it only ever runs after ordinary matching left pins
//! missing).

use std::collections::VecDeque;

use crate::blob::{passes_filters, Frame};
use crate::contour::ContourScanner;
use crate::params::BlobParams;
use crate::shape::Moments;

/// Largest cluster area, in multiples of `max_area`.
const MAX_PINS_PER_CLUSTER: f32 = 3.0;
/// Lloyd iterations of the 1-D k-means along the cluster's long axis.
const KMEANS_ITERATIONS: usize = 10;

/// One white 8-connected component of possible multi-pin size.
#[derive(Clone, Debug, PartialEq)]
pub struct Cluster {
    /// Its pixels (x, y), sorted by (y, x).
    pub pixels: Vec<[i32; 2]>,
    /// Whether the component passed the blob filters (so it already gave a keypoint).
    pub passed: bool,
}

/// White components whose contour area lies in
/// `[min_area, 3 * max_area)`, binarised at the middle threshold of `p`.
/// Empty unless `p.blob_color` is 255 (white pins).
pub fn find_clusters(img: &Frame, p: &BlobParams) -> Vec<Cluster> {
    let thresholds = p.thresholds();
    let (width, height) = (img.width() as usize, img.height() as usize);
    if p.blob_color != 255 || thresholds.is_empty() || width == 0 || height == 0 {
        return Vec::new();
    }
    let mut scanner = ContourScanner::new(width, height);
    scanner.binarise(img.as_raw(), thresholds[thresholds.len() / 2]);
    scanner.trace_all();
    let (lo, hi) = (
        f64::from(p.min_area),
        f64::from(MAX_PINS_PER_CLUSTER * p.max_area),
    );
    let mut seen = vec![false; width * height];
    scanner
        .outer_contours()
        .filter(|c| {
            let area = Moments::of_polygon(c).m00;
            area >= lo && area < hi
        })
        .map(|c| Cluster {
            pixels: flood(&scanner, c[0], &mut seen),
            passed: passes_filters(c, &scanner, p),
        })
        .collect()
}

/// The 8-connected white component containing `seed`.
fn flood(scanner: &ContourScanner, seed: [i32; 2], seen: &mut [bool]) -> Vec<[i32; 2]> {
    let (width, height) = scanner.size();
    let index = |q: [i32; 2]| q[1] as usize * width + q[0] as usize;
    let mut pixels = Vec::new();
    let mut queue = VecDeque::from([seed]);
    seen[index(seed)] = true;
    while let Some(q) = queue.pop_front() {
        pixels.push(q);
        for dy in -1..=1 {
            for dx in -1..=1 {
                let n = [q[0] + dx, q[1] + dy];
                let inside =
                    n[0] >= 0 && n[1] >= 0 && (n[0] as usize) < width && (n[1] as usize) < height;
                if inside && !seen[index(n)] && scanner.is_white(n[0] as usize, n[1] as usize) {
                    seen[index(n)] = true;
                    queue.push_back(n);
                }
            }
        }
    }
    pixels.sort_unstable_by_key(|q| (q[1], q[0]));
    pixels
}

impl Cluster {
    /// Whether pixel (x, y) belongs to the cluster.
    pub fn contains(&self, x: i32, y: i32) -> bool {
        self.pixels
            .binary_search_by_key(&(y, x), |q| (q[1], q[0]))
            .is_ok()
    }

    /// Squared distance from `point` to the nearest cluster pixel centre.
    pub fn distance2(&self, point: [f64; 2]) -> f64 {
        self.pixels
            .iter()
            .map(|q| (f64::from(q[0]) - point[0]).powi(2) + (f64::from(q[1]) - point[1]).powi(2))
            .fold(f64::INFINITY, f64::min)
    }

    /// Splits the cluster into `k` pin centres: 1-D k-means of the pixels
    /// projected on the principal (long) axis, then each part's centroid.
    pub fn split(&self, k: usize) -> Vec<[f64; 2]> {
        if k == 0 || self.pixels.is_empty() {
            return Vec::new();
        }
        let (centre, axis) = principal_axis(&self.pixels);
        let along: Vec<f64> = self
            .pixels
            .iter()
            .map(|q| {
                (f64::from(q[0]) - centre[0]) * axis[0] + (f64::from(q[1]) - centre[1]) * axis[1]
            })
            .collect();
        let labels = kmeans_1d(&along, k);
        (0..k)
            .filter_map(|part| {
                let members: Vec<[i32; 2]> = self
                    .pixels
                    .iter()
                    .zip(&labels)
                    .filter(|(_, &l)| l == part)
                    .map(|(q, _)| *q)
                    .collect();
                pixel_centroid(&members)
            })
            .collect()
    }
}

fn pixel_centroid(pixels: &[[i32; 2]]) -> Option<[f64; 2]> {
    if pixels.is_empty() {
        return None;
    }
    let n = pixels.len() as f64;
    let sx: f64 = pixels.iter().map(|q| f64::from(q[0])).sum();
    let sy: f64 = pixels.iter().map(|q| f64::from(q[1])).sum();
    Some([sx / n, sy / n])
}

/// Pixel centroid and unit direction of largest spread.
fn principal_axis(pixels: &[[i32; 2]]) -> ([f64; 2], [f64; 2]) {
    let centre = pixel_centroid(pixels).unwrap_or([0.0, 0.0]);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for q in pixels {
        let (dx, dy) = (f64::from(q[0]) - centre[0], f64::from(q[1]) - centre[1]);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    (centre, [angle.cos(), angle.sin()])
}

/// Labels 0..k of a 1-D k-means started from evenly spaced quantiles.
fn kmeans_1d(values: &[f64], k: usize) -> Vec<usize> {
    let mut sorted = values.to_vec();
    sorted.sort_unstable_by(f64::total_cmp);
    let n = sorted.len();
    let mut means: Vec<f64> = (0..k)
        .map(|j| sorted[((2 * j + 1) * n / (2 * k)).min(n - 1)])
        .collect();
    let nearest = |v: f64, means: &[f64]| -> usize {
        (0..means.len())
            .min_by(|&a, &b| (v - means[a]).abs().total_cmp(&(v - means[b]).abs()))
            .unwrap_or(0)
    };
    for _ in 0..KMEANS_ITERATIONS {
        let mut sums = vec![(0.0, 0usize); k];
        for &v in values {
            let j = nearest(v, &means);
            sums[j].0 += v;
            sums[j].1 += 1;
        }
        for (m, (s, c)) in means.iter_mut().zip(&sums) {
            if *c > 0 {
                *m = s / *c as f64;
            }
        }
    }
    values.iter().map(|&v| nearest(v, &means)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two discs of radius 3 at (10, 10) and (16, 10) joined by a neck.
    fn dumbbell() -> Frame {
        Frame::from_fn(30, 20, |x, y| {
            let (x, y) = (f64::from(x), f64::from(y));
            let disc = |cx: f64| (x - cx).hypot(y - 10.0) <= 3.0;
            image::Luma([if disc(10.0) || disc(16.0) { 255 } else { 0 }])
        })
    }

    fn white_pins() -> BlobParams {
        BlobParams {
            min_area: 5.0,
            max_area: 40.0,
            ..BlobParams::preset("real256").expect("preset")
        }
    }

    #[test]
    fn dumbbell_is_one_cluster_that_splits_into_both_discs() {
        let clusters = find_clusters(&dumbbell(), &white_pins());
        assert_eq!(clusters.len(), 1);
        let mut parts = clusters[0].split(2);
        parts.sort_by(|a, b| a[0].total_cmp(&b[0]));
        assert!((parts[0][0] - 10.0).abs() < 1.0 && (parts[0][1] - 10.0).abs() < 1e-9);
        assert!((parts[1][0] - 16.0).abs() < 1.0 && (parts[1][1] - 10.0).abs() < 1e-9);
        assert!(clusters[0].contains(10, 10) && !clusters[0].contains(0, 0));
    }

    #[test]
    fn dark_blob_settings_find_no_clusters() {
        let p = BlobParams {
            blob_color: 0,
            ..white_pins()
        };
        assert!(find_clusters(&dumbbell(), &p).is_empty());
        assert!(white_pins().thresholds().len() > 1);
    }
}
