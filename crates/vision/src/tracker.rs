//! Puts detected blobs into the order of the reference pins (report ch. 4.1:
//! the displacement vector compares each pin with its own rest position).
//! Pins can move further than their spacing, so nearest-neighbour matching
//! swaps them; instead the tracker works coarse to fine: predict every pin
//! from a smooth displacement field, solve an optimal one-to-one assignment
//! within a gate, refit the field from the matches with a narrower kernel,
//! and repeat. Missing pins are filled from the final field. A result with
//! a neighbour triangle turned over (a swap, see [`crate::fold`]) is
//! repaired locally; fold-free results are returned as they are.

use crate::assign::{assign_usable, Edge, EdgeRows};
use crate::blob::KeyPoint;
use crate::detection::Detection;
use crate::error::VisionError;
use crate::field::{fill_missing, smooth_field, Kernel, Observations, EXACT_TOLERANCE};
use crate::fold::FoldCheck;
use crate::merged::Cluster;

mod grid;
mod propagate;
mod repair;
mod split;
mod stalled;
mod start;
mod window;

use grid::Grid;

/// Fewest reference pins that define an affine field.
const MIN_REFERENCE_PINS: usize = 3;
/// Weight of the affine prior in the local residual average (matched pins).
const PRIOR_WEIGHT: f64 = 0.2;
/// A missing pin predicted within this many spacings of a cluster's pixels
/// is taken to be inside it.
const CLUSTER_REACH: f64 = 0.35;

/// One coarse-to-fine pass: matching gate, then the kernel refitted after it
/// (both in units of the reference pin spacing).
struct Stage {
    gate: f64,
    kernel: Kernel,
}

/// The coarse-to-fine stages: gate and kernel width (spacings), and the
/// tolerance below which the cut field drops a kernel weight.
const STAGES: [(f64, f64, f64); 4] = [
    (3.0, 3.0, CUT_TOLERANCE),
    (1.5, 2.0, CUT_TOLERANCE),
    (1.0, 1.2, CUT_TOLERANCE),
    (0.6, 1.0, EXACT_TOLERANCE),
];

/// Fewest reference pins for which the tracker cuts the smooth field by
/// default ([`PinTracker::with_exact_field`]): below it the exact field is
/// cheap (127 pins) and the ordering stays what it was, bit for bit.
pub const CUT_MIN_PINS: usize = 200;

/// Kernel weights below this share of the peak are dropped in the cut
/// field of the wide stages (those whose field only predicts where the next
/// stage looks).
pub const CUT_TOLERANCE: f64 = 1e-2;

/// The stages for a reference layout of median spacing `spacing` px.
fn stages(reference: &[[f64; 2]], spacing: f64, exact: bool) -> Vec<Stage> {
    STAGES
        .iter()
        .map(|&(gate, sigma, cut)| Stage {
            gate: gate * spacing,
            kernel: Kernel::new(
                reference,
                sigma * spacing,
                if exact { EXACT_TOLERANCE } else { cut },
            )
            .with_prior(PRIOR_WEIGHT),
        })
        .collect()
}

/// Orders keypoints like a fixed reference pin set.
pub struct PinTracker {
    reference: Vec<[f64; 2]>,
    spacing: f64,
    stages: Vec<Stage>,
    folds: FoldCheck,
    /// Whether the matching may start from nearest neighbours
    /// (`tracker/grid.rs`).
    nearest: bool,
    /// Margin (in squared spacings) by which a nearest-neighbour start with
    /// pins missing must settle every pairing; `None`: such starts are
    /// never kept.
    nearest_margin: Option<f64>,
    /// Whether the speed cuts that change no pin are on
    /// ([`PinTracker::with_speed_cuts`]).
    cuts: bool,
    /// Whether a dropped nearest-neighbour start is tried once more from
    /// its own pins ([`PinTracker::with_second_start`]).
    second: bool,
    /// Whether the nearest-neighbour pairs grow from the field fitted to
    /// them before the start ([`PinTracker::with_grown_pairs`]).
    grow: bool,
    /// Radius (spacings) of the pins' windows of the fast path, `None`
    /// for none ([`PinTracker::with_windows`]).
    windows: Option<f64>,
    /// Whether the split pass starts from the first pass's pins
    /// ([`PinTracker::with_seeded_split`]).
    seeded: bool,
    /// Whether the first pass tries the propagated start first
    /// ([`PinTracker::with_propagated_start`]).
    propagated: bool,
    /// Whether the start scales the reference to the points' spread
    /// ([`PinTracker::with_scaled_start`]).
    scaled: bool,
    /// Whether a stalled propagated growth is matched again
    /// ([`PinTracker::with_stalled_growth`]).
    stalled: bool,
}

/// The first pass of the ordering on one frame's keypoints
/// ([`PinTracker::first_pass`]).
pub struct FirstPass {
    points: Vec<[f64; 2]>,
    tracked: Tracked,
    /// Per pin, the index of its point.
    sources: Vec<Option<usize>>,
}

impl FirstPass {
    /// The pins as [`PinTracker::order`] gives them.
    pub fn tracked(&self) -> &Tracked {
        &self.tracked
    }

    /// The pins, as [`FirstPass::tracked`].
    pub fn into_tracked(self) -> Tracked {
        self.tracked
    }
}

/// Pins in reference order for one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Tracked {
    /// Pin centres, px, same order and length as the reference; a missing
    /// pin holds the position the smooth field of its neighbours predicts.
    pub pins: Vec<[f64; 2]>,
    /// `false` where the pin was filled in rather than detected.
    pub matched: Vec<bool>,
    /// Reference pins with no detected blob.
    pub missing: usize,
    /// Detected blobs assigned to no pin.
    pub extra: usize,
}

impl Tracked {
    /// Displacement vector, all x then all y (2P values, px), pins minus
    /// reference (report ch. 4.1). Pairs beyond the shorter slice are dropped.
    pub fn displacement(&self, reference: &[[f64; 2]]) -> Vec<f32> {
        let pairs = self.pins.iter().zip(reference);
        let xs = pairs.clone().map(|(p, r)| (p[0] - r[0]) as f32);
        let ys = pairs.map(|(p, r)| (p[1] - r[1]) as f32);
        xs.chain(ys).collect()
    }

    /// Number of pins matched to a detected blob.
    pub fn matched_count(&self) -> usize {
        self.matched.iter().filter(|&&m| m).count()
    }
}

impl PinTracker {
    /// A tracker for the rest pin centres `reference` (px, from the
    /// undeformed frame). Needs at least three distinct, finite pins.
    pub fn new(reference: Vec<[f64; 2]>) -> Result<Self, VisionError> {
        if reference.len() < MIN_REFERENCE_PINS {
            return Err(VisionError::TooFewReferencePins {
                found: reference.len(),
                required: MIN_REFERENCE_PINS,
            });
        }
        if let Some(index) = reference
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            return Err(VisionError::NonFiniteReference { index });
        }
        let spacing = median_spacing(&reference);
        if spacing.is_nan() || spacing <= 0.0 {
            return Err(VisionError::DegenerateReference);
        }
        let exact = reference.len() < CUT_MIN_PINS;
        Ok(Self {
            folds: FoldCheck::new(&reference, spacing),
            stages: stages(&reference, spacing, exact),
            reference,
            spacing,
            nearest: true,
            nearest_margin: Some(grid::NEAREST_MARGIN),
            cuts: true,
            second: true,
            grow: true,
            windows: Some(window::WINDOW_REACH),
            seeded: true,
            propagated: true,
            scaled: true,
            stalled: true,
        })
    }

    /// This tracker with the exact smooth field (every kernel weight down
    /// to [`EXACT_TOLERANCE`]; the default below [`CUT_MIN_PINS`] pins) or
    /// the cut one (the wide stages' kernels cut at [`CUT_TOLERANCE`]; the
    /// default from [`CUT_MIN_PINS`] pins). Kept to check that the cut
    /// changes nothing that matters (`tests/it/cut_field.rs`).
    pub fn with_exact_field(mut self, exact: bool) -> Self {
        self.stages = stages(&self.reference, self.spacing, exact);
        self
    }

    /// This tracker with the nearest-neighbour start on (the default) or
    /// off. Off, every frame runs all the coarse-to-fine stages from the
    /// centroid shift: slower, the same result on the shared sets
    /// (`tests/it/speed.rs`), kept to check that.
    pub fn with_nearest_start(mut self, on: bool) -> Self {
        self.nearest = on;
        self
    }

    /// This tracker keeping a nearest-neighbour start that leaves pins
    /// missing only when its first matching is clear by `margin` squared
    /// spacings (see `tracker/grid.rs`); `None` never keeps such a start
    /// (the behaviour before the margin). Kept to measure the margin
    /// against the full path (`examples/order_timing.rs`).
    pub fn with_nearest_margin(mut self, margin: Option<f64>) -> Self {
        self.nearest_margin = margin;
        self
    }

    /// This tracker with the speed cuts that change no pin on (the
    /// default) or off: the last stage's field computed only at the
    /// missing pins; the widest stage's candidates taken from the grid
    /// and its edge buffer sized for its gate; the split pass's cluster
    /// lookups pruned (`tracker/split.rs`); an unsettled nearest-neighbour
    /// start with fewer points than pins dropped right after its first
    /// matching (`PinTracker::coarse_to_fine`). Off, the ordering is computed as before them, to the
    /// same pins bit for bit; kept to check that (`tests/it/speed_cuts.rs`,
    /// `examples/order_timing.rs --plain`).
    pub fn with_speed_cuts(mut self, on: bool) -> Self {
        self.cuts = on;
        self
    }

    /// This tracker trying a dropped nearest-neighbour start once more,
    /// from the nearest neighbours of the pins it gave (the default), or
    /// not (every such frame runs all the stages from the centroid shift,
    /// as before). The same pins on the shared sets (`tests/it/speed.rs`);
    /// kept to check that and to time it (`tracker/start.rs`).
    pub fn with_second_start(mut self, on: bool) -> Self {
        self.second = on;
        self
    }

    /// This tracker growing the nearest-neighbour pairs before a start
    /// (the default: unpaired pins, put where the field fitted to the
    /// pairs puts them, pair with free points by the same rule, a few
    /// rounds; see `tracker/grid.rs`) or not (the start from the first
    /// pairs alone, as before). The same pins on the shared sets
    /// (`tests/it/speed.rs`); kept to check that and to time it.
    pub fn with_grown_pairs(mut self, on: bool) -> Self {
        self.grow = on;
        self
    }

    /// This tracker with the windowed fast path of its matchings (the
    /// default: each pin looked for in a window of `reach` spacings around
    /// its prediction, every pin taking the only point of its window when
    /// no window is ambiguous; see `tracker/window.rs`) or without it
    /// (`None`: every stage lists its candidates and solves the
    /// assignment, as before). The same matchings by construction, for any
    /// reach whose window and band fit in the stage's gate (wider ones
    /// are not used); kept to check that (`tests/it/speed.rs`) and to time it.
    pub fn with_windows(mut self, reach: Option<f64>) -> Self {
        self.windows = reach;
        self
    }

    /// This tracker ordering the split pass's points from the first
    /// pass's pins (the default: its last stage, else its narrow stages,
    /// predicted from them, kept by the nearest-neighbour start's rule;
    /// see `tracker/split.rs`) or from scratch (`false`: every start
    /// tried anew, as before). The same pins on the shared sets
    /// (`tests/it/speed_cuts.rs`); kept to check that and to time it.
    pub fn with_seeded_split(mut self, on: bool) -> Self {
        self.seeded = on;
        self
    }

    /// This tracker trying the propagated start first in the first pass
    /// (the default: matches grown outward from the nearest-neighbour
    /// pairs over the reference neighbours, each pin then predicted by
    /// its matched neighbours' mean displacement, and the last stage
    /// alone run from there, kept by the nearest-neighbour start's rule;
    /// see `tracker/propagate.rs`) or not (`false`: the nearest-neighbour
    /// start and the narrow stages, as before). The same pins on the
    /// shared sets (docs/results/speed.md); kept to check that and to
    /// time it (`examples/order_timing.rs --unpropagated`).
    pub fn with_propagated_start(mut self, on: bool) -> Self {
        self.propagated = on;
        self
    }

    /// This tracker starting from the reference moved by the centroids'
    /// difference and, on a frame with as many points as pins, scaled
    /// about its centroid by the ratio of the two point sets'
    /// root-mean-square distances from their centroids (the default: a
    /// pressed dome spreads its pins, about 4 % between the 127-pin set's
    /// undeformed frame and its taps), or only moved (as before). With
    /// pins missing or extra points the spreads say little (a scaled start
    /// on those frames changed a synthetic sensor's ordering), so those
    /// frames are only moved. Both starts, the stages' and the
    /// nearest-neighbour ones, begin there. The same pins, bit for bit, on every frame of the
    /// shared sets (`tests/it/speed.rs`), for fewer failed starts; kept to
    /// check that and to time it (`examples/order_timing.rs --unscaled`).
    pub fn with_scaled_start(mut self, on: bool) -> Self {
        self.scaled = on;
        self
    }

    /// This tracker matching again the propagated start's growth where it
    /// stalls (the default: the ungrown pins and a ring of their
    /// neighbours, two in the later rounds, assigned anew, jointly, the
    /// growth resumed, then the last stage; see `tracker/stalled.rs`) or not (`false`: such a frame
    /// goes on to the nearest-neighbour start, as before). The same pins,
    /// bit for bit, on every frame of the shared sets
    /// (docs/results/speed.md); kept to check that and to time it
    /// (`examples/order_timing.rs --unstalled`).
    pub fn with_stalled_growth(mut self, on: bool) -> Self {
        self.stalled = on;
        self
    }

    /// The rest pin centres, px.
    pub fn reference(&self) -> &[[f64; 2]] {
        &self.reference
    }

    /// Median nearest-neighbour distance of the reference pins, px.
    pub fn spacing(&self) -> f64 {
        self.spacing
    }

    /// Number of triangles of neighbouring reference pins that `tracked`
    /// turns over (signed-area ratio below [`crate::TURNED_RATIO`]; 0 for a
    /// correct ordering, a swap of two pins gives a few).
    pub fn turned_triangles(&self, tracked: &Tracked) -> usize {
        self.folds.turned(&tracked.pins).len()
    }

    /// Number of neighbour triangles of the reference that the fold check
    /// watches.
    pub fn triangle_count(&self) -> usize {
        self.folds.len()
    }

    /// Assigns keypoints to reference pins (see the module docs). Never
    /// fails: with no keypoints every pin is missing and sits at rest.
    pub fn order(&self, keypoints: &[KeyPoint]) -> Tracked {
        self.order_points(&finite_centres(keypoints)).0
    }

    /// [`PinTracker::order`], then, if pins are missing, a second pass where
    /// each cluster of touching pins (see [`crate::find_clusters`]) that has
    /// missing pins predicted on it is split into as many centres as pins
    /// it holds. The second pass is kept when it matches at least as many pins.
    /// If the kept result has a turned-over triangle, the clusters around it
    /// are split anew (see `tracker/repair.rs`).
    pub fn order_with_clusters(&self, keypoints: &[KeyPoint], clusters: &[Cluster]) -> Tracked {
        self.split_pass(self.first_pass(keypoints), clusters)
    }

    /// [`PinTracker::order`] on a detection's points, then, if pins are
    /// missing and it has clusters, [`PinTracker::order_with_clusters`]
    /// (the first pass run once).
    pub fn track(&self, detection: &Detection) -> Tracked {
        let first = self.first_pass(&detection.points);
        if first.tracked.missing == 0 || detection.clusters.is_empty() {
            return first.tracked;
        }
        self.split_pass(first, &detection.clusters)
    }

    /// The first pass of [`PinTracker::order_with_clusters`]: its
    /// [`FirstPass::tracked`] is what [`PinTracker::order`] gives. When
    /// pins are missing, [`PinTracker::split_pass`] goes on from it without
    /// running it again.
    pub fn first_pass(&self, keypoints: &[KeyPoint]) -> FirstPass {
        let points = finite_centres(keypoints);
        let (tracked, sources) = self.order_points(&points);
        FirstPass {
            points,
            tracked,
            sources,
        }
    }

    /// The coarse-to-fine matching on finite points, then, only if a
    /// neighbour triangle has turned over, the local repair
    /// ([`PinTracker::unfold`]); also returns, per pin, the index of its point.
    fn order_points(&self, points: &[[f64; 2]]) -> (Tracked, Vec<Option<usize>>) {
        let (tracked, matches) = self.coarse_to_fine(points);
        if self.folds.any_turned(&tracked.pins) {
            return self.unfold(points, tracked, matches);
        }
        (tracked, matches)
    }

    /// The coarse-to-fine stages and the fill of missing pins: from the
    /// propagated start where it holds (`tracker/propagate.rs`), else from
    /// the nearest-neighbour start where it holds (no pin missing, or its first
    /// matching settled; see `tracker/grid.rs`), or from the second start
    /// taken from a dropped one's pins (`tracker/start.rs`), else every
    /// stage from the centroid shift. With fewer points than pins some pin
    /// is missing whatever the stages match (the matching is one to one),
    /// so a start holds only if its first matching is settled: that is
    /// checked before the later stages run, and an unsettled start is
    /// dropped at once (the same result, without the stages it would drop).
    fn coarse_to_fine(&self, points: &[[f64; 2]]) -> (Tracked, Vec<Option<usize>>) {
        let grid = Grid::new(points, grid::CELL * self.spacing);
        if let (true, Some(grid)) = (self.nearest, &grid) {
            // The pairs of the centroid shift, which both starts begin from.
            let pairs = self.centroid_pairs(points, grid);
            if let Some(found) = self.order_propagated(points, grid, &pairs) {
                return found;
            }
            if let Some(found) = self.order_from_nearest(points, grid, pairs) {
                return found;
            }
        }
        let start = self.centroid_shift(points);
        self.run_stages(start, &self.stages, points, grid.as_ref(), |_| true)
            .expect("every stage runs when the first matching goes on")
    }

    /// `stages` from the predictions `predicted`, then the fill; `go_on`
    /// sees the first stage's matches and stops the stages (`None`) when
    /// it says no.
    fn run_stages(
        &self,
        mut predicted: Vec<[f64; 2]>,
        stages: &[Stage],
        points: &[[f64; 2]],
        grid: Option<&Grid>,
        mut go_on: impl FnMut(&[Option<usize>]) -> bool,
    ) -> Option<(Tracked, Vec<Option<usize>>)> {
        let mut observed: Vec<Option<[f64; 2]>> = vec![None; self.reference.len()];
        let mut matches: Vec<Option<usize>> = vec![None; self.reference.len()];
        let mut by_x = None;
        for (s, stage) in stages.iter().enumerate() {
            let source = match grid.filter(|_| self.uses_grid(stage)) {
                Some(g) => Candidates::Grid(g),
                None => Candidates::ByX(by_x.get_or_insert_with(|| ByX::new(points))),
            };
            matches = self.match_points(&predicted, points, source, stage.gate);
            if s == 0 && !go_on(&matches) {
                return None;
            }
            observed = self.displacements(&matches, points);
            predicted = if s + 1 < stages.len() || !self.cuts {
                self.predict(&observed, &stage.kernel)
            } else {
                // The last field only fills the missing pins (`finish`).
                self.fill(&observed, &stage.kernel)
            };
        }
        let tracked = self.finish(&matches, &observed, &predicted, points.len());
        Some((tracked, matches))
    }

    /// Reference moved by the difference of the two point sets' centroids
    /// and, with the scaled start and as many points as pins, scaled about
    /// the points' centroid by the ratio of their spreads
    /// ([`PinTracker::with_scaled_start`]).
    fn centroid_shift(&self, points: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let (Some(a), Some(b)) = (centroid(points), centroid(&self.reference)) else {
            return self.reference.clone();
        };
        let spread = |set: &[[f64; 2]], c: [f64; 2]| {
            let n = set.len() as f64;
            (set.iter()
                .map(|p| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2))
                .sum::<f64>()
                / n)
                .sqrt()
        };
        let scale = if self.scaled && points.len() == self.reference.len() {
            Some(spread(points, a) / spread(&self.reference, b))
                .filter(|s| s.is_finite() && *s > 0.0)
        } else {
            None
        };
        match scale {
            Some(s) => self
                .reference
                .iter()
                .map(|r| [a[0] + s * (r[0] - b[0]), a[1] + s * (r[1] - b[1])])
                .collect(),
            None => {
                let shift = [a[0] - b[0], a[1] - b[1]];
                self.reference
                    .iter()
                    .map(|r| [r[0] + shift[0], r[1] + shift[1]])
                    .collect()
            }
        }
    }

    /// Optimal one-to-one matching of predicted pins to points, squared
    /// distance cost, pairs farther than `gate` not allowed: from the
    /// pins' windows where none is ambiguous (`tracker/window.rs`, the
    /// same matching), else in full. Candidates come
    /// from the x-window of each prediction (through the grid's cells or
    /// the x-sorted points: the same edges) and are listed by point index
    /// (as a scan over all points would list them), through a bit set.
    fn match_points(
        &self,
        predicted: &[[f64; 2]],
        points: &[[f64; 2]],
        source: Candidates,
        gate: f64,
    ) -> Vec<Option<usize>> {
        if let Candidates::Grid(grid) = source {
            if let Some(matches) = self.window_matches(predicted, points, grid, gate) {
                return matches;
            }
        }
        let gate2 = gate * gate;
        // The cost of leaving a pin unassigned (as `assign_rows` takes it).
        let unassigned = if gate2.is_finite() {
            gate2
        } else {
            f64::MAX / 4.0
        };
        // Room for the candidates within the gate (about 3.6 (gate /
        // spacing)^2 a pin on a hexagonal layout) and the "unassigned"
        // edge, so the widest stage does not grow the buffer.
        let per_pin = if self.cuts {
            16.max((4.0 * (gate / self.spacing).powi(2)) as usize + 8)
        } else {
            16
        };
        let mut rows = EdgeRows::with_capacity(predicted.len(), per_pin * predicted.len());
        let mut candidates = vec![0u64; points.len().div_ceil(64)];
        let mut costs = vec![0.0; points.len()];
        for p in predicted {
            let mut consider = |col: usize, x: f64, y: f64| {
                let dy2 = (p[1] - y).powi(2);
                if dy2 >= unassigned {
                    return; // the cost is at least dy2
                }
                let cost = (p[0] - x).powi(2) + dy2;
                if cost < unassigned {
                    candidates[col / 64] |= 1 << (col % 64);
                    costs[col] = cost;
                }
            };
            match source {
                Candidates::ByX(by_x) => {
                    let from = by_x.xs.partition_point(|&x| x < p[0] - gate);
                    let window = by_x.xs[from..].iter().zip(&by_x.ys[from..]);
                    for ((&x, &y), &col) in window.zip(&by_x.order[from..]) {
                        if x > p[0] + gate {
                            break;
                        }
                        consider(col, x, y);
                    }
                }
                Candidates::Grid(grid) => grid.around(p, gate, |col| {
                    let [x, y] = points[col];
                    // The x-window's own test, so the edges are the same.
                    if x >= p[0] - gate && x <= p[0] + gate {
                        consider(col, x, y);
                    }
                }),
            }
            for (w, word) in candidates.iter_mut().enumerate() {
                while *word != 0 {
                    let col = 64 * w + word.trailing_zeros() as usize;
                    *word &= *word - 1;
                    rows.edges.push(Edge {
                        col,
                        cost: costs[col],
                    });
                }
            }
            // The pin's own "unassigned" column.
            rows.edges.push(Edge {
                col: points.len() + rows.len(),
                cost: unassigned,
            });
            rows.end_row();
        }
        assign_usable(points.len(), &rows)
    }

    /// Per pin, its point minus its reference position, px.
    fn displacements(
        &self,
        matches: &[Option<usize>],
        points: &[[f64; 2]],
    ) -> Vec<Option<[f64; 2]>> {
        self.reference
            .iter()
            .zip(matches)
            .map(|(r, m)| m.map(|k| [points[k][0] - r[0], points[k][1] - r[1]]))
            .collect()
    }

    /// Every pin's position under the field fitted to `observed`.
    fn predict(&self, observed: &Observations, kernel: &Kernel) -> Vec<[f64; 2]> {
        smooth_field(&self.reference, observed, kernel, PRIOR_WEIGHT)
            .iter()
            .zip(&self.reference)
            .map(|(d, r)| [r[0] + d[0], r[1] + d[1]])
            .collect()
    }

    /// Missing pins where the field fitted to `observed` puts them, the
    /// others at their observation: [`PinTracker::predict`] where
    /// [`PinTracker::finish`] reads it (`field::fill_missing`).
    fn fill(&self, observed: &Observations, kernel: &Kernel) -> Vec<[f64; 2]> {
        fill_missing(&self.reference, observed, kernel, PRIOR_WEIGHT)
            .iter()
            .zip(&self.reference)
            .map(|(d, r)| [r[0] + d[0], r[1] + d[1]])
            .collect()
    }

    /// Matched pins at their points, the others at `predicted`.
    fn finish(
        &self,
        matches: &[Option<usize>],
        observed: &Observations,
        predicted: &[[f64; 2]],
        n_points: usize,
    ) -> Tracked {
        let pins: Vec<[f64; 2]> = self
            .reference
            .iter()
            .zip(observed)
            .zip(predicted)
            .map(|((r, o), p)| o.map_or(*p, |d| [r[0] + d[0], r[1] + d[1]]))
            .collect();
        let matched: Vec<bool> = matches.iter().map(Option::is_some).collect();
        let matched_count = matched.iter().filter(|&&m| m).count();
        Tracked {
            pins,
            matched,
            missing: self.reference.len() - matched_count,
            extra: n_points - matched_count,
        }
    }
}

/// Where a matching stage finds its candidate points.
#[derive(Clone, Copy)]
enum Candidates<'a> {
    ByX(&'a ByX),
    Grid(&'a Grid),
}

/// Point indices sorted by x, with their x and y values.
struct ByX {
    order: Vec<usize>,
    xs: Vec<f64>,
    ys: Vec<f64>,
}

impl ByX {
    fn new(points: &[[f64; 2]]) -> Self {
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_unstable_by(|&a, &b| points[a][0].total_cmp(&points[b][0]));
        let xs = order.iter().map(|&i| points[i][0]).collect();
        let ys = order.iter().map(|&i| points[i][1]).collect();
        Self { order, xs, ys }
    }
}

fn finite_centres(keypoints: &[KeyPoint]) -> Vec<[f64; 2]> {
    keypoints
        .iter()
        .filter(|k| k.x.is_finite() && k.y.is_finite())
        .map(|k| [k.x, k.y])
        .collect()
}

fn centroid(points: &[[f64; 2]]) -> Option<[f64; 2]> {
    if points.is_empty() {
        return None;
    }
    let n = points.len() as f64;
    let sx: f64 = points.iter().map(|p| p[0]).sum();
    let sy: f64 = points.iter().map(|p| p[1]).sum();
    Some([sx / n, sy / n])
}

/// Median over pins of the distance to the nearest other pin, px (1 for
/// fewer than two pins, so callers can scale tolerances by it safely).
pub fn median_spacing(points: &[[f64; 2]]) -> f64 {
    if points.len() < 2 {
        return 1.0;
    }
    let mut nearest: Vec<f64> = points
        .iter()
        .enumerate()
        .map(|(i, a)| {
            points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    nearest.sort_unstable_by(f64::total_cmp);
    nearest[nearest.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactrace_testdata::layouts::hex_lattice;

    /// The scaled start puts a layout spread by 4 % (a pressed dome) and
    /// moved exactly on its points, and on them in the same order; the
    /// start only moved is off by the spread, most at the rim; with a
    /// point short, the start is only moved.
    #[test]
    fn the_scaled_start_undoes_a_spread_and_a_move() {
        let reference = hex_lattice([128.0, 128.0], 18.0, 6);
        let points: Vec<[f64; 2]> = reference
            .iter()
            .map(|r| [121.5 + 1.04 * (r[0] - 128.0), 124.0 + 1.04 * (r[1] - 128.0)])
            .collect();
        let off = |start: &[[f64; 2]]| {
            start
                .iter()
                .zip(&points)
                .map(|(s, p)| (s[0] - p[0]).hypot(s[1] - p[1]))
                .fold(0.0, f64::max)
        };
        let tracker = PinTracker::new(reference.clone()).expect("tracker");
        assert!(off(&tracker.centroid_shift(&points)) < 1e-9);
        // One point short: only moved (the spreads would not compare).
        let short = tracker.centroid_shift(&points[1..]);
        let [a, b] = [&points[1..], &reference[..]].map(|set| centroid(set).expect("points"));
        assert!((short[5][0] - reference[5][0] - (a[0] - b[0])).abs() < 1e-9);
        let moved = tracker.with_scaled_start(false).centroid_shift(&points);
        let rim = 6.0 * 18.0 * 0.04;
        assert!(
            (off(&moved) - rim).abs() < 1e-6,
            "{} against {rim}",
            off(&moved)
        );
    }
}
