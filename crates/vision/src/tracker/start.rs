//! The nearest-neighbour start of the coarse-to-fine matching
//! (`tracker/grid.rs`) and its second try (issue 21, item 6).
//!
//! A start is kept when its result turns no neighbour triangle over and
//! either no pin is missing or its first matching is settled; otherwise
//! the frame runs every stage from the centroid shift. On the real 127-pin
//! frames nearly every dropped start is one under a large shear (pins
//! moved about half a spacing against the centroid shift): the pairs of
//! nearest neighbours thin out where the pins moved most, the field fitted
//! to them misses there, and a few pins and as many points stay unmatched.
//! (The pairs grown before the start, `tracker/grid.rs`, hold it on about
//! half of those frames.) The pins that result are still near their
//! points almost everywhere, so the start is tried once more from them: their nearest neighbours, the
//! field fitted to those pairs, the narrow stages, kept by the same rule.
//! On the 331-pin frames, with fewer points than pins (merged or unseen
//! pins), the first try is dropped when its first matching is not
//! settled; its stages then run on all the same, to give the second its
//! pins. A result so kept is the full path's whenever the first one would
//! have been (the rule, not the way there, decides): checked bit for bit
//! on every frame of the shared sets (`tests/it/speed.rs`,
//! `examples/order_timing.rs --full --compare`: all 3763 127-pin frames,
//! all 5000 train/ and 2000 val/ frames of the 331-pin shear set) and on
//! synthetic taps (the tests here).

use super::grid::{Grid, Pairs, NEAREST_STAGE};
use super::{PinTracker, Stage, Tracked};

/// An ordering: the pins and, per pin, the index of its point.
type Found = (Tracked, Vec<Option<usize>>);

impl PinTracker {
    /// The ordering from the nearest-neighbour start, or from the second
    /// start when the first is dropped ([`PinTracker::with_second_start`]);
    /// `None` when neither holds (the caller runs every stage from the
    /// centroid shift). `pairs`: the nearest-neighbour pairs of the
    /// centroid shift ([`PinTracker::centroid_pairs`]).
    pub(super) fn order_from_nearest(
        &self,
        points: &[[f64; 2]],
        grid: &Grid,
        pairs: Pairs,
    ) -> Option<Found> {
        let start = self.grown_start(pairs, points, grid)?;
        let pins = match self.try_start(start, points, grid, self.second) {
            Ok(found) => return Some(found),
            Err(pins) => pins.filter(|_| self.second)?,
        };
        let start = self.nearest_from(&pins, points, grid)?;
        self.try_start(start, points, grid, false).ok()
    }

    /// The stages after the start's kernel from the pins predicted at
    /// `start`; `Ok` when the result holds, else `Err` with the pins it
    /// gave. With fewer points than pins some pin is missing whatever the
    /// stages match, so an unsettled first matching cannot hold: unless
    /// `pins_wanted`, the stages stop there (`Err(None)`).
    pub(super) fn try_start(
        &self,
        start: Vec<[f64; 2]>,
        points: &[[f64; 2]],
        grid: &Grid,
        pins_wanted: bool,
    ) -> Result<Found, Option<Vec<[f64; 2]>>> {
        let after = &self.stages[NEAREST_STAGE + 1..];
        self.try_stages(after, start, points, grid, pins_wanted)
    }

    /// [`PinTracker::try_start`] running the stages `after` (at least one)
    /// from the pins at `start`, kept by the same rule (its first matching
    /// settled by the gate of the first of `after`).
    pub(super) fn try_stages(
        &self,
        after: &[Stage],
        start: Vec<[f64; 2]>,
        points: &[[f64; 2]],
        grid: &Grid,
        pins_wanted: bool,
    ) -> Result<Found, Option<Vec<[f64; 2]>>> {
        let must_miss = points.len() < self.reference.len();
        let settled =
            |first: &[Option<usize>]| self.settled(&start, points, first, after[0].gate, grid);
        // The first matching, when whether it settles is left until after
        // the stages (`None`: checked already, and settled).
        let mut first = None;
        let early = |matches: &[Option<usize>]| {
            if must_miss && self.cuts && !pins_wanted {
                return settled(matches);
            }
            first = Some(matches.to_vec());
            true
        };
        let (tracked, matches) = self
            .run_stages(start.clone(), after, points, Some(grid), early)
            .ok_or(None)?;
        let holds = tracked.missing == 0 || first.as_deref().is_none_or(settled);
        if holds && !self.folds.any_turned(&tracked.pins) {
            return Ok((tracked, matches));
        }
        Err(Some(tracked.pins))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use tactrace_testdata::layouts::hex_lattice;

    /// A tap on a layout of pins `spacing` px apart around `centre`: a
    /// sliding bump, up to two spacings off the centre, moves the pins
    /// under it by 0.6-1.4 spacings one way and the rest little, with
    /// jitter; the points shuffled.
    fn sheared_tap(
        reference: &[[f64; 2]],
        spacing: f64,
        centre: [f64; 2],
        rng: &mut impl Rng,
    ) -> Vec<[f64; 2]> {
        moved_tap(reference, spacing, centre, rng, |rng| {
            let size = rng.random_range(0.6..1.4) * spacing;
            let width = rng.random_range(1.5..3.0) * spacing;
            move |d2| size * (-d2 / (2.0 * width * width)).exp()
        })
    }

    /// A tap whose pins move one way (a drawn angle) by `lift(d2)` px, `d2`
    /// their squared distance from a point up to two spacings off
    /// `centre` (`lift` drawn by `shape`), with jitter; the points shuffled.
    fn moved_tap<R: Rng, L: Fn(f64) -> f64>(
        reference: &[[f64; 2]],
        spacing: f64,
        centre: [f64; 2],
        rng: &mut R,
        shape: impl FnOnce(&mut R) -> L,
    ) -> Vec<[f64; 2]> {
        let off = 2.0 * spacing;
        let c = [
            centre[0] + rng.random_range(-off..off),
            centre[1] + rng.random_range(-off..off),
        ];
        let a = rng.random_range(0.0..std::f64::consts::TAU);
        let lift = shape(rng);
        let mut points: Vec<[f64; 2]> = reference
            .iter()
            .map(|r| {
                let g = lift((r[0] - c[0]).powi(2) + (r[1] - c[1]).powi(2));
                let j = 0.05 * spacing;
                [
                    r[0] + g * a.cos() + rng.random_range(-j..j),
                    r[1] + g * a.sin() + rng.random_range(-j..j),
                ]
            })
            .collect();
        for k in (1..points.len()).rev() {
            points.swap(k, rng.random_range(0..=k));
        }
        points
    }

    /// The pins' coordinates' bits.
    fn bits(t: &Tracked) -> Vec<[u64; 2]> {
        t.pins.iter().map(|p| p.map(f64::to_bits)).collect()
    }

    /// Whether the first start at `points` is dropped and the second
    /// holds.
    fn second_holds(tracker: &PinTracker, points: &[[f64; 2]]) -> bool {
        let grid = Grid::new(points, super::super::grid::CELL * tracker.spacing).expect("grid");
        let Some(start) = tracker.nearest_start(points, &grid) else {
            return false;
        };
        let Err(Some(pins)) = tracker.try_start(start, points, &grid, true) else {
            return false;
        };
        tracker
            .nearest_from(&pins, points, &grid)
            .is_some_and(|start| tracker.try_start(start, points, &grid, false).is_ok())
    }

    /// Asserts that `trackers` order `points` as `full` does, bit for bit
    /// (the first also with the same matched flags and points).
    fn assert_as_full(
        trackers: [&PinTracker; 2],
        full: &PinTracker,
        points: &[[f64; 2]],
        trial: usize,
    ) {
        let c = full.order_points(points);
        let a = trackers[0].order_points(points);
        assert_eq!(bits(&a.0), bits(&c.0), "trial {trial}");
        assert_eq!((&a.0.matched, &a.1), (&c.0.matched, &c.1), "trial {trial}");
        let b = trackers[1].order_points(points);
        assert_eq!(bits(&b.0), bits(&c.0), "trial {trial}");
    }

    /// Orders every tap of `taps` on `reference` with the default tracker,
    /// the one without the second start and the full path (no
    /// nearest-neighbour start), asserts the three the same bit for bit,
    /// and returns on how many taps the second start held.
    fn second_starts(reference: &[[f64; 2]], taps: impl Iterator<Item = Vec<[f64; 2]>>) -> usize {
        let tracker = || PinTracker::new(reference.to_vec()).expect("tracker");
        let (fast, once) = (tracker(), tracker().with_second_start(false));
        let full = tracker().with_nearest_start(false);
        let mut second = 0;
        for (trial, points) in taps.enumerate() {
            second += usize::from(second_holds(&fast, &points));
            assert_as_full([&fast, &once], &full, &points, trial);
        }
        second
    }

    /// On 120 synthetic taps with a sliding bump (pins moved up to 1.4
    /// spacings where the centroid shift barely moves), the tracker orders
    /// every tap as the full coarse-to-fine path and as the tracker without
    /// the second start, bit for bit; and the second start is what holds
    /// on some of them.
    #[test]
    fn second_start_orders_sheared_127_pin_taps_as_the_full_path() {
        let spacing = 14.0;
        let reference = hex_lattice([128.0, 128.0], spacing, 6);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(127);
        let taps = (0..120).map(|_| sheared_tap(&reference, spacing, [128.0, 128.0], &mut rng));
        let second = second_starts(&reference, taps);
        assert!(second >= 8, "the second start held on {second} of 120 taps");
    }

    /// The start's predictions' bits, grown or not (`None`: too few pairs).
    fn start_bits(tracker: &PinTracker, points: &[[f64; 2]]) -> Option<Vec<[u64; 2]>> {
        let grid = Grid::new(points, super::super::grid::CELL * tracker.spacing).expect("grid");
        let start = tracker.nearest_start(points, &grid)?;
        Some(start.iter().map(|p| p.map(f64::to_bits)).collect())
    }

    /// On 120 synthetic 127-pin taps with a patch of pins slid most of a
    /// spacing (so that fewer than 85 % of the pins pair from the centroid
    /// shift), the tracker that grows the nearest-neighbour pairs orders
    /// every tap as the one that does not and as the full path, bit for
    /// bit; and the pairs do grow (another start) on some taps. (On these
    /// taps no first start holds, grown or not; on the real frames the
    /// grown one holds on about half of the frames that needed the second
    /// start: docs/vision.md.)
    #[test]
    fn grown_pairs_order_sheared_taps_as_the_full_path() {
        let spacing = 14.0;
        let reference = hex_lattice([128.0, 128.0], spacing, 6);
        let tracker = || PinTracker::new(reference.clone()).expect("tracker");
        let (grown, plain) = (tracker(), tracker().with_grown_pairs(false));
        let full = tracker().with_nearest_start(false);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(128);
        let mut other_starts = 0;
        for trial in 0..120 {
            // The pins within 2-3 spacings of the point slide 0.7-1.0
            // spacings, the rest stay.
            let points = moved_tap(&reference, spacing, [128.0, 128.0], &mut rng, |rng| {
                let radius = rng.random_range(2.0..3.0) * spacing;
                let size = rng.random_range(0.7..1.0) * spacing;
                move |d2| if d2 < radius * radius { size } else { 0.0 }
            });
            other_starts += usize::from(start_bits(&grown, &points) != start_bits(&plain, &points));
            assert_as_full([&grown, &plain], &full, &points, trial);
        }
        assert!(
            other_starts >= 5,
            "the pairs grew on {other_starts} of 120 taps"
        );
    }

    /// On 100 synthetic taps of the 331-pin rings with a sliding bump and
    /// one to four pins not detected (fewer points than pins, so a start
    /// holds only when its first matching is settled), the tracker orders
    /// every tap as the full path and as the tracker without the second
    /// start, bit for bit; and the second start, taken after a first one
    /// stopped unsettled, is what holds on some of them.
    #[test]
    fn second_start_orders_331_pin_taps_with_pins_missing_as_the_full_path() {
        let reference = crate::field::tests::rings();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3311);
        let taps = (0..100).map(|trial| {
            let mut points = sheared_tap(&reference, 5.0, [64.0, 64.0], &mut rng);
            for _ in 0..1 + trial % 4 {
                points.remove(rng.random_range(0..points.len()));
            }
            points
        });
        let second = second_starts(&reference, taps);
        assert!(second >= 8, "the second start held on {second} of 100 taps");
    }
}
