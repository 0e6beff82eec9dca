//! The propagated start of the first pass
//! ([`PinTracker::with_propagated_start`]): a cheap prediction of every
//! pin, grown outward over the reference layout's neighbours, in place of
//! the nearest-neighbour start's field and the narrow stages.
//!
//! The nearest-neighbour pairs of the centroid shift (`tracker/grid.rs`)
//! are the seed. From them the matches grow: an unmatched pin with matched
//! neighbours (the reference pins within 1.5 spacings, as the fold check
//! lists them) is predicted at its rest position moved by the mean of
//! their displacements, and takes the point of its window when the window
//! answers by the rule of `tracker/window.rs` (one point within 0.45
//! spacings, no other within a band of 0.1 beyond it) and no pin holds
//! that point yet; each new match is passed on to its neighbours, and a
//! pin is looked at again whenever another of its neighbours matches.
//!
//! The grown matches then predict every pin by the same mean over its
//! matched neighbours (its own point left out, so the test below is not
//! answered by the very point it tests; the affine fit of all the matches
//! for a pin with none). Only the last stage runs from those predictions
//! (its matching within 0.6 spacings, then the fill of the missing pins
//! with the kernel of 1 spacing), and its result is kept by the
//! nearest-neighbour start's own rule (`tracker/start.rs`): no neighbour
//! triangle turned over, and no pin missing or the matching settled by the
//! margin (`PinTracker::settled`). Otherwise the frame goes on to the
//! nearest-neighbour start from the same pairs, as before. A frame whose
//! growth leaves [`UNGROWN_BEYOND_DEFICIT`] or more pins unmatched beyond
//! those that must be (more pins than points) skips the last stage: on the
//! fitting part such a start almost never held, and the attempt only
//! added to the frames that go on to the slower starts. Such a growth is
//! matched again instead (`tracker/stalled.rs`), and only a frame where
//! that does not hold goes on to the nearest-neighbour start.
//!
//! The pins follow from the last matching alone (matched pins at their
//! points, the others filled from the observations), so a kept result is
//! the other starts' whenever the two last matchings agree. That is
//! measured on the shared sets, not assumed: the same pins, bit for bit,
//! on every frame (`examples/order_timing.rs --dump`; docs/results/speed.md,
//! "The first pass by propagation").

use std::collections::VecDeque;

use super::grid::{Grid, Pairs};
use super::window::{window_point, WINDOW_BAND, WINDOW_REACH};
use super::{PinTracker, Tracked};
use crate::field::fit_affine;

/// An ordering: the pins and, per pin, the index of its point.
type Found = (Tracked, Vec<Option<usize>>);

/// Pins left unmatched by the growth, beyond the frame's deficit of
/// points, from which the last stage is not tried. Chosen on the
/// e-select part (train/ frames with N % 5 = 1) of the 331-pin shear set:
/// of its 1000 frames, 847 left 0-1 such pins (the start held on 826) and
/// 153 left 2 or more (held on 16); 3 kept 12 more starts for a higher
/// p95 of thread CPU, no limit raised that p95 by a quarter.
pub(super) const UNGROWN_BEYOND_DEFICIT: usize = 2;

/// The grown matches and, per pin, the summed displacement (px) of its
/// matched neighbours and their count.
pub(super) struct Grown {
    pub(super) matches: Vec<Option<usize>>,
    sums: Vec<[f64; 2]>,
    counts: Vec<u32>,
}

impl Grown {
    /// Pins left unmatched.
    pub(super) fn ungrown(&self) -> usize {
        self.matches.iter().filter(|m| m.is_none()).count()
    }
}

impl PinTracker {
    /// The first pass from the propagated start seeded by the
    /// nearest-neighbour `pairs` (see the module docs), or `None` when it
    /// is off, no pin pairs, the growth stalls or the result does not hold.
    pub(super) fn order_propagated(
        &self,
        points: &[[f64; 2]],
        grid: &Grid,
        pairs: &Pairs,
    ) -> Option<Found> {
        if !self.propagated || pairs.1 == 0 {
            return None;
        }
        let grown = self.grow_matches(&pairs.0, points, grid);
        let deficit = self.reference.len().saturating_sub(points.len());
        if grown.ungrown() >= deficit + UNGROWN_BEYOND_DEFICIT {
            return self
                .stalled
                .then(|| self.order_stalled(grown, points, grid))
                .flatten();
        }
        let predicted = self.neighbour_means(&grown, points);
        let last = &self.stages[self.stages.len() - 1..];
        self.try_stages(last, predicted, points, grid, false).ok()
    }

    /// The matches grown from the `seed` pairs over the reference
    /// neighbours (see the module docs).
    pub(super) fn grow_matches(
        &self,
        seed: &[Option<usize>],
        points: &[[f64; 2]],
        grid: &Grid,
    ) -> Grown {
        let n = self.reference.len();
        let mut grown = Grown {
            matches: seed.to_vec(),
            sums: vec![[0.0; 2]; n],
            counts: vec![0; n],
        };
        let mut taken = vec![false; points.len()];
        let mut queue = VecDeque::with_capacity(n);
        for i in 0..n {
            if let Some(k) = grown.matches[i] {
                taken[k] = true;
                self.pass_on(i, points, &mut grown, &mut queue);
            }
        }
        let reach = WINDOW_REACH * self.spacing;
        let outer = reach + WINDOW_BAND * self.spacing;
        // A pin is looked at again only when more neighbours match.
        let mut tried = vec![0u32; n];
        while let Some(i) = queue.pop_front() {
            if grown.matches[i].is_some() || grown.counts[i] == tried[i] {
                continue;
            }
            tried[i] = grown.counts[i];
            let at = self.neighbour_mean(i, &grown);
            match window_point(&at, points, grid, reach, outer) {
                Some(k) if !taken[k] => {
                    taken[k] = true;
                    grown.matches[i] = Some(k);
                    self.pass_on(i, points, &mut grown, &mut queue);
                }
                _ => {}
            }
        }
        grown
    }

    /// Adds matched pin `i`'s displacement to its neighbours' sums and
    /// queues those still unmatched.
    fn pass_on(
        &self,
        i: usize,
        points: &[[f64; 2]],
        grown: &mut Grown,
        queue: &mut VecDeque<usize>,
    ) {
        let Some(k) = grown.matches[i] else {
            return;
        };
        let r = self.reference[i];
        let d = [points[k][0] - r[0], points[k][1] - r[1]];
        for &j in self.folds.around(i) {
            grown.sums[j] = [grown.sums[j][0] + d[0], grown.sums[j][1] + d[1]];
            grown.counts[j] += 1;
            if grown.matches[j].is_none() {
                queue.push_back(j);
            }
        }
    }

    /// Pin `i`'s rest position moved by the mean displacement of its
    /// matched neighbours (at least one), px.
    fn neighbour_mean(&self, i: usize, grown: &Grown) -> [f64; 2] {
        let (s, c) = (grown.sums[i], f64::from(grown.counts[i]));
        let r = self.reference[i];
        [r[0] + s[0] / c, r[1] + s[1] / c]
    }

    /// Every pin at its neighbours' mean ([`PinTracker::neighbour_mean`]),
    /// or where the affine fit of all the matches puts it when none of its
    /// neighbours matched.
    fn neighbour_means(&self, grown: &Grown, points: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let mut affine = None;
        (0..self.reference.len())
            .map(|i| {
                if grown.counts[i] > 0 {
                    return self.neighbour_mean(i, grown);
                }
                let fit = affine.get_or_insert_with(|| {
                    fit_affine(&self.reference, &self.displacements(&grown.matches, points))
                });
                let r = self.reference[i];
                let d = fit.apply(r);
                [r[0] + d[0], r[1] + d[1]]
            })
            .collect()
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use tactrace_testdata::layouts::hex_lattice;

    /// A tap on `reference` (pins `s` px apart around `c`): a shear and a
    /// bump that move the pins up to about half a spacing, jitter, `drop`
    /// points left out, the rest shuffled.
    fn tap(
        reference: &[[f64; 2]],
        s: f64,
        c: f64,
        drop: usize,
        rng: &mut impl Rng,
    ) -> Vec<[f64; 2]> {
        let shear = rng.random_range(-0.1..0.1);
        let bump = s * rng.random_range(0.0..0.5);
        let mut points: Vec<[f64; 2]> = reference
            .iter()
            .map(|r| {
                let (x, y) = (r[0] - c, r[1] - c);
                let g = bump * (-(x * x + y * y) / (10.0 * s * s)).exp();
                let j = 0.05 * s;
                [
                    r[0] + shear * y + g + rng.random_range(-j..j),
                    r[1] - 0.5 * g + rng.random_range(-j..j),
                ]
            })
            .collect();
        for _ in 0..drop {
            points.remove(rng.random_range(0..points.len()));
        }
        for k in (1..points.len()).rev() {
            points.swap(k, rng.random_range(0..=k));
        }
        points
    }

    /// The pins' coordinates' bits.
    pub(in crate::tracker) fn bits(t: &Tracked) -> Vec<[u64; 2]> {
        t.pins.iter().map(|p| p.map(f64::to_bits)).collect()
    }

    /// Whether the propagated start holds on `points`.
    pub(in crate::tracker) fn holds(tracker: &PinTracker, points: &[[f64; 2]]) -> bool {
        let grid = Grid::new(points, super::super::grid::CELL * tracker.spacing).expect("grid");
        let pairs = tracker.centroid_pairs(points, &grid);
        tracker.order_propagated(points, &grid, &pairs).is_some()
    }

    /// On 80 synthetic taps of each layout (the 331-pin rings, a 127-pin
    /// hexagonal lattice), a third of them with points missing, the
    /// tracker with the propagated start orders every tap as the one
    /// without it, bit for bit (pins, flags, points), and the propagated
    /// start holds on at least 30 of each (41 of the ring taps and 69 of
    /// the lattice taps when written: on the rings, whose neighbours are
    /// less regular, the growth stalls more often and the frame is left to
    /// the other starts).
    #[test]
    fn propagated_start_orders_ring_and_hex_taps_as_without_it() {
        let layouts = [
            (crate::field::tests::rings(), 5.0, 64.0),
            (hex_lattice([128.0, 128.0], 14.0, 6), 14.0, 128.0),
        ];
        for (reference, s, c) in layouts {
            let on = PinTracker::new(reference.clone()).expect("tracker");
            let off = PinTracker::new(reference.clone())
                .expect("tracker")
                .with_propagated_start(false);
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2020);
            let mut held = 0;
            for trial in 0..80 {
                let points = tap(&reference, s, c, [0, 0, 2][trial % 3], &mut rng);
                held += usize::from(holds(&on, &points));
                let (a, b) = (on.order_points(&points), off.order_points(&points));
                assert_eq!(
                    bits(&a.0),
                    bits(&b.0),
                    "{} pins, trial {trial}",
                    reference.len()
                );
                assert_eq!((&a.0.matched, &a.1), (&b.0.matched, &b.1), "trial {trial}");
            }
            eprintln!(
                "{} pins: the propagated start held on {held} of 80",
                reference.len()
            );
            assert!(held >= 30, "{} pins: held on {held} of 80", reference.len());
        }
    }

    /// Two neighbouring pins seen as one point halfway between them: the
    /// point is half a spacing from both pins' predictions, so the last
    /// stage's matching is not settled and the propagated start falls back;
    /// the tracker then orders the frame as the one without it.
    #[test]
    fn a_merged_pair_it_cannot_settle_falls_back() {
        for (reference, s) in [
            (crate::field::tests::rings(), 5.0),
            (hex_lattice([128.0, 128.0], 14.0, 6), 14.0),
        ] {
            let on = PinTracker::new(reference.clone()).expect("tracker");
            let off = PinTracker::new(reference.clone())
                .expect("tracker")
                .with_propagated_start(false);
            let mut points = reference.clone();
            // Pin 40 and its nearest other pin, merged at their midpoint.
            let (a, b) = (40, nearest_other(&reference, 40));
            assert!((points[a][0] - points[b][0]).hypot(points[a][1] - points[b][1]) < 1.2 * s);
            points[a] = [
                0.5 * (points[a][0] + points[b][0]),
                0.5 * (points[a][1] + points[b][1]),
            ];
            points.remove(b);
            assert!(!holds(&on, &points), "{} pins", reference.len());
            let (x, y) = (on.order_points(&points), off.order_points(&points));
            assert_eq!(bits(&x.0), bits(&y.0));
            assert_eq!((&x.0.matched, &x.1), (&y.0.matched, &y.1));
            assert_eq!(x.0.missing, 1);
        }
    }

    fn nearest_other(reference: &[[f64; 2]], i: usize) -> usize {
        let d =
            |j: usize| (reference[j][0] - reference[i][0]).hypot(reference[j][1] - reference[i][1]);
        (0..reference.len())
            .filter(|&j| j != i)
            .min_by(|&j, &k| d(j).total_cmp(&d(k)))
            .expect("another pin")
    }
}
