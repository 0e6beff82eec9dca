//! The windowed fast path of a matching stage (issue 21, item 6).
//!
//! Each pin is looked for only in a small window: a disc of
//! [`WINDOW_REACH`] spacings around where the stage predicts it. When
//! every window holds exactly one point, no other point lies in a band of
//! [`WINDOW_BAND`] spacings around its rim and no point is in two
//! windows, each pin takes the point of its window, without the
//! candidates within the stage's gate being listed or the assignment
//! solved. Any ambiguous window (empty, two points, a point near its rim,
//! a point shared) leaves the stage to the full matching, as before.
//!
//! The result is the full matching's, not just on the frames tried: the
//! window's point is then its pin's single cheapest candidate (any other
//! point costs at least the band's outer radius squared, more than the
//! window's radius squared, and leaving the pin unassigned costs the gate
//! squared, more again since the reach is below the gate), and the
//! cheapest candidates of the pins are distinct, so the assignment is
//! exactly each pin at its own minimum (`assign.rs`,
//! `distinct_unique_minima`: the unique optimum, which the solver returns
//! as it is). The costs are computed by the same expression as the
//! matching's, so the comparison is the matching's own, bit for bit.
//!
//! A window around the rest pins moved by the centroid shift (the stage
//! before any field is fitted) was tried as a path for the whole frame:
//! on the real 127-pin frames the pins move too far against that shift
//! (the median frame has a pin 0.61 spacings off it), so almost no frame
//! took it (`docs/results/speed.md`). Around the fields' predictions of
//! the narrow stages the windows answer about two matchings in three.

use super::grid::Grid;
use super::PinTracker;

/// Radius of a pin's window, in reference spacings.
pub(super) const WINDOW_REACH: f64 = 0.45;
/// Width of the band around a window's rim (spacings) that must hold no
/// point besides the window's own.
pub(super) const WINDOW_BAND: f64 = 0.1;

impl PinTracker {
    /// Every pin predicted at `predicted` matched to the only point in its
    /// window, or `None` when a window is ambiguous, the reach is not
    /// positive or the window (with its band) is not inside the gate `gate`
    /// px. Where it answers, the full matching within the gate gives the
    /// same (see the module docs).
    pub(super) fn window_matches(
        &self,
        predicted: &[[f64; 2]],
        points: &[[f64; 2]],
        grid: &Grid,
        gate: f64,
    ) -> Option<Vec<Option<usize>>> {
        let reach = self.windows? * self.spacing;
        let outer = reach + WINDOW_BAND * self.spacing;
        if !(reach > 0.0 && outer < gate) {
            return None;
        }
        let mut taken = vec![false; points.len()];
        let mut matches = Vec::with_capacity(predicted.len());
        for p in predicted {
            let k = window_point(p, points, grid, reach, outer)?;
            if std::mem::replace(&mut taken[k], true) {
                return None;
            }
            matches.push(Some(k));
        }
        Some(matches)
    }
}

/// The only point within `reach` px of `p` when no other point lies
/// within `outer` px of it (the window and its band), else `None`.
pub(super) fn window_point(
    p: &[f64; 2],
    points: &[[f64; 2]],
    grid: &Grid,
    reach: f64,
    outer: f64,
) -> Option<usize> {
    let (reach2, outer2) = (reach * reach, outer * outer);
    let (mut own, mut clear) = (None, true);
    grid.around(p, outer, |k| {
        // The matching's cost, by the same expression.
        let dy2 = (p[1] - points[k][1]).powi(2);
        let d2 = (p[0] - points[k][0]).powi(2) + dy2;
        if d2 >= outer2 {
            return;
        }
        clear &= d2 < reach2 && own.is_none();
        own = Some(k);
    });
    own.filter(|_| clear)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tracker::grid::CELL;
    use crate::tracker::Candidates;
    use rand::{Rng, SeedableRng};
    use tactrace_testdata::layouts::hex_lattice;

    fn tracker() -> PinTracker {
        PinTracker::new(hex_lattice([100.0, 100.0], 10.0, 4)).unwrap()
    }

    /// The window matching and the full one at gate `gate` spacings.
    fn both(
        t: &PinTracker,
        predicted: &[[f64; 2]],
        points: &[[f64; 2]],
        gate: f64,
    ) -> (Option<Vec<Option<usize>>>, Vec<Option<usize>>) {
        let grid = Grid::new(points, CELL * t.spacing).unwrap();
        let gate = gate * t.spacing;
        let windows = t.window_matches(predicted, points, &grid, gate);
        let full =
            t.with_windows_off()
                .match_points(predicted, points, Candidates::Grid(&grid), gate);
        (windows, full)
    }

    impl PinTracker {
        fn with_windows_off(&self) -> PinTracker {
            PinTracker::new(self.reference.clone())
                .unwrap()
                .with_windows(None)
        }
    }

    /// Predictions within 0.07 spacings of the pins, each point within 0.2
    /// of its prediction: every other point is at least 0.66 away, outside
    /// the band, so every window answers.
    #[test]
    fn every_pin_near_its_point_is_matched_as_the_full_matching() {
        let t = tracker();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        let s = t.spacing;
        for _ in 0..50 {
            let predicted: Vec<[f64; 2]> = t
                .reference
                .iter()
                .map(|r| {
                    let j = [rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05)];
                    [r[0] + j[0] * s, r[1] + j[1] * s]
                })
                .collect();
            let mut points: Vec<[f64; 2]> = predicted
                .iter()
                .map(|p| {
                    let (a, d) = (
                        rng.random_range(0.0..6.3f64),
                        rng.random_range(0.0..0.2) * s,
                    );
                    [p[0] + d * a.cos(), p[1] + d * a.sin()]
                })
                .collect();
            // An extra point far from every pin.
            points.push([-50.0, -50.0]);
            let (windows, full) = both(&t, &predicted, &points, 1.0);
            let windows = windows.expect("every window holds its own point alone");
            assert_eq!(windows, full);
            assert!(windows.iter().enumerate().all(|(i, m)| *m == Some(i)));
        }
    }

    /// Points at the reference pins, the pins predicted there too.
    fn at_rest(t: &PinTracker) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
        (t.reference.clone(), t.reference.clone())
    }

    #[test]
    fn a_point_at_the_windows_rim_falls_back() {
        let t = tracker();
        let (predicted, mut points) = at_rest(&t);
        // Pin 5's point moved to its window's rim: just inside the band.
        points[5][0] += (WINDOW_REACH + 0.02) * t.spacing;
        let (windows, full) = both(&t, &predicted, &points, 1.0);
        assert_eq!(windows, None);
        assert_eq!(full[5], Some(5), "the full matching still pairs it");
        // Just inside the window, with the band clear: answered.
        let (predicted, mut points) = at_rest(&t);
        points[5][0] += (WINDOW_REACH - 0.02) * t.spacing;
        let (windows, full) = both(&t, &predicted, &points, 1.0);
        assert_eq!(windows, Some(full));
    }

    #[test]
    fn two_points_in_one_window_fall_back() {
        let t = tracker();
        let (predicted, mut points) = at_rest(&t);
        // A second point in pin 7's window, as a split or spurious blob.
        let p = points[7];
        points.push([p[0] + 0.15 * t.spacing, p[1]]);
        assert_eq!(both(&t, &predicted, &points, 1.0).0, None);
        // Two pins predicted on one point: the point is in two windows.
        let (mut predicted, mut points) = at_rest(&t);
        predicted[8] = predicted[7];
        points.remove(8);
        assert_eq!(both(&t, &predicted, &points, 1.0).0, None);
    }

    #[test]
    fn an_empty_window_falls_back() {
        let t = tracker();
        let (predicted, mut points) = at_rest(&t);
        points.remove(3);
        let (windows, full) = both(&t, &predicted, &points, 0.9);
        assert_eq!(windows, None);
        assert_eq!(full[3], None, "the full matching leaves it missing");
    }

    #[test]
    fn a_window_wider_than_the_gate_or_off_falls_back() {
        let t = tracker();
        let (predicted, points) = at_rest(&t);
        assert!(both(&t, &predicted, &points, 0.6).0.is_some());
        let narrow = WINDOW_REACH + WINDOW_BAND;
        assert_eq!(both(&t, &predicted, &points, narrow).0, None);
        let grid = Grid::new(&points, CELL * t.spacing).unwrap();
        let off = t.with_windows_off();
        assert_eq!(
            off.window_matches(&predicted, &points, &grid, 9.0 * t.spacing),
            None
        );
        let empty = t.with_windows_off().with_windows(Some(0.0));
        assert_eq!(
            empty.window_matches(&predicted, &points, &grid, 9.0 * t.spacing),
            None
        );
    }
}
