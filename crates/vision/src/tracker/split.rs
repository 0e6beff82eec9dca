//! The touching-pin split of the ordering (`PinTracker::split_pass`):
//! the clusters of touching pins that have missing pins predicted on them
//! are split into as many centres as pins they hold, and the frame is
//! ordered again. Kept apart from `tracker.rs` for its size; the lookups
//! of clusters are pruned (issue 21, item 6) without changing a pin.

use super::{FirstPass, PinTracker, Tracked, CLUSTER_REACH};
use crate::merged::Cluster;

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
        let (second, _) = self.order_points(&retry);
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
