//! Where the tracker finds its candidates fast (issue 21, item 6): a
//! bucket grid over a frame's points, and the nearest-neighbour start of
//! the coarse-to-fine matching.
//!
//! The grid lists, for a predicted pin, the points of the cells its gate
//! box touches; the matching then applies the same tests as the scan over
//! the x-sorted points, so the edges handed to the assignment solver are
//! the same, in the same order (point index).
//!
//! The nearest-neighbour start replaces the wide first stages (gates of 3
//! and 1.5 spacings, about 30 candidates a pin) where the tap moves the
//! pins little: each pin shifted by the centroids' difference takes its
//! nearest point within [`NEAREST_REACH`] when that point's nearest pin is
//! it too; when fewer than [`GROW_BELOW`] of the pins pair so, the pairs
//! grow for up to [`GROW_ROUNDS`] rounds (each unpaired pin, where the field
//! of 3 spacings fitted to the pairs puts it, pairs with a free point by
//! the same rule: under a large shear the pairs thin out where the pins
//! moved most, and grow back in from its edge); the field fitted to the
//! pairs (kernel of 2 spacings) predicts every pin, and the narrow stages
//! run from there. It is used only when at least
//! [`NEAREST_MIN_SHARE`] of the pins pair up, the result turns no triangle
//! over, and either no pin is missing or the first narrow matching is
//! settled by [`NEAREST_MARGIN`] ([`PinTracker::settled`]: every later
//! stage depends on the start only through that matching, so a settled one
//! is what the full path finds unless its start moves the costs by the
//! margin); otherwise it is tried once more from the pins it gave
//! (`tracker/start.rs`), and when that does not hold either the tracker
//! runs every stage from the centroid shift, as it always did.

use super::{PinTracker, Stage};

/// Grid cell side, in reference spacings.
pub(super) const CELL: f64 = 0.5;
/// Widest gate (spacings) matched through the grid: every stage's (the
/// widest, 3 spacings, visits about 40 points a pin through 13 rows of
/// cells where the x-window of the sorted points held about 100 on a
/// 331-pin frame). A point set whose grid cannot be built scans the
/// x-sorted points.
pub(super) const GRID_GATE: f64 = 3.0;
/// [`GRID_GATE`] with the speed cuts off ([`PinTracker::with_speed_cuts`]):
/// wider gates scan the x-sorted points, as before (the same edges).
const PLAIN_GRID_GATE: f64 = 1.5;
/// Radius (spacings) within which a pin and a point are nearest neighbours.
const NEAREST_REACH: f64 = 0.5;
/// Rounds at most in which the nearest-neighbour pairs grow from the
/// field fitted to them ([`PinTracker::with_grown_pairs`]); chosen with
/// [`GROW_BELOW`] by instruction counts on every 20th 127-pin frame (1
/// round: no lower p95; 4: more instructions for the same).
const GROW_ROUNDS: usize = 2;
/// Share of pins below which the first pairs grow (fewer pins pairing
/// up: the pins moved far from the centroid shift somewhere); 0.8 left
/// more frames to the second start, 0.9 grew the median frame's cost.
const GROW_BELOW: f64 = 0.85;
/// Stage whose kernel (3 spacings) puts the unpaired pins where the pairs
/// grow from.
const GROW_STAGE: usize = 0;
/// Share of pins that must pair up for the nearest-neighbour start.
const NEAREST_MIN_SHARE: f64 = 0.5;
/// Stage whose kernel (2 spacings) fits the field to the
/// nearest-neighbour pairs; the stages after it are run (a narrower
/// kernel leaves more frames to the full path).
pub(super) const NEAREST_STAGE: usize = 1;
/// Margin, in squared spacings, by which a nearest-neighbour start that
/// leaves pins missing must settle its first matching to be kept
/// ([`PinTracker::settled`]); chosen on the 331-pin shear set's train part.
pub(super) const NEAREST_MARGIN: f64 = 0.25;

/// Nearest-neighbour pairs: per pin, the index of its point, and how many
/// pins have one.
pub(super) type Pairs = (Vec<Option<usize>>, usize);

/// Points bucketed by cell, each cell's points in index order.
pub(super) struct Grid {
    cell: f64,
    origin: [f64; 2],
    cols: usize,
    rows: usize,
    /// Per cell, where its points start in `members` (one more entry).
    starts: Vec<u32>,
    /// Point indices, grouped by cell.
    members: Vec<u32>,
}

impl Grid {
    /// The grid of `points` (finite) with cells of side `cell` px (widened
    /// so there are at most a few cells a point); `None` when their extent
    /// overflows.
    pub fn new(points: &[[f64; 2]], cell: f64) -> Option<Self> {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        if points.is_empty() {
            (lo, hi) = ([0.0; 2], [0.0; 2]);
        }
        if !(hi[0] - lo[0]).is_finite() || !(hi[1] - lo[1]).is_finite() {
            return None;
        }
        let most = 16 * points.len() + 64;
        let mut cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            1.0
        };
        let count = |c: f64, a: usize| ((hi[a] - lo[a]) / c).floor() + 1.0;
        while count(cell, 0) * count(cell, 1) > most as f64 {
            cell *= 2.0;
        }
        let (cols, rows) = (count(cell, 0) as usize, count(cell, 1) as usize);
        let mut grid = Self {
            cell,
            origin: lo,
            cols,
            rows,
            starts: vec![0; cols * rows + 1],
            members: vec![0; points.len()],
        };
        let cells: Vec<usize> = points.iter().map(|p| grid.cell_of(p)).collect();
        for &c in &cells {
            grid.starts[c + 1] += 1;
        }
        for c in 0..cols * rows {
            grid.starts[c + 1] += grid.starts[c];
        }
        let mut next = grid.starts.clone();
        for (k, &c) in cells.iter().enumerate() {
            grid.members[next[c] as usize] = k as u32;
            next[c] += 1;
        }
        Some(grid)
    }

    fn cell_of(&self, p: &[f64; 2]) -> usize {
        let col = self.index(p[0], 0).clamp(0, self.cols as i64 - 1) as usize;
        let row = self.index(p[1], 1).clamp(0, self.rows as i64 - 1) as usize;
        row * self.cols + col
    }

    /// The cell index of coordinate `v` along axis `a` (may be outside).
    /// Any non-decreasing map does (a point between two query bounds
    /// falls between their cells); this one is the floor except at
    /// negative integers, without a call to libm's `floor`.
    fn index(&self, v: f64, a: usize) -> i64 {
        let t = (v - self.origin[a]) / self.cell;
        t as i64 - i64::from(t < 0.0)
    }

    /// Calls `visit(k)` for every point `k` whose cell meets the box of
    /// half-width `reach` around `p` (a superset of the points within it).
    pub fn around(&self, p: &[f64; 2], reach: f64, mut visit: impl FnMut(usize)) {
        // A margin far above rounding, so a point at the box's edge is kept.
        let margin = 1e-9 * (1.0 + reach + p[0].abs() + p[1].abs());
        let span = |a: usize, n: usize| {
            let lo = self.index(p[a] - reach - margin, a).max(0);
            let hi = self.index(p[a] + reach + margin, a).min(n as i64 - 1);
            lo..=hi
        };
        let (xs, ys) = (span(0, self.cols), span(1, self.rows));
        if xs.is_empty() {
            return;
        }
        for row in ys {
            let first = row as usize * self.cols;
            let (a, b) = (first + *xs.start() as usize, first + *xs.end() as usize);
            for &k in &self.members[self.starts[a] as usize..self.starts[b + 1] as usize] {
                visit(k as usize);
            }
        }
    }
}

impl PinTracker {
    /// Every pin's prediction from the nearest-neighbour pairs of the
    /// reference shifted by the centroids' difference (see the module
    /// docs), or `None` when too few pins pair up.
    #[cfg(test)]
    pub(super) fn nearest_start(&self, points: &[[f64; 2]], grid: &Grid) -> Option<Vec<[f64; 2]>> {
        self.grown_start(self.centroid_pairs(points, grid), points, grid)
    }

    /// The nearest-neighbour pairs of the reference shifted by the
    /// centroids' difference, before any growth.
    pub(super) fn centroid_pairs(&self, points: &[[f64; 2]], grid: &Grid) -> Pairs {
        self.first_pairs(&self.centroid_shift(points), points, grid)
    }

    /// The nearest-neighbour pairs of the pins at `shifted` (px).
    fn first_pairs(&self, shifted: &[[f64; 2]], points: &[[f64; 2]], grid: &Grid) -> Pairs {
        let mut pairs = vec![None; shifted.len()];
        let paired = self.pair_nearest(shifted, points, grid, &mut pairs);
        (pairs, paired)
    }

    /// [`PinTracker::nearest_start`] with the pins at `shifted` (px, one
    /// a reference pin) instead of the centroid shift. The pairs are grown
    /// first ([`PinTracker::with_grown_pairs`]): up to [`GROW_ROUNDS`]
    /// times, each unpaired pin where the field fitted to the pairs (kernel
    /// of [`GROW_STAGE`]) puts it pairs with a free point in the same way.
    pub(super) fn nearest_from(
        &self,
        shifted: &[[f64; 2]],
        points: &[[f64; 2]],
        grid: &Grid,
    ) -> Option<Vec<[f64; 2]>> {
        self.grown_start(self.first_pairs(shifted, points, grid), points, grid)
    }

    /// The rest of [`PinTracker::nearest_from`] after its first `pairs`:
    /// the pairs grown, then every pin predicted from them.
    pub(super) fn grown_start(
        &self,
        (mut pairs, mut paired): Pairs,
        points: &[[f64; 2]],
        grid: &Grid,
    ) -> Option<Vec<[f64; 2]>> {
        let kernel = &self.stages[GROW_STAGE].kernel;
        let grows = self.grow && (paired as f64) < GROW_BELOW * pairs.len() as f64;
        for _ in 0..if grows { GROW_ROUNDS } else { 0 } {
            let at = self.fill(&self.displacements(&pairs, points), kernel);
            match self.pair_nearest(&at, points, grid, &mut pairs) {
                0 => break,
                grew => paired += grew,
            }
        }
        if (paired as f64) < NEAREST_MIN_SHARE * self.reference.len() as f64 {
            return None;
        }
        let observed = self.displacements(&pairs, points);
        Some(self.predict(&observed, &self.stages[NEAREST_STAGE].kernel))
    }

    /// Pairs each pin `i` with no pair yet (`pairs[i]` is `None`) and a
    /// position `at[i]` with the nearest point within [`NEAREST_REACH`]
    /// that no pin holds, when that point's nearest such pin is it too;
    /// returns how many pairs it added.
    fn pair_nearest(
        &self,
        at: &[[f64; 2]],
        points: &[[f64; 2]],
        grid: &Grid,
        pairs: &mut [Option<usize>],
    ) -> usize {
        let reach = NEAREST_REACH * self.spacing;
        let reach2 = reach * reach;
        // Per point, its nearest pin (a held point: -inf, never taken);
        // per pin, its nearest point.
        let mut pin_of = vec![(f64::INFINITY, usize::MAX); points.len()];
        for &k in pairs.iter().flatten() {
            pin_of[k].0 = f64::NEG_INFINITY;
        }
        let mut point_of = vec![(f64::INFINITY, usize::MAX); pairs.len()];
        for (i, &p) in at.iter().enumerate() {
            if pairs[i].is_some() {
                continue;
            }
            grid.around(&p, reach, |k| {
                let d2 = (p[0] - points[k][0]).powi(2) + (p[1] - points[k][1]).powi(2);
                if d2 < reach2 {
                    if d2 < point_of[i].0 && pin_of[k].0 > f64::NEG_INFINITY {
                        point_of[i] = (d2, k);
                    }
                    if d2 < pin_of[k].0 {
                        pin_of[k] = (d2, i);
                    }
                }
            });
        }
        let mut added = 0;
        for (i, &(_, k)) in point_of.iter().enumerate() {
            if k != usize::MAX && pin_of[k].1 == i {
                pairs[i] = Some(k);
                added += 1;
            }
        }
        added
    }

    /// Whether the matching `matches` of the pins predicted at `predicted`
    /// to `points` within `gate` px is settled by the tracker's margin: every
    /// pin is at least the margin nearer (in squared distance) its own point
    /// than any other point within reach, every matched point the margin
    /// nearer its own pin than any other pin, no pair within the margin of
    /// the gate, and no unmatched point within reach of an unmatched pin.
    /// A start whose prediction moves the costs by less than half the margin
    /// then leads to the same matching (see the module docs).
    pub(super) fn settled(
        &self,
        predicted: &[[f64; 2]],
        points: &[[f64; 2]],
        matches: &[Option<usize>],
        gate: f64,
        grid: &Grid,
    ) -> bool {
        let Some(share) = self.nearest_margin else {
            return false;
        };
        let margin = share * self.spacing * self.spacing;
        let gate2 = gate * gate;
        let reach2 = gate2 + margin;
        let mut owner = vec![usize::MAX; points.len()];
        for (i, m) in matches.iter().enumerate() {
            if let Some(k) = *m {
                owner[k] = i;
            }
        }
        let cost = |i: usize, k: usize| {
            (predicted[i][0] - points[k][0]).powi(2) + (predicted[i][1] - points[k][1]).powi(2)
        };
        predicted.iter().enumerate().all(|(i, p)| {
            let own = matches[i].map(|k| cost(i, k));
            if own.is_some_and(|c| c > gate2 - margin) {
                return false;
            }
            let mut clear = true;
            grid.around(p, reach2.sqrt(), |k| {
                let c = cost(i, k);
                if Some(k) == matches[i] || c >= reach2 {
                    return;
                }
                let near_own = own.is_some_and(|o| c - o <= margin);
                let contested = match owner[k] {
                    usize::MAX => own.is_none(),
                    j => c - cost(j, k) <= margin,
                };
                clear &= !(near_own || contested);
            });
            clear
        })
    }

    /// Whether `stage` matches through the grid (see [`GRID_GATE`]).
    pub(super) fn uses_grid(&self, stage: &Stage) -> bool {
        let widest = if self.cuts {
            GRID_GATE
        } else {
            PLAIN_GRID_GATE
        };
        stage.gate <= widest * self.spacing
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid visits every point within the reach (and each once).
    #[test]
    fn grid_visits_every_point_within_reach_once() {
        let points: Vec<[f64; 2]> = (0..200)
            .map(|k| {
                let t = k as f64;
                [(t * 7.31) % 97.0, (t * 3.17) % 61.0]
            })
            .collect();
        for cell in [0.7, 3.0, 50.0, 1e-6] {
            let grid = Grid::new(&points, cell).expect("finite extent");
            for p in [
                [10.0, 10.0],
                [0.0, 0.0],
                [96.9, 60.9],
                [-5.0, 30.0],
                [200.0, 5.0],
            ] {
                for reach in [0.5, 2.0, 9.0] {
                    let mut seen = vec![0; points.len()];
                    grid.around(&p, reach, |k| seen[k] += 1);
                    for (k, q) in points.iter().enumerate() {
                        assert!(seen[k] <= 1);
                        let inside = (q[0] - p[0]).abs() <= reach && (q[1] - p[1]).abs() <= reach;
                        assert!(!inside || seen[k] == 1, "{cell} {p:?} {reach} {q:?}");
                    }
                }
            }
        }
        assert!(Grid::new(&[[-1e308, 0.0], [1e308, 0.0]], 1.0).is_none());
    }

    /// A matching is settled only when every pin and point prefers its own
    /// partner by the margin: a point halfway between a matched and a
    /// missing pin is not, the same point well nearer its own pin is, and
    /// without a margin nothing is.
    #[test]
    fn settled_rejects_a_point_two_pins_contest() {
        let reference: Vec<[f64; 2]> = (0..6).map(|k| [5.0 * f64::from(k), 0.0]).collect();
        let tracker = PinTracker::new(reference.clone()).expect("tracker");
        let settled = |tracker: &PinTracker, points: &[[f64; 2]], matches: &[Option<usize>]| {
            let grid = Grid::new(points, CELL * tracker.spacing).expect("grid");
            tracker.settled(&reference, points, matches, 5.0, &grid)
        };
        // Pins 2 and 3 merged: one point between them, given to pin 2.
        let mut points = vec![
            [0.0, 0.0],
            [5.0, 0.0],
            [12.5, 0.2],
            [20.0, 0.0],
            [25.0, 0.0],
        ];
        let matches = [Some(0), Some(1), Some(2), None, Some(3), Some(4)];
        assert!(!settled(&tracker, &points, &matches));
        // The point right on pin 2: pin 3 is clearly missing.
        points[2] = [10.2, 0.1];
        assert!(settled(&tracker, &points, &matches));
        // A pin matched near the gate's edge is not settled either.
        points[2] = [14.8, 0.0];
        assert!(!settled(&tracker, &points, &matches));
        points[2] = [10.2, 0.1];
        let never = PinTracker::new(reference.clone())
            .expect("tracker")
            .with_nearest_margin(None);
        assert!(!settled(&never, &points, &matches));
    }
}

#[cfg(test)]
mod early_tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A tap on the 331-pin rings (5 px apart): a shear, jitter, and
    /// `merged` neighbouring pairs seen as one point at their midpoint, so
    /// there are fewer points than pins.
    fn merged_tap(reference: &[[f64; 2]], merged: usize, rng: &mut impl Rng) -> Vec<[f64; 2]> {
        let shear = rng.random_range(-0.12..0.12);
        let mut points: Vec<[f64; 2]> = reference
            .iter()
            .map(|r| {
                let j = 0.3;
                let y = r[1] - 64.0;
                [
                    r[0] + shear * y + rng.random_range(-j..j),
                    r[1] + rng.random_range(-j..j),
                ]
            })
            .collect();
        for _ in 0..merged {
            let a = rng.random_range(0..points.len());
            let near = (0..points.len()).filter(|&b| b != a).min_by(|&b, &c| {
                let d = |k: usize| (points[k][0] - points[a][0]).hypot(points[k][1] - points[a][1]);
                d(b).total_cmp(&d(c))
            });
            if let Some(b) = near {
                let mid = [
                    0.5 * (points[a][0] + points[b][0]),
                    0.5 * (points[a][1] + points[b][1]),
                ];
                points[a] = mid;
                points.remove(b);
            }
        }
        points
    }

    /// With fewer points than pins, an unsettled nearest-neighbour start
    /// goes to the full path before its later stages: the pins are those of
    /// the order of checks without that cut (the speed cuts off), bit for
    /// bit, and such taps occur (the early branch is taken).
    #[test]
    fn unsettled_start_with_fewer_points_falls_back_early_bit_for_bit() {
        let reference = crate::field::tests::rings();
        let fast = PinTracker::new(reference.clone()).expect("tracker");
        let plain = PinTracker::new(reference.clone())
            .expect("tracker")
            .with_speed_cuts(false);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3310);
        let mut early = 0;
        for trial in 0..60 {
            let points = merged_tap(&reference, 1 + trial % 6, &mut rng);
            assert!(points.len() < reference.len());
            let grid = Grid::new(&points, CELL * fast.spacing).expect("grid");
            if let Some(start) = fast.nearest_start(&points, &grid) {
                let after = &fast.stages[NEAREST_STAGE + 1..];
                let mut settled = true;
                let _ = fast.run_stages(start.clone(), after, &points, Some(&grid), |m| {
                    settled = fast.settled(&start, &points, m, after[0].gate, &grid);
                    false
                });
                early += usize::from(!settled);
            }
            let (a, b) = (fast.order_points(&points), plain.order_points(&points));
            let bits = |t: &super::super::Tracked| -> Vec<[u64; 2]> {
                t.pins.iter().map(|p| p.map(f64::to_bits)).collect()
            };
            assert_eq!(bits(&a.0), bits(&b.0), "trial {trial}");
            assert_eq!((a.0.matched, a.1), (b.0.matched, b.1), "trial {trial}");
        }
        assert!(early >= 5, "only {early} of 60 taps had an unsettled start");
    }
}
