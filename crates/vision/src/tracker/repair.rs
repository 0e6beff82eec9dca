//! Repair of a fold-over in the tracker's result (report ch. 4.1: each
//! entry of the displacement vector must belong to its own pin). Runs only
//! when a neighbour triangle has turned over ([`crate::fold`]), which
//! happened on 2 of the 3762 real frames, both under ~30 px shear with
//! strong compression at the edge; fold-free results never get here.
//! Two levels: the points of the pins around the fold re-ordered among
//! them ([`PinTracker::unfold`], after every coarse-to-fine pass), and,
//! after the touching-pin split, the clusters around the fold split anew
//! ([`PinTracker::resplit`]).

use super::{PinTracker, Tracked};
use crate::fold::reorder_region;
use crate::merged::Cluster;

/// Gate (spacings) of the re-ordering around a fold: that of the last stage.
const UNFOLD_GATE: f64 = 0.6;
/// Most pins re-ordered around a fold (7! = 5040 orders).
const UNFOLD_PINS: usize = 7;
/// A cluster within this many spacings of a pin around a fold may be
/// split anew.
const RESPLIT_REACH: f64 = 0.5;
/// At most this many clusters are split anew (3 counts each: 81 passes).
const RESPLIT_CLUSTERS: usize = 4;
/// Pins per re-split cluster tried: 1 to this.
const RESPLIT_MAX_PINS: usize = 3;

impl PinTracker {
    /// Local repair of a fold (see [`crate::fold`]): the corners of the
    /// turned triangles and their unmatched neighbours (at most
    /// [`UNFOLD_PINS`]) are predicted from the field of the other matched
    /// pins (the last stage's kernel: a wider one smooths away the steep
    /// compression next to the edge where folds occur), their points
    /// re-ordered among them ([`reorder_region`]: each point within the
    /// last stage's gate of its pin's prediction, no turned triangle,
    /// smallest residual) and the final field refitted. Returned when still
    /// fold-free, else `tracked` as it is.
    #[cold]
    #[inline(never)]
    pub(super) fn unfold(
        &self,
        points: &[[f64; 2]],
        tracked: Tracked,
        matches: Vec<Option<usize>>,
    ) -> (Tracked, Vec<Option<usize>>) {
        let turned = self.folds.turned(&tracked.pins);
        let mut region = self.folds.corners_and(&turned, |j| matches[j].is_none());
        region.truncate(UNFOLD_PINS);
        let mut outside = self.displacements(&matches, points);
        for &i in &region {
            outside[i] = None;
        }
        let last = &self.stages[self.stages.len() - 1].kernel;
        let around = self.predict(&outside, last);
        let reordered = reorder_region(
            &self.folds,
            &tracked.pins,
            points,
            &matches,
            &region,
            &around,
            UNFOLD_GATE * self.spacing,
        );
        if let Some(rematched) = reordered {
            let observed = self.displacements(&rematched, points);
            let predicted = self.predict(&observed, last);
            let repaired = self.finish(&rematched, &observed, &predicted, points.len());
            if !self.folds.any_turned(&repaired.pins) {
                return (repaired, rematched);
            }
        }
        (tracked, matches)
    }

    /// Repair of a fold left by the cluster split (a cluster given too many
    /// pins next to one given too few): the clusters near the pins around
    /// the turned triangles that gave no keypoint, or hold other than one
    /// point, are split anew into 1..=3 pins each (a count of 1 for a
    /// cluster that gave keypoints keeps them), every combination ordered
    /// again. The best result (fewest turned triangles, then fewest pins
    /// missing, then fewest extra points, then smoothest,
    /// [`crate::fold::FoldCheck::roughness`]) replaces `kept` when it has
    /// fewer turned triangles. `kept_points` are the points
    /// `kept` was ordered from, `keypoints` the detected ones.
    #[cold]
    #[inline(never)]
    pub(super) fn resplit(
        &self,
        kept: Tracked,
        kept_points: &[[f64; 2]],
        keypoints: &[[f64; 2]],
        clusters: &[Cluster],
    ) -> Tracked {
        let turned = self.folds.turned(&kept.pins);
        let region = self.folds.region(&turned, 1);
        let inside = |c: &Cluster, q: [f64; 2]| c.distance2(q) <= 0.5;
        let reach2 = (RESPLIT_REACH * self.spacing).powi(2);
        let mut near: Vec<(f64, usize)> = clusters
            .iter()
            .enumerate()
            .filter(|(_, c)| {
                !c.passed || kept_points.iter().filter(|&&q| inside(c, q)).count() != 1
            })
            .map(|(k, c)| {
                let around = kept.pins.iter().zip(&region).filter(|(_, &r)| r);
                let d2 = around.map(|(p, _)| c.distance2(*p));
                (d2.fold(f64::INFINITY, f64::min), k)
            })
            .filter(|&(d2, _)| d2 < reach2)
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        near.truncate(RESPLIT_CLUSTERS);
        let chosen: Vec<&Cluster> = near.iter().map(|&(_, k)| &clusters[k]).collect();
        let base: Vec<[f64; 2]> = kept_points
            .iter()
            .filter(|&&q| !chosen.iter().any(|c| inside(c, q)))
            .copied()
            .collect();
        let score = |t: &Tracked| {
            let rough = self.folds.roughness(&self.reference, &t.pins);
            (self.turned_triangles(t), t.missing, t.extra, rough)
        };
        // Every combination, those with as many points as pins first: a
        // combination with `m` points has at least `pins - m` missing or
        // `m - pins` extra, so once one scores better than that bound it
        // is skipped without its ordering pass (the best is the same as
        // over all combinations in turn, short of an exact tie).
        let slots = chosen.len() as u32;
        let total = |combo: usize| {
            let ks =
                (0..slots).map(|slot| 1 + combo / RESPLIT_MAX_PINS.pow(slot) % RESPLIT_MAX_PINS);
            base.len() + ks.sum::<usize>()
        };
        let pins = self.reference.len();
        let mut combos: Vec<usize> = (0..RESPLIT_MAX_PINS.pow(slots)).collect();
        combos.sort_by_key(|&c| total(c).abs_diff(pins));
        let mut best: Option<((usize, usize, usize, f64), Tracked)> = None;
        for combo in combos {
            let m = total(combo);
            let bound = (
                0,
                pins.saturating_sub(m),
                m.saturating_sub(pins),
                f64::NEG_INFINITY,
            );
            if best
                .as_ref()
                .is_some_and(|(b, _)| b.partial_cmp(&bound).is_some_and(|o| o.is_le()))
            {
                continue;
            }
            let mut points = base.clone();
            for (slot, c) in chosen.iter().enumerate() {
                let k = 1 + combo / RESPLIT_MAX_PINS.pow(slot as u32) % RESPLIT_MAX_PINS;
                if k == 1 && c.passed {
                    points.extend(keypoints.iter().filter(|&&q| inside(c, q)));
                } else {
                    points.extend(c.split(k));
                }
            }
            let (tracked, _) = self.order_points(&points);
            let s = score(&tracked);
            if best
                .as_ref()
                .is_none_or(|(b, _)| s.partial_cmp(b).is_some_and(|o| o.is_lt()))
            {
                best = Some((s, tracked));
            }
        }
        match best {
            Some((s, tracked)) if s.0 < self.turned_triangles(&kept) => tracked,
            _ => kept,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPACING: f64 = 11.0;

    /// 127 pins in 6 hexagonal rings, spacing 11 px, centred at (128, 128).
    fn hex_reference() -> Vec<[f64; 2]> {
        let mut pins = Vec::new();
        for q in -6i32..=6 {
            for r in -6i32..=6 {
                if (q + r).abs() <= 6 {
                    let x = 128.0 + SPACING * (f64::from(q) + 0.5 * f64::from(r));
                    let y = 128.0 + SPACING * 0.75f64.sqrt() * f64::from(r);
                    pins.push([x, y]);
                }
            }
        }
        pins
    }

    /// Smooth, fold-free: translation plus a Gaussian bump of `scale` px
    /// (1 px wiggle per pin from `seed`).
    fn moved(reference: &[[f64; 2]], scale: f64, seed: u64) -> Vec<[f64; 2]> {
        reference
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let (dx, dy) = (p[0] - 140.0, p[1] - 120.0);
                let g = scale * (-(dx * dx + dy * dy) / (2.0 * 30.0f64.powi(2))).exp();
                let h = ((i as u64 * 7919 + seed * 104_729) % 1000) as f64 / 1000.0 - 0.5;
                [p[0] + 5.0 + g + h, p[1] - 4.0 + 0.5 * g - h]
            })
            .collect()
    }

    /// The tracked result of `points` under `matches`, as the last stage
    /// would finish it.
    fn finished(tracker: &PinTracker, points: &[[f64; 2]], matches: &[Option<usize>]) -> Tracked {
        let observed = tracker.displacements(matches, points);
        let last = &tracker.stages[tracker.stages.len() - 1].kernel;
        let predicted = tracker.predict(&observed, last);
        tracker.finish(matches, &observed, &predicted, points.len())
    }

    fn neighbours(reference: &[[f64; 2]], i: usize) -> Vec<usize> {
        (0..reference.len())
            .filter(|&j| {
                let d =
                    (reference[i][0] - reference[j][0]).hypot(reference[i][1] - reference[j][1]);
                j != i && d < 1.2 * SPACING
            })
            .collect()
    }

    /// Two neighbouring pins holding each other's points, or three mutual
    /// neighbours holding their points in a cycle, at the centre and at the
    /// rim: the repair restores the correct order, which is what the
    /// coarse-to-fine stages give on these points.
    #[test]
    fn swapped_and_cycled_neighbours_are_put_back() {
        let reference = hex_reference();
        let tracker = PinTracker::new(reference.clone()).expect("tracker");
        for (seed, pin) in [0usize, 30, 63, 100, 126].into_iter().enumerate() {
            let points = moved(&reference, 12.0, seed as u64);
            let (right, right_matches) = tracker.coarse_to_fine(&points);
            let identity: Vec<Option<usize>> = (0..points.len()).map(Some).collect();
            assert_eq!(right_matches, identity, "pin {pin}");
            let around = neighbours(&reference, pin);
            let next = around[0];
            let third = *around
                .iter()
                .find(|&&k| neighbours(&reference, next).contains(&k))
                .expect("a common neighbour");
            let mut swapped = identity.clone();
            swapped.swap(pin, next);
            let mut cycled = identity.clone();
            (cycled[pin], cycled[next], cycled[third]) = (Some(next), Some(third), Some(pin));
            for wrong in [swapped, cycled] {
                let folded = finished(&tracker, &points, &wrong);
                assert!(tracker.folds.any_turned(&folded.pins), "pin {pin}: no fold");
                let (repaired, matches) = tracker.unfold(&points, folded, wrong);
                assert_eq!(matches, identity, "pin {pin}");
                assert_eq!(repaired, right, "pin {pin}");
            }
        }
    }

    /// Without a fold the repair is skipped, and would change nothing.
    #[test]
    fn fold_free_results_are_returned_unchanged() {
        let reference = hex_reference();
        let tracker = PinTracker::new(reference.clone()).expect("tracker");
        for seed in 0..10u64 {
            let mut points = moved(&reference, 4.0 * seed as f64, seed);
            points.remove((seed as usize * 13) % points.len());
            points.push([30.0, 40.0 + seed as f64]);
            let (plain, plain_matches) = tracker.coarse_to_fine(&points);
            assert!(!tracker.folds.any_turned(&plain.pins), "seed {seed}");
            assert_eq!(
                tracker.order_points(&points),
                (plain.clone(), plain_matches.clone())
            );
            let again = tracker.unfold(&points, plain.clone(), plain_matches.clone());
            assert_eq!(again, (plain, plain_matches), "seed {seed}");
        }
    }
}
