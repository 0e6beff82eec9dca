//! The blob detector's contours of a binary frame (report ch. 4.1) found
//! without the raster scan of border following. The white pixels are read
//! as horizontal runs (32 or 16 pixels a compare, `row_bits.rs`; the
//! binary frame written on the way) and joined into 8-connected components
//! by union-find. A component whose Euler number (its runs minus its pairs
//! of touching runs in adjacent rows) is 1 has no hole, so OpenCV's
//! `findContours` gives it exactly one contour, its outer border, started
//! at its first pixel in raster order. When the area filter surely rejects that border, known
//! from the runs alone (its area is at least the number of squares of four
//! white pixels and at most its box's: the rim's long arcs, the specks),
//! it is never walked; otherwise it is walked directly from there
//! (`ContourScanner::outer_border_at`, the tracer's own walk), or, for a
//! component of one run a row (nearly every pin), written from its runs
//! with the walk's points in the walk's order (`chain.rs`). A component
//! with holes is traced in a window of its own. Every contour is measured
//! by the same functions, so the blobs are the full-frame tracer's, bit
//! for bit (the tests here, in `binary.rs` and `tests/it/runs.rs`).

use crate::blob::{
    colour_passes, measure_shape, measure_shape_in, Contour, Known, Radius, Scratch,
};
use crate::chain::diagonal_steps;
use crate::contour::ContourScanner;
use crate::grouping::Centre;
use crate::params::BlobParams;
use crate::row_bits::row_mask;
use crate::shape::Octagon;

/// No run (a link to nothing).
const NONE: u32 = u32::MAX;

/// A horizontal run of white pixels `x0..=x1` in row `y`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Run {
    pub(crate) y: u32,
    pub(crate) x0: u32,
    pub(crate) x1: u32,
}

/// What [`RunDetector::join`] sums over a component's runs.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    /// Its runs.
    count: u32,
    /// Its pairs of touching runs (one row apart).
    touching: u32,
    /// The unit squares whose four corners are its pixels.
    blocks: u32,
    /// The extremes of x, y, x + y and x - y over its pixels (its box and
    /// its outer border's octagon).
    octagon: Octagon,
}

impl Sums {
    /// The sums of one run, pixels `x0..=x1` of row `y`.
    fn of_run(r: Run) -> Self {
        Self {
            count: 1,
            touching: 0,
            blocks: 0,
            octagon: Octagon::row(r.y as i32, r.x0 as i32, r.x1 as i32),
        }
    }

    /// Adds run `r`, which touches `touching` runs of the row above
    /// sharing `blocks` squares of four pixels with them.
    /// Runs come in raster order, so `r`'s row is the component's lowest.
    fn add_run(&mut self, r: Run, touching: u32, blocks: u32) {
        self.count += 1;
        self.touching += touching;
        self.blocks += blocks;
        let o = &mut self.octagon;
        let (y, x0, x1) = (i64::from(r.y), i64::from(r.x0), i64::from(r.x1));
        o.x = [o.x[0].min(x0), o.x[1].max(x1)];
        o.y[1] = y;
        o.sum = [o.sum[0].min(x0 + y), o.sum[1].max(x1 + y)];
        o.diff = [o.diff[0].min(x0 - y), o.diff[1].max(x1 - y)];
    }

    /// Adds another component's sums.
    fn merge(&mut self, other: &Self) {
        self.count += other.count;
        self.touching += other.touching;
        self.blocks += other.blocks;
        self.octagon.merge(&other.octagon);
    }
}

/// Reusable buffers of [`RunDetector::centres`].
#[derive(Default)]
pub(crate) struct RunDetector {
    runs: Vec<Run>,
    parent: Vec<u32>,
    /// Per root (a component's first run): the component's sums (stale
    /// at other runs).
    sums: Vec<Sums>,
    /// The runs that began a component, in raster order (after a merge,
    /// only the earlier of two is still a root).
    firsts: Vec<u32>,
    grouped: Vec<Run>,
    /// Per run, the last run of the next row found touching it (`NONE`
    /// if none): a component of one run a row is its first run and these
    /// links.
    below: Vec<u32>,
    found: Vec<(usize, Centre)>,
    /// The whole binary frame (its outer borders are walked on it).
    frame: ContourScanner,
    /// A component with holes, traced in a window of its own.
    scanner: Option<ContourScanner>,
    shape: Scratch,
}

impl RunDetector {
    /// The centres of the blobs of `pixels` (`width` x `height`, white
    /// above `level`, at least -1) that pass every filter of `p`, in
    /// OpenCV's contour order (the reverse of discovery in raster order):
    /// the same list as tracing the whole binarised frame. Hole-free
    /// blobs' radii as `radius` says (those with holes are measured).
    pub(crate) fn centres(
        &mut self,
        pixels: &[u8],
        [width, height]: [usize; 2],
        level: i16,
        p: &BlobParams,
        radius: Radius,
    ) -> Vec<Centre> {
        // The binary frame, for the border walks, is written row by row as
        // the runs are read (every label rewritten, walk marks included).
        if self.frame.size() != (width, height) {
            self.frame.clear(width, height);
        }
        white_runs(
            pixels,
            width,
            height,
            level,
            &mut self.runs,
            &mut self.frame,
        );
        self.join();
        self.found.clear();
        for f in 0..self.firsts.len() {
            let i = self.firsts[f] as usize;
            if self.parent[i] as usize != i {
                continue;
            }
            // Euler number (runs minus touching pairs, for 8-connected
            // white; the tests check it against the tracer's hole borders)
            // 1: no hole, so the outer border is the only contour.
            let sums = &self.sums[i];
            if sums.count == sums.touching + 1 {
                if self.area_rejects(i, p) {
                    continue;
                }
                let (x, y) = (self.runs[i].x0 as usize, self.runs[i].y as usize);
                let (contour, diagonal) = if self.gather_chain(i) {
                    let runs = &self.grouped[..];
                    (Contour::Chain(runs), diagonal_steps(runs))
                } else {
                    let (points, diagonal) = self.frame.outer_border_at(x, y);
                    (Contour::Points(points), diagonal)
                };
                let known = Known {
                    octagon: Some(&self.sums[i].octagon),
                    diagonal_steps: Some(diagonal),
                    radius,
                };
                if let Some(c) = measure_shape_in(contour, known, p, &mut self.shape) {
                    if colour_passes(&c, pixels, width, height, level, p) {
                        self.found.push((y * width + x, c));
                    }
                }
            } else {
                self.gather(i);
                self.trace_window(width, pixels, height, level, p);
            }
        }
        self.found
            .sort_unstable_by_key(|&(key, _)| std::cmp::Reverse(key));
        self.found.iter().map(|&(_, c)| c).collect()
    }

    /// Whether the area filter surely rejects the only contour of the
    /// hole-free component whose first run is `root`, known from its runs
    /// alone (after [`RunDetector::join`]): its outer border, a polygon
    /// through pixel centres, holds every unit square whose four corners
    /// are its pixels, so its area is at least their number, and lies in
    /// the box of its pixel centres, so its area is at most
    /// `(box width - 1) (box height - 1)`. The rim's long arcs and the
    /// specks are dropped here, before any border walk.
    fn area_rejects(&self, root: usize, p: &BlobParams) -> bool {
        if !p.filter_by_area {
            return false;
        }
        let Sums {
            blocks, octagon, ..
        } = self.sums[root];
        let Octagon { x, y, .. } = octagon;
        let most = (x[1] - x[0]) as f64 * (y[1] - y[0]) as f64;
        let least = f64::from(blocks);
        most < f64::from(p.min_area) || least >= f64::from(p.max_area)
    }

    /// Joins the runs into 8-connected components (union-find over runs
    /// of adjacent rows, in one pass): afterwards a component's first run
    /// (its root) is the only run that is its own `parent`, and the root's
    /// `sums` are the component's. Each run is added to its root's sums as
    /// it is joined, and when two components meet the later root's sums
    /// are added to the earlier one's; `firsts` lists the runs that began
    /// a component (the roots among them are the components').
    fn join(&mut self) {
        let Self {
            runs,
            parent,
            sums,
            firsts,
            below,
            ..
        } = self;
        firsts.clear();
        // Each run's parent, link below and root's sums are written before
        // being read (a run's link when the next row is joined).
        let n = runs.len();
        if parent.len() < n {
            parent.resize(n, 0);
            sums.resize(n, Sums::default());
        }
        if below.len() < n {
            below.resize(n, NONE);
        }
        let (mut above, mut row_start, mut row_y) = (0, 0, u32::MAX);
        for (i, &r) in runs.iter().enumerate() {
            if r.y != row_y {
                above = if r.y == row_y.wrapping_add(1) {
                    row_start
                } else {
                    i
                };
                (row_start, row_y) = (i, r.y);
            }
            // Runs of the row above, in x order: skip those ending left of
            // this one's reach; those after, up to the first starting right
            // of it, touch it.
            while above < row_start && runs[above].x1 + 1 < r.x0 {
                above += 1;
            }
            let (mut root, mut touching, mut blocks) = (i, 0, 0);
            for (j, q) in runs[above..row_start].iter().enumerate() {
                if q.x0 > r.x1 + 1 {
                    break;
                }
                let top = find(parent, above + j);
                root = if touching == 0 {
                    top
                } else {
                    merge(parent, sums, root, top)
                };
                touching += 1;
                below[above + j] = i as u32;
                // x and x + 1 in both runs: a square of four white pixels.
                blocks += q.x1.min(r.x1).saturating_sub(q.x0.max(r.x0));
            }
            parent[i] = root as u32;
            below[i] = NONE;
            if root == i {
                sums[i] = Sums::of_run(r);
                firsts.push(i as u32);
            } else {
                sums[root].add_run(r, touching, blocks);
            }
        }
    }

    /// Whether the component whose first run is `root` has one run a row
    /// (after [`RunDetector::join`]); if so, its runs from the top into
    /// `grouped`, by the links to the run below (with one run a row, the
    /// only run touching a run from below).
    fn gather_chain(&mut self, root: usize) -> bool {
        let Octagon { y, .. } = self.sums[root].octagon;
        if i64::from(self.sums[root].count) != y[1] - y[0] + 1 {
            return false;
        }
        self.grouped.clear();
        let mut at = root as u32;
        while at != NONE {
            self.grouped.push(self.runs[at as usize]);
            at = self.below[at as usize];
        }
        true
    }

    /// The runs of the component whose first run is `root`, in raster
    /// order, into `grouped` (after [`RunDetector::join`]).
    fn gather(&mut self, root: usize) {
        self.grouped.clear();
        for i in root..self.runs.len() {
            if self.parent[i] as usize == root || find(&mut self.parent, i) == root {
                self.grouped.push(self.runs[i]);
            }
        }
    }

    /// Traces one component (its runs in `grouped`) in a window of
    /// its own, as `components.rs` does: its bounding box plus the column
    /// to its right where the frame has one (a hole border may start
    /// there); the same contours and starting pixels as in the full frame.
    fn trace_window(
        &mut self,
        width: usize,
        pixels: &[u8],
        height: usize,
        level: i16,
        p: &BlobParams,
    ) {
        let runs = &self.grouped;
        let (y0, y1) = (runs[0].y, runs[runs.len() - 1].y);
        let x0 = runs.iter().map(|r| r.x0).min().unwrap_or(0);
        let x1 = runs.iter().map(|r| r.x1).max().unwrap_or(0);
        let w = (x1 as usize + 2).min(width) - x0 as usize;
        let scanner = self
            .scanner
            .get_or_insert_with(|| ContourScanner::new(0, 0));
        scanner.reset_window(w, (y1 - y0 + 1) as usize, [x0 as i32, y0 as i32]);
        for r in runs {
            scanner.set_labels(
                (r.y - y0) as usize,
                (r.x0 - x0) as usize,
                (r.x1 - x0) as usize,
                1,
            );
        }
        scanner.trace_all();
        for (trigger, contour) in scanner.contours_with_trigger() {
            if let Some(c) = measure_shape(contour, p, &mut self.shape) {
                if colour_passes(&c, pixels, width, height, level, p) {
                    let key = trigger[1] as usize * width + trigger[0] as usize;
                    self.found.push((key, c));
                }
            }
        }
    }
}

/// The runs of pixels above `level` (at least -1), row by row, and the
/// binary image into `frame` (`width` x `height`; 1 white, 0 background,
/// every label rewritten): each row is read into bit masks and its labels
/// ([`row_mask`]), and the runs start and end where a bit differs from the
/// one before it ([`row_runs`]).
fn white_runs(
    pixels: &[u8],
    width: usize,
    height: usize,
    level: i16,
    runs: &mut Vec<Run>,
    frame: &mut ContourScanner,
) {
    runs.clear();
    if width == 0 {
        return;
    }
    let mut masks = vec![0u64; width.div_ceil(64)];
    for (y, row) in pixels.chunks_exact(width).take(height).enumerate() {
        let labels = frame.row_mut(y);
        if level >= 255 {
            labels.fill(0);
            continue;
        }
        if level < 0 {
            // Every pixel is above.
            labels.fill(1);
            masks.fill(u64::MAX);
            if !width.is_multiple_of(64) {
                masks[width / 64] = u64::MAX >> (64 - width % 64);
            }
        } else {
            row_mask(row, level as u8, labels, &mut masks);
        }
        row_runs(&masks, y as u32, width as u32, runs);
    }
}

/// The runs of row `y` (`width` pixels, bit `x % 64` of `masks[x / 64]`
/// set where pixel x is white, no bit set past the row) appended to `runs`:
/// a run starts or ends at every bit that differs from the bit before it
/// (the one before the row counts as clear).
pub(crate) fn row_runs(masks: &[u64], y: u32, width: u32, runs: &mut Vec<Run>) {
    let mut open: Option<u32> = None;
    let mut carry = 0;
    for (c, &mask) in masks.iter().enumerate() {
        let mut steps = mask ^ ((mask << 1) | carry);
        carry = mask >> 63;
        while steps != 0 {
            let x = 64 * c as u32 + steps.trailing_zeros();
            steps &= steps - 1;
            match open.take() {
                None => open = Some(x),
                Some(x0) => runs.push(Run { y, x0, x1: x - 1 }),
            }
        }
    }
    if let Some(x0) = open {
        runs.push(Run {
            y,
            x0,
            x1: width - 1,
        });
    }
}

/// Joins the components of roots `a` and `b`: the earlier root stays
/// (roots are first runs) and takes the other's sums; returns it.
fn merge(parent: &mut [u32], sums: &mut [Sums], a: usize, b: usize) -> usize {
    if a == b {
        return a;
    }
    let (keep, gone) = (a.min(b), a.max(b));
    parent[gone] = keep as u32;
    let other = sums[gone];
    sums[keep].merge(&other);
    keep
}

/// The root of run `i`'s component, halving the path on the way.
pub(crate) fn find(parent: &mut [u32], mut i: usize) -> usize {
    while parent[i] as usize != i {
        parent[i] = parent[parent[i] as usize];
        i = parent[i] as usize;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chain::{chain_border, chain_moments};
    use crate::shape::Moments;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Every contour of `pixels` traced over the whole frame, with its
    /// starting pixel: the reference.
    fn traced(pixels: &[u8], width: usize, height: usize) -> Vec<([i32; 2], Vec<[i32; 2]>)> {
        let mut full = ContourScanner::new(width, height);
        full.binarise_above(pixels, 127);
        full.trace_all();
        full.contours_with_trigger()
            .map(|(t, c)| (t, c.to_vec()))
            .collect()
    }

    /// A random binary frame of small blobs: discs, bars one pixel thick,
    /// diagonal strokes, rings and noise (touching ones merge).
    fn random_frame(rng: &mut ChaCha8Rng, width: usize, height: usize) -> Vec<u8> {
        let mut px = vec![0u8; width * height];
        for _ in 0..rng.random_range(0..20) {
            let (cx, cy) = (
                rng.random_range(-2.0..width as f64 + 2.0),
                rng.random_range(-2.0..height as f64 + 2.0),
            );
            let (r, hole): (f64, f64) = (rng.random_range(0.3..5.0), rng.random_range(-1.0..3.0));
            let (sx, sy) = (rng.random_range(0.3..1.7), rng.random_range(0.3..1.7));
            for y in 0..height {
                for x in 0..width {
                    let d = ((x as f64 - cx) * sx).hypot((y as f64 - cy) * sy);
                    if d <= r && d > hole.min(r - 1.0) {
                        px[y * width + x] = 255;
                    }
                }
            }
        }
        for _ in 0..rng.random_range(0..30) {
            let i = rng.random_range(0..px.len());
            px[i] ^= 255;
        }
        px
    }

    /// The outer border walked from a component's first pixel, without
    /// the raster scan, is exactly the tracer's (same points, same order)
    /// for every component, so is the border written from the runs of a
    /// component of one run a row, and the Euler number of the runs counts the
    /// hole borders: the tracer's contours are one a component plus one a
    /// hole.
    #[test]
    fn run_walk_equals_the_traced_border() {
        let mut rng = ChaCha8Rng::seed_from_u64(2105);
        let (mut walked, mut with_holes, mut chains) = (0, 0, 0);
        for case in 0..400 {
            let (w, h) = (rng.random_range(1..48), rng.random_range(1..48));
            let px = random_frame(&mut rng, w, h);
            let reference = traced(&px, w, h);
            let mut d = RunDetector::default();
            d.frame.clear(w, h);
            white_runs(&px, w, h, 127, &mut d.runs, &mut d.frame);
            d.join();
            let mut contours = 0;
            for i in 0..d.runs.len() {
                if d.parent[i] as usize != i {
                    continue;
                }
                let first = d.runs[i];
                let start = [first.x0 as i32, first.y as i32];
                let want = reference
                    .iter()
                    .find(|(t, _)| *t == start)
                    .expect("a contour starts at the component's first pixel");
                let (got, diagonal) = d.frame.outer_border_at(first.x0 as usize, first.y as usize);
                let got = got.to_vec();
                assert_eq!(got, want.1, "case {case} component at {start:?}");
                let next = got.iter().cycle().skip(1);
                let diagonals = got
                    .iter()
                    .zip(next)
                    .filter(|(a, b)| a[0] != b[0] && a[1] != b[1]);
                assert_eq!(diagonal, diagonals.count(), "case {case}: diagonal steps");
                // Holes: as many as the Euler number says.
                let holes = (d.sums[i].touching + 1 - d.sums[i].count) as usize;
                if holes == 0 {
                    check_area_bounds(&d, i, &got);
                    if d.gather_chain(i) {
                        let mut written = Vec::new();
                        let steps = chain_border(&d.grouped, &mut written);
                        assert_eq!(written, got, "case {case}: chain at {start:?}");
                        assert_eq!(steps, diagonal, "case {case}: chain's diagonal steps");
                        assert_eq!(diagonal_steps(&d.grouped), diagonal, "case {case}");
                        let bits = |m: Moments| {
                            [m.m00, m.m10, m.m01, m.mu20, m.mu11, m.mu02].map(f64::to_bits)
                        };
                        let moments = chain_moments(&d.grouped).expect("small enough");
                        assert_eq!(
                            bits(moments),
                            bits(Moments::of_polygon(&got)),
                            "case {case}"
                        );
                        chains += 1;
                    }
                    // The octagon of the runs is the border's.
                    let mut octagon = Octagon::row(got[0][1], got[0][0], got[0][0]);
                    got.iter().for_each(|&[x, y]| octagon.add_row(y, x, x));
                    assert_eq!(d.sums[i].octagon, octagon, "case {case} at {start:?}");
                }
                contours += 1 + holes;
                walked += 1;
                with_holes += usize::from(holes > 0);
            }
            assert_eq!(
                contours,
                reference.len(),
                "case {case}: one border a component and hole"
            );
        }
        assert!(
            walked > 2000 && with_holes > 100 && chains > 1000,
            "{walked} components walked, {with_holes} with holes, {chains} chains"
        );
    }

    /// The area bounds of [`RunDetector::area_rejects`] hold for the
    /// polygon of the hole-free component whose first run is `root`: the
    /// squares of four white pixels <= its area <= the box's; the area
    /// filter set to either bound's far side rejects it, set just inside
    /// both it does not.
    fn check_area_bounds(d: &RunDetector, root: usize, border: &[[i32; 2]]) {
        let area = Moments::of_polygon(border).m00;
        let Octagon { x, y, .. } = d.sums[root].octagon;
        let most = (x[1] - x[0]) as f64 * (y[1] - y[0]) as f64;
        let least = f64::from(d.sums[root].blocks);
        assert!(least <= area && area <= most, "{least} <= {area} <= {most}");
        let filter = |min_area: f64, max_area: f64| BlobParams {
            min_area: min_area as f32,
            max_area: max_area as f32,
            ..BlobParams::default()
        };
        assert!(d.area_rejects(root, &filter(most + 0.5, most + 1.0)));
        if least > 0.0 {
            assert!(d.area_rejects(root, &filter(0.0, least)));
        }
        assert!(!d.area_rejects(root, &filter(area, area + 0.5)));
    }

    /// Runs at every level, including -1 (all white) and rows of any
    /// width, are the pixels above the level.
    #[test]
    fn runs_cover_exactly_the_pixels_above_the_level() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut runs = Vec::new();
        let mut frame = ContourScanner::new(0, 0);
        for _ in 0..200 {
            let (w, h) = (rng.random_range(1..70), rng.random_range(1..6));
            let px: Vec<u8> = (0..w * h)
                .map(|_| {
                    if rng.random_bool(0.6) {
                        0
                    } else {
                        rng.random()
                    }
                })
                .collect();
            let level: i16 = rng.random_range(-1..256);
            if frame.size() != (w, h) {
                frame.clear(w, h);
            }
            white_runs(&px, w, h, level, &mut runs, &mut frame);
            let mut mask = vec![false; w * h];
            for r in &runs {
                for x in r.x0..=r.x1 {
                    mask[r.y as usize * w + x as usize] = true;
                }
            }
            let want: Vec<bool> = px.iter().map(|&v| i16::from(v) > level).collect();
            assert_eq!(mask, want);
            let labelled: Vec<bool> = (0..w * h).map(|i| frame.is_white(i % w, i / w)).collect();
            assert_eq!(labelled, want, "the frame's labels");
        }
    }
}
