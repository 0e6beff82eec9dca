//! The touching-pin split of the ordering (`PinTracker::split_pass`):
//! the clusters of touching pins that have missing pins predicted on them
//! are split into as many centres as pins they hold, and the frame is
//! ordered again. Kept apart from `tracker.rs` for its size; the lookups
//! of clusters are pruned without changing a pin.
//!
//! The second ordering starts from the first pass's pins
//! ([`PinTracker::with_seeded_split`]): only the clusters' points changed,
//! so every other pin already sits on its point and the missing ones where
//! the field of their neighbours puts them, next to the new centres. Those
//! pins stand in for the nearest-neighbour start's prediction (the pairs
//! and the field of 2 spacings fitted to them, `tracker/grid.rs`): the
//! last stage alone runs from them (its matching, then the fill), or when
//! that does not hold the two narrow stages, each kept by the start's own
//! rule (no triangle turned over; no pin missing, or the first matching
//! settled by the margin); else the points are ordered from scratch as
//! before. A kept result is the one any kept start gives when its last
//! matching is the same (the pins follow from that matching alone);
//! checked bit for bit on the shared sets (`tests/it/speed_cuts.rs`, and
//! `examples/order_timing.rs --dump` on every frame of the 331-pin shear
//! set and the 127-pin edge set) and on synthetic taps (the tests here).

use super::grid::{Grid, CELL};
use super::{FirstPass, PinTracker, Tracked, CLUSTER_REACH};
use crate::merged::Cluster;

/// An ordering: the pins and, per pin, the index of its point.
type Found = (Tracked, Vec<Option<usize>>);

impl PinTracker {
    /// The rest of [`PinTracker::order_with_clusters`] after `first` (on
    /// the same keypoints): the same result.
    pub fn split_pass(&self, first: FirstPass, clusters: &[Cluster]) -> Tracked {
        let FirstPass {
            points,
            tracked: first,
            sources,
        } = first;
        if first.missing == 0 || clusters.is_empty() {
            return first;
        }
        let missing_in = self.missing_per_cluster(&first, clusters);
        if missing_in.iter().all(|&m| m == 0) {
            return first;
        }
        let owner: Vec<Option<usize>> = if self.cuts {
            let with_missing: Vec<usize> =
                (0..clusters.len()).filter(|&c| missing_in[c] > 0).collect();
            points
                .iter()
                .map(|q| owning_cluster_among(q, clusters, &with_missing))
                .collect()
        } else {
            points
                .iter()
                .map(|q| owning_cluster(q, clusters, &missing_in))
                .collect()
        };
        let mut retry: Vec<[f64; 2]> = points
            .iter()
            .zip(&owner)
            .filter(|(_, o)| o.is_none())
            .map(|(q, _)| *q)
            .collect();
        for (c, cluster) in clusters
            .iter()
            .enumerate()
            .filter(|(c, _)| missing_in[*c] > 0)
        {
            let held = sources
                .iter()
                .flatten()
                .filter(|&&k| owner[k] == Some(c))
                .count();
            retry.extend(cluster.split(held + missing_in[c]));
        }
        let (second, _) = self.order_seeded(&retry, &first.pins);
        let (kept, kept_points) = if second.matched_count() >= first.matched_count() {
            (second, retry)
        } else {
            (first, points.clone())
        };
        if self.folds.any_turned(&kept.pins) {
            return self.resplit(kept, &kept_points, &points, clusters);
        }
        kept
    }

    /// [`PinTracker::order_points`] on the split pass's `points`, tried
    /// first from the first pass's pins `seed` (see the module docs).
    fn order_seeded(&self, points: &[[f64; 2]], seed: &[[f64; 2]]) -> Found {
        match self.seeded_start(points, seed) {
            Some(found) => found,
            None => self.order_points(points),
        }
    }

    /// The last stage from the pins `seed`, else the two narrow stages
    /// from them, when the result holds by the nearest-neighbour start's
    /// rule; `None` when neither does (or the seeded start or the
    /// nearest-neighbour start is off).
    fn seeded_start(&self, points: &[[f64; 2]], seed: &[[f64; 2]]) -> Option<Found> {
        if !(self.seeded && self.nearest) {
            return None;
        }
        let grid = Grid::new(points, CELL * self.spacing)?;
        let last = &self.stages[self.stages.len() - 1..];
        if let Ok(found) = self.try_stages(last, seed.to_vec(), points, &grid, false) {
            return Some(found);
        }
        self.try_start(seed.to_vec(), points, &grid, false).ok()
    }

    /// For each cluster, how many missing pins are predicted on or next to
    /// it (each missing pin counts for its nearest cluster only).
    fn missing_per_cluster(&self, tracked: &Tracked, clusters: &[Cluster]) -> Vec<usize> {
        let reach2 = (CLUSTER_REACH * self.spacing).powi(2);
        let mut counts = vec![0; clusters.len()];
        let bounds: Vec<[f64; 4]> = clusters.iter().map(bounds).collect();
        for (pin, _) in tracked
            .pins
            .iter()
            .zip(&tracked.matched)
            .filter(|(_, m)| !**m)
        {
            // Only a cluster within reach counts, so those whose box is
            // out of reach (no pixel nearer than the box) are skipped:
            // the first nearest within reach is the same.
            let nearest = clusters
                .iter()
                .zip(&bounds)
                .enumerate()
                .filter(|(_, (_, b))| !self.cuts || box_distance2(b, pin) < reach2)
                .map(|(k, (c, _))| (k, c.distance2(*pin)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((c, d2)) = nearest {
                if d2 < reach2 {
                    counts[c] += 1;
                }
            }
        }
        counts
    }
}

/// The cluster (among those with missing pins) whose pixel holds `point`.
fn owning_cluster(point: &[f64; 2], clusters: &[Cluster], missing_in: &[usize]) -> Option<usize> {
    let (x, y) = (point[0].round() as i32, point[1].round() as i32);
    (0..clusters.len()).find(|&c| missing_in[c] > 0 && clusters[c].contains(x, y))
}

/// The first of the clusters `among` (indices, ascending) whose pixel
/// holds `point`: [`owning_cluster`] with the clusters without missing
/// pins left out beforehand.
fn owning_cluster_among(point: &[f64; 2], clusters: &[Cluster], among: &[usize]) -> Option<usize> {
    let (x, y) = (point[0].round() as i32, point[1].round() as i32);
    among.iter().copied().find(|&c| clusters[c].contains(x, y))
}

/// A cluster's pixel centres' box: min x, min y, max x, max y (an empty
/// cluster's box is inverted: [`box_distance2`] to it is infinite).
fn bounds(cluster: &Cluster) -> [f64; 4] {
    cluster.pixels.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, q| {
            let (x, y) = (f64::from(q[0]), f64::from(q[1]));
            [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)]
        },
    )
}

/// Squared distance from `p` to the box `b`: never above the squared
/// distance to any pixel centre inside it, as `Cluster::distance2` rounds
/// it (rounding is monotone), so a box out of reach holds no pixel within it.
fn box_distance2(b: &[f64; 4], p: &[f64; 2]) -> f64 {
    let dx = (b[0] - p[0]).max(p[0] - b[2]).max(0.0);
    let dy = (b[1] - p[1]).max(p[1] - b[3]).max(0.0);
    dx * dx + dy * dy
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blob::KeyPoint;
    use rand::{Rng, SeedableRng};

    /// The pixels within `r` px of `a` or `b`, sorted by (y, x): two pin
    /// tips touching in the binarised image.
    fn dumbbell(a: [f64; 2], b: [f64; 2], r: f64) -> Vec<[i32; 2]> {
        let near = |q: [f64; 2], x: f64, y: f64| (q[0] - x).hypot(q[1] - y) <= r;
        let span = |k: usize| {
            let lo = (a[k].min(b[k]) - r).floor() as i32;
            lo..=(a[k].max(b[k]) + r).ceil() as i32
        };
        span(1)
            .flat_map(|y| span(0).map(move |x| [x, y]))
            .filter(|q| {
                let (x, y) = (f64::from(q[0]), f64::from(q[1]));
                near(a, x, y) || near(b, x, y)
            })
            .collect()
    }

    /// A tap on the 331-pin rings (5 px apart): a shear and jitter, and
    /// `merged` pairs of neighbouring pins touching: one keypoint at the
    /// pair's pixel centroid and a cluster of its pixels each.
    fn touching_tap(
        reference: &[[f64; 2]],
        merged: usize,
        rng: &mut impl Rng,
    ) -> (Vec<KeyPoint>, Vec<Cluster>) {
        let shear = rng.random_range(-0.12..0.12);
        let mut points: Vec<Option<[f64; 2]>> = reference
            .iter()
            .map(|r| {
                let j = 0.3;
                let x = r[0] + shear * (r[1] - 64.0) + rng.random_range(-j..j);
                Some([x, r[1] + rng.random_range(-j..j)])
            })
            .collect();
        let mut clusters = Vec::new();
        while clusters.len() < merged {
            let a = rng.random_range(0..points.len());
            let Some(pa) = points[a] else { continue };
            let b = (0..points.len())
                .filter(|&b| b != a)
                .filter_map(|b| points[b].map(|p| (b, (p[0] - pa[0]).hypot(p[1] - pa[1]))))
                .min_by(|x, y| x.1.total_cmp(&y.1));
            let Some((b, _)) = b else { break };
            let pixels = dumbbell(pa, points[b].expect("some"), 2.0);
            let n = pixels.len() as f64;
            let sum = |k: usize| pixels.iter().map(|q| f64::from(q[k])).sum::<f64>();
            points[a] = Some([sum(0) / n, sum(1) / n]);
            points[b] = None;
            clusters.push(Cluster {
                pixels,
                passed: true,
            });
        }
        let keypoints = points
            .iter()
            .flatten()
            .map(|p| KeyPoint {
                x: p[0],
                y: p[1],
                size: 2.5,
            })
            .collect();
        (keypoints, clusters)
    }

    /// On synthetic taps with touching pins, the split pass started from
    /// the first pass's pins gives the pins of the split pass from
    /// scratch, bit for bit, and the seeded start holds on most of them
    /// (its last stage alone on most, too).
    #[test]
    fn seeded_split_pass_is_the_one_from_scratch_bit_for_bit() {
        let reference = crate::field::tests::rings();
        let seeded = PinTracker::new(reference.clone()).expect("tracker");
        let scratch = PinTracker::new(reference.clone())
            .expect("tracker")
            .with_seeded_split(false);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1933);
        let (mut split, mut held, mut alone) = (0, 0, 0);
        for trial in 0..60 {
            let (keypoints, clusters) = touching_tap(&reference, 1 + trial % 5, &mut rng);
            let a = seeded.order_with_clusters(&keypoints, &clusters);
            let b = scratch.order_with_clusters(&keypoints, &clusters);
            let bits = |t: &Tracked| -> Vec<[u64; 2]> {
                t.pins.iter().map(|p| p.map(f64::to_bits)).collect()
            };
            assert_eq!(bits(&a), bits(&b), "trial {trial}");
            assert_eq!(a.matched, b.matched, "trial {trial}");
            assert_eq!((a.missing, a.extra), (b.missing, b.extra), "trial {trial}");
            // The split pass's points: each cluster's keypoint replaced by
            // its two pieces (each cluster holds two pins).
            let first = seeded.first_pass(&keypoints);
            if first.tracked.missing == 0 {
                continue;
            }
            split += 1;
            let mut retry: Vec<[f64; 2]> = first
                .points
                .iter()
                .filter(|q| {
                    let (x, y) = (q[0].round() as i32, q[1].round() as i32);
                    !clusters.iter().any(|c| c.contains(x, y))
                })
                .copied()
                .collect();
            retry.extend(clusters.iter().flat_map(|c| c.split(2)));
            let found = seeded.seeded_start(&retry, &first.tracked.pins);
            held += usize::from(found.is_some_and(|(t, _)| t.missing == 0));
            let grid = Grid::new(&retry, CELL * seeded.spacing).expect("grid");
            let last = &seeded.stages[seeded.stages.len() - 1..];
            let seed = first.tracked.pins.clone();
            alone += usize::from(seeded.try_stages(last, seed, &retry, &grid, false).is_ok());
            assert!(scratch.seeded_start(&retry, &first.tracked.pins).is_none());
        }
        assert!(split >= 40, "only {split} taps left pins missing");
        assert!(
            held * 2 >= split,
            "the seeded start held on {held} of {split}"
        );
        assert!(
            alone * 2 >= split,
            "the last stage alone held on {alone} of {split}"
        );
    }
}
