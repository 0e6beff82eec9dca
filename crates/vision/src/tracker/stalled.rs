//! The propagated start's growth when it stalls
//! ([`PinTracker::with_stalled_growth`]): a line of pins along a pressed
//! edge.
//!
//! Where an edge presses into the dome, a line of pins moves much farther
//! than the pins beside it. The growth of `tracker/propagate.rs` predicts
//! a pin by its matched neighbours' mean displacement, which cannot
//! predict that jump; worse, the nearest-neighbour seed often gave a line
//! pin's point to a neighbour that barely moved, whose own point is then
//! left free. So the growth stops with the line's pins, and pins no seed
//! reached (a rim pin with no neighbour), unmatched, and on the 127-pin
//! frames such a frame went on to the nearest-neighbour start and every
//! stage after it: about three times the ordering's usual cost, and most
//! of the frames above its p95 (docs/results/speed.md, "What sets the
//! 127-pin p95 now").
//!
//! Here the ungrown pins and a ring of their reference neighbours are
//! released and matched again, jointly, by the optimal
//! assignment (`assign.rs`): each predicted at its rest position moved by
//! the mean displacement of its matched neighbours outside that set (the
//! affine fit of all the matches for a pin with none), to the points no
//! pin outside the set holds, within [`STALLED_GATE`] spacings. A neighbour
//! that holds a line pin's point then gives it back when its own point is
//! the cheaper whole. The matches grow again from there, and the release
//! is repeated up to [`STALLED_ROUNDS`] times while pins stay ungrown.
//! When every pin that can be matched is (no more unmatched pins than the
//! frame has points too few), the last stage runs from the smooth field
//! fitted to the matches with the kernel of the stage before it: where the
//! narrow stages would have predicted from, had they matched the same.
//! The result is kept by the nearest-neighbour start's own rule
//! (`tracker/start.rs`): no neighbour triangle turned over, and no pin
//! missing or the matching settled by the margin. Otherwise the frame goes
//! on to the nearest-neighbour start, as before.
//!
//! As for the other starts, a kept result is the full path's whenever the
//! two last matchings agree; that is measured on the shared sets, not
//! assumed: the same pins, bit for bit, on every frame
//! (`examples/order_timing.rs --dump`; docs/results/speed.md, "The stalled
//! growth matched again").

use super::grid::Grid;
use super::propagate::Grown;
use super::{PinTracker, Tracked};
use crate::assign::{assign_usable, Edge, EdgeRows};
use crate::field::fit_affine;

/// An ordering: the pins and, per pin, the index of its point.
type Found = (Tracked, Vec<Option<usize>>);

/// Gate (spacings) of the released pins' assignment. With
/// [`STALLED_RINGS`], chosen by the ordering's instructions a frame on
/// the first 1000 frames of the 127-pin set (in file-name order; its
/// other 2763 frames left to score the choice): gates of 1.0, 1.2 and
/// 1.5 spacings, one or two rings in every round, or one ring then two,
/// three rounds (four added nothing); the p95 frame 330-383 k against
/// 477 k without the release, this choice 336 k with the lowest mean.
const STALLED_GATE: f64 = 1.2;
/// Per round, the rings of reference neighbours around the ungrown pins
/// released with them; there are as many rounds at most as entries. One
/// ring leaves more frames to the slower starts (p99 530-900 k), two in
/// every round cost more on the frames it holds (p95 365-383 k).
const STALLED_RINGS: [usize; 3] = [1, 2, 2];

impl PinTracker {
    /// The first pass from the stalled growth `grown` (see the module
    /// docs), or `None` when pins still do not grow or the result does
    /// not hold.
    pub(super) fn order_stalled(
        &self,
        grown: Grown,
        points: &[[f64; 2]],
        grid: &Grid,
    ) -> Option<Found> {
        let deficit = self.reference.len().saturating_sub(points.len());
        let mut grown = grown;
        for rings in STALLED_RINGS {
            let matches = self.release_and_match(&grown, points, grid, rings);
            grown = self.grow_matches(&matches, points, grid);
            if grown.ungrown() <= deficit {
                let observed = self.displacements(&grown.matches, points);
                let n = self.stages.len();
                let predicted = self.predict(&observed, &self.stages[n - 2].kernel);
                let last = &self.stages[n - 1..];
                return self.try_stages(last, predicted, points, grid, false).ok();
            }
        }
        None
    }

    /// `grown`'s matches with the ungrown pins and `rings` rings of their
    /// neighbours released and assigned anew (see the module docs).
    fn release_and_match(
        &self,
        grown: &Grown,
        points: &[[f64; 2]],
        grid: &Grid,
        rings: usize,
    ) -> Vec<Option<usize>> {
        let (released, in_set) = self.released(grown, rings);
        let mut held = vec![false; points.len()];
        for (m, _) in grown.matches.iter().zip(&in_set).filter(|(_, &r)| !r) {
            if let Some(k) = *m {
                held[k] = true;
            }
        }
        let gate = STALLED_GATE * self.spacing;
        let gate2 = gate * gate;
        let mut affine = None;
        let mut rows = EdgeRows::with_capacity(released.len(), 16 * released.len());
        for (row, &i) in released.iter().enumerate() {
            let at = self
                .outside_mean(i, grown, &in_set, points)
                .unwrap_or_else(|| {
                    let fit = affine.get_or_insert_with(|| {
                        fit_affine(&self.reference, &self.displacements(&grown.matches, points))
                    });
                    let (r, d) = (self.reference[i], fit.apply(self.reference[i]));
                    [r[0] + d[0], r[1] + d[1]]
                });
            grid.around(&at, gate, |k| {
                let cost = (at[0] - points[k][0]).powi(2) + (at[1] - points[k][1]).powi(2);
                if !held[k] && cost < gate2 {
                    rows.edges.push(Edge { col: k, cost });
                }
            });
            // The pin's own "unassigned" column.
            rows.edges.push(Edge {
                col: points.len() + row,
                cost: gate2,
            });
            rows.end_row();
        }
        let mut matches = grown.matches.clone();
        for (&i, k) in released.iter().zip(assign_usable(points.len(), &rows)) {
            matches[i] = k;
        }
        matches
    }

    /// The ungrown pins and `rings` rings of their neighbours, in the
    /// order found, and per pin whether it is one of them.
    fn released(&self, grown: &Grown, rings: usize) -> (Vec<usize>, Vec<bool>) {
        let n = self.reference.len();
        let mut in_set: Vec<bool> = grown.matches.iter().map(Option::is_none).collect();
        let mut released: Vec<usize> = (0..n).filter(|&i| in_set[i]).collect();
        let mut from = 0;
        for _ in 0..rings {
            let to = released.len();
            for s in from..to {
                for &j in self.folds.around(released[s]) {
                    if !std::mem::replace(&mut in_set[j], true) {
                        released.push(j);
                    }
                }
            }
            from = to;
        }
        (released, in_set)
    }

    /// Pin `i`'s rest position moved by the mean displacement of its
    /// matched neighbours outside the released set, px; `None` when it
    /// has none.
    fn outside_mean(
        &self,
        i: usize,
        grown: &Grown,
        in_set: &[bool],
        points: &[[f64; 2]],
    ) -> Option<[f64; 2]> {
        let (mut sum, mut count) = ([0.0; 2], 0.0);
        for &j in self.folds.around(i).iter().filter(|&&j| !in_set[j]) {
            if let Some(k) = grown.matches[j] {
                let r = self.reference[j];
                sum = [sum[0] + points[k][0] - r[0], sum[1] + points[k][1] - r[1]];
                count += 1.0;
            }
        }
        let r = self.reference[i];
        (count > 0.0).then(|| [r[0] + sum[0] / count, r[1] + sum[1] / count])
    }
}

#[cfg(test)]
mod tests {
    use super::super::propagate::tests::{bits, holds};
    use super::*;
    use rand::{Rng, SeedableRng};
    use tactrace_testdata::layouts::hex_lattice;

    /// A tap that presses a line into a hexagonal layout (pins `s` px
    /// apart around `c`): the pins within about half a spacing of a line
    /// through a point near the centre jump across it by `jump` spacings,
    /// the others move little; jitter; the points shuffled. Returns the
    /// points and, per pin, the index of its point.
    fn pressed_line(
        reference: &[[f64; 2]],
        s: f64,
        c: f64,
        jump: f64,
        rng: &mut impl Rng,
    ) -> (Vec<[f64; 2]>, Vec<usize>) {
        let a = rng.random_range(0.0..std::f64::consts::PI);
        let (nx, ny) = (-a.sin(), a.cos());
        let o = [c + rng.random_range(-s..s), c + rng.random_range(-s..s)];
        let moved: Vec<[f64; 2]> = reference
            .iter()
            .map(|r| {
                let d = ((r[0] - o[0]) * nx + (r[1] - o[1]) * ny) / s;
                let g = jump * s * (-(d / 0.45).powi(2)).exp();
                let j = 0.04 * s;
                [
                    r[0] + g * nx + rng.random_range(-j..j),
                    r[1] + g * ny + rng.random_range(-j..j),
                ]
            })
            .collect();
        let mut order: Vec<usize> = (0..moved.len()).collect();
        for k in (1..order.len()).rev() {
            order.swap(k, rng.random_range(0..=k));
        }
        let points = order.iter().map(|&i| moved[i]).collect();
        let mut truth = vec![0; moved.len()];
        for (k, &i) in order.iter().enumerate() {
            truth[i] = k;
        }
        (points, truth)
    }

    /// On 60 taps that press a line into a 127-pin hexagonal layout, the
    /// tracker orders every tap as the full path (no nearest-neighbour
    /// start) and as the tracker without the stalled growth's release,
    /// bit for bit, and every pin at its own point; the propagated start
    /// holds on more taps with the release than without it.
    #[test]
    fn a_pressed_line_is_matched_again_and_ordered_as_the_full_path() {
        let (s, c) = (14.0, 128.0);
        let reference = hex_lattice([c, c], s, 6);
        let on = PinTracker::new(reference.clone()).expect("tracker");
        let off = PinTracker::new(reference.clone())
            .expect("tracker")
            .with_stalled_growth(false);
        let full = PinTracker::new(reference.clone())
            .expect("tracker")
            .with_nearest_start(false);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2024);
        let (mut held_on, mut held_off) = (0, 0);
        for trial in 0..60 {
            let jump = rng.random_range(0.5..0.75);
            let (points, truth) = pressed_line(&reference, s, c, jump, &mut rng);
            held_on += usize::from(holds(&on, &points));
            held_off += usize::from(holds(&off, &points));
            let a = on.order_points(&points);
            let expected: Vec<Option<usize>> = truth.iter().map(|&k| Some(k)).collect();
            assert_eq!(a.1, expected, "trial {trial}: a pin off its own point");
            for other in [&off, &full] {
                let b = other.order_points(&points);
                assert_eq!(bits(&a.0), bits(&b.0), "trial {trial}");
                assert_eq!(a.1, b.1, "trial {trial}");
            }
        }
        eprintln!(
            "the propagated start held on {held_on} of 60 taps, {held_off} without the release"
        );
        assert!(held_on > held_off + 10, "{held_on} against {held_off}");
    }
}
