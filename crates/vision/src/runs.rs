//! The blob detector's contours of a binary frame (report ch. 4.1) found
//! without the raster scan of border following. The white pixels are read
//! as horizontal runs (16 pixels a compare, the binary frame written on the
//! way) and joined into 8-connected components by union-find. A component
//! whose Euler number (its runs minus its pairs of touching runs in
//! adjacent rows) is 1 has no hole, so OpenCV's `findContours` gives it
//! exactly one contour, its outer border, started at its first pixel in
//! raster order. When the area filter surely rejects that border, known
//! from the runs alone (its area is at least the number of squares of four
//! white pixels and at most its box's: the rim's long arcs, the specks),
//! it is never walked; otherwise it is walked directly from there
//! (`ContourScanner::outer_border_at`, the tracer's own walk). A component
//! with holes is traced in a window of its own. Every contour is measured
//! by the same functions, so the blobs are the full-frame tracer's, bit
//! for bit (the tests here, in `binary.rs` and `tests/runs.rs`).

use crate::blob::{colour_passes, measure_shape, measure_shape_in, Scratch};
use crate::contour::ContourScanner;
use crate::grouping::Centre;
use crate::params::BlobParams;
use crate::shape::Octagon;

/// A horizontal run of white pixels `x0..=x1` in row `y`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Run {
    y: u32,
    x0: u32,
    x1: u32,
}

/// Reusable buffers of [`RunDetector::centres`].
pub(crate) struct RunDetector {
    runs: Vec<Run>,
    parent: Vec<u32>,
    /// Per root (a component's first run): its number of runs.
    count: Vec<u32>,
    /// Per run, then summed into each root: pairs of touching runs (one
    /// row apart) whose lower run it is.
    touching: Vec<u32>,
    /// Per run, then summed into each root: the unit squares between it
    /// and the runs above whose four corners are white pixels.
    blocks: Vec<u32>,
    /// Per root: the extremes of x, y, x + y and x - y over the
    /// component's pixels (its box and its outer border's octagon).
    octagons: Vec<Octagon>,
    grouped: Vec<Run>,
    found: Vec<(usize, Centre)>,
    /// The whole binary frame (its outer borders are walked on it).
    frame: ContourScanner,
    /// A component with holes, traced in a window of its own.
    scanner: Option<ContourScanner>,
    shape: Scratch,
}

impl Default for RunDetector {
    fn default() -> Self {
        Self {
            runs: Vec::new(),
            parent: Vec::new(),
            count: Vec::new(),
            touching: Vec::new(),
            blocks: Vec::new(),
            octagons: Vec::new(),
            grouped: Vec::new(),
            found: Vec::new(),
            frame: ContourScanner::new(0, 0),
            scanner: None,
            shape: Scratch::default(),
        }
    }
}

impl RunDetector {
    /// The centres of the blobs of `pixels` (`width` x `height`, white
    /// above `level`, at least -1) that pass every filter of `p`, in
    /// OpenCV's contour order (the reverse of discovery in raster order):
    /// the same list as tracing the whole binarised frame.
    pub(crate) fn centres(
        &mut self,
        pixels: &[u8],
        width: usize,
        height: usize,
        level: i16,
        p: &BlobParams,
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
        for i in 0..self.runs.len() {
            if self.parent[i] as usize != i {
                continue;
            }
            // Euler number (runs minus touching pairs, for 8-connected
            // white; the tests check it against the tracer's hole borders)
            // 1: no hole, so the outer border is the only contour.
            if self.count[i] == self.touching[i] + 1 {
                if self.area_rejects(i, p) {
                    continue;
                }
                let (x, y) = (self.runs[i].x0 as usize, self.runs[i].y as usize);
                let points = self.frame.outer_border_at(x, y);
                let octagon = Some(&self.octagons[i]);
                if let Some(c) = measure_shape_in(points, octagon, p, &mut self.shape) {
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
        let Octagon { x, y, .. } = self.octagons[root];
        let most = (x[1] - x[0]) as f64 * (y[1] - y[0]) as f64;
        let least = f64::from(self.blocks[root]);
        most < f64::from(p.min_area) || least >= f64::from(p.max_area)
    }

    /// Joins the runs into 8-connected components (union-find over runs
    /// of adjacent rows): afterwards a component's first run (its root) is
    /// the only run that is its own `parent`, and the root's `count`,
    /// `touching`, `blocks` and `octagons` are the component's.
    fn join(&mut self) {
        let runs = &self.runs;
        self.parent.clear();
        self.parent.extend(0..runs.len() as u32);
        self.touching.clear();
        self.touching.resize(runs.len(), 0);
        self.blocks.clear();
        self.blocks.resize(runs.len(), 0);
        let (mut above, mut row_start) = (0, 0);
        for i in 0..runs.len() {
            if i > 0 && runs[i].y != runs[i - 1].y {
                above = if runs[i].y == runs[i - 1].y + 1 {
                    row_start
                } else {
                    i
                };
                row_start = i;
            }
            let r = runs[i];
            // Runs of the row above, in x order: skip those ending left of
            // this one's reach, stop at the first starting right of it.
            let mut j = above;
            while j < row_start {
                let q = runs[j];
                j += 1;
                if q.x1 + 1 < r.x0 {
                    above = j;
                    continue;
                }
                if q.x0 > r.x1 + 1 {
                    break;
                }
                union(&mut self.parent, i, j - 1);
                self.touching[i] += 1;
                // x and x + 1 in both runs: a square of four white pixels.
                self.blocks[i] += q.x1.min(r.x1).saturating_sub(q.x0.max(r.x0));
            }
        }
        // Roots are first runs; count each root's runs, touching pairs
        // and squares, and its octagon.
        self.count.clear();
        self.count.resize(runs.len(), 0);
        self.octagons.resize(runs.len(), Octagon::default());
        for (i, r) in runs.iter().enumerate() {
            // Parents have smaller indices and are done: one step to the root.
            let root = self.parent[self.parent[i] as usize] as usize;
            self.parent[i] = root as u32;
            self.count[root] += 1;
            let (y, x0, x1) = (r.y as i32, r.x0 as i32, r.x1 as i32);
            if root == i {
                self.octagons[i] = Octagon::row(y, x0, x1);
            } else {
                self.touching[root] += self.touching[i];
                self.blocks[root] += self.blocks[i];
                self.octagons[root].add_row(y, x0, x1);
            }
        }
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
/// every label rewritten): each row is read 64 pixels at a time into a bit
/// mask and its labels ([`above_mask`]), and the mask's runs of ones are
/// found by bit counting.
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
    // v > level for u8 v: all when level < 0, none from 255.
    let (lvl, all) = (level.clamp(0, 254) as u8, level < 0);
    for (y, row) in pixels.chunks_exact(width).take(height).enumerate() {
        let labels = frame.row_mut(y);
        if level >= 255 {
            labels.fill(0);
            continue;
        }
        let mut open: Option<usize> = None;
        for (c, block) in row.chunks(64).enumerate() {
            let out = &mut labels[c * 64..c * 64 + block.len()];
            let mask = if all {
                out.fill(1);
                u64::MAX >> (64 - block.len())
            } else {
                above_mask(block, lvl, out)
            };
            let base = c * 64;
            let mut at = 0;
            // Alternate: skip zeros, then ones, closing and opening runs.
            while at < block.len() {
                let rest = mask >> at;
                if open.is_none() {
                    if rest == 0 {
                        break;
                    }
                    at += rest.trailing_zeros() as usize;
                    open = Some(base + at);
                } else {
                    let ones = (!rest).trailing_zeros() as usize;
                    if at + ones >= block.len() {
                        break;
                    }
                    at += ones;
                    push_run(runs, y, open.take(), base + at);
                }
            }
        }
        push_run(runs, y, open, width);
    }
}

/// Bit `i` set, and `out[i]` 1 (else 0), where `block[i] > lvl` (`block`
/// and `out` of the same length, at most 64 pixels): 16 pixels a vector
/// compare on x86_64 (SSE2, part of its baseline), one at a time elsewhere
/// and for the tail.
fn above_mask(block: &[u8], lvl: u8, out: &mut [i8]) -> u64 {
    let mut mask = 0u64;
    #[cfg(target_arch = "x86_64")]
    let done = {
        use std::arch::x86_64::{
            _mm_and_si128, _mm_cmpeq_epi8, _mm_loadu_si128, _mm_max_epu8, _mm_movemask_epi8,
            _mm_set1_epi8, _mm_storeu_si128,
        };
        for (c, (chunk, dst)) in block
            .chunks_exact(16)
            .zip(out.chunks_exact_mut(16))
            .enumerate()
        {
            // SAFETY: SSE2 is in the x86_64 baseline, so these intrinsics
            // exist on every x86_64 CPU; `chunk` holds the 16 bytes loaded
            // and `dst` the 16 stored (no alignment needed). v > lvl <=>
            // max(v, lvl + 1) == v (lvl < 255: checked by the caller).
            let hits = unsafe {
                let v = _mm_loadu_si128(chunk.as_ptr().cast());
                let bound = _mm_set1_epi8((lvl + 1) as i8);
                let hit = _mm_cmpeq_epi8(_mm_max_epu8(v, bound), v);
                _mm_storeu_si128(
                    dst.as_mut_ptr().cast(),
                    _mm_and_si128(hit, _mm_set1_epi8(1)),
                );
                _mm_movemask_epi8(hit)
            };
            mask |= u64::from(hits as u16) << (16 * c);
        }
        block.len() / 16 * 16
    };
    #[cfg(not(target_arch = "x86_64"))]
    let done = 0;
    for (i, (&v, d)) in block.iter().zip(out.iter_mut()).enumerate().skip(done) {
        *d = i8::from(v > lvl);
        mask |= u64::from(v > lvl) << i;
    }
    mask
}

/// Adds the run `x0..end` of row `y` when one is open.
fn push_run(runs: &mut Vec<Run>, y: usize, x0: Option<usize>, end: usize) {
    if let Some(x0) = x0 {
        runs.push(Run {
            y: y as u32,
            x0: x0 as u32,
            x1: (end - 1) as u32,
        });
    }
}

fn find(parent: &mut [u32], mut i: usize) -> usize {
    while parent[i] as usize != i {
        parent[i] = parent[parent[i] as usize];
        i = parent[i] as usize;
    }
    i
}

fn union(parent: &mut [u32], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    // The smaller index stays root, so roots are first runs.
    if ra < rb {
        parent[rb] = ra as u32;
    } else {
        parent[ra] = rb as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
    /// for every component, and the Euler number of the runs counts the
    /// hole borders: the tracer's contours are one a component plus one a
    /// hole.
    #[test]
    fn issue21_run_walk_equals_the_traced_border() {
        let mut rng = ChaCha8Rng::seed_from_u64(2105);
        let (mut walked, mut with_holes) = (0, 0);
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
                let got = d
                    .frame
                    .outer_border_at(first.x0 as usize, first.y as usize)
                    .to_vec();
                assert_eq!(got, want.1, "case {case} component at {start:?}");
                // Holes: as many as the Euler number says.
                let holes = (d.touching[i] + 1 - d.count[i]) as usize;
                if holes == 0 {
                    check_area_bounds(&d, i, &got);
                    // The octagon of the runs is the border's.
                    let mut octagon = Octagon::row(got[0][1], got[0][0], got[0][0]);
                    got.iter().for_each(|&[x, y]| octagon.add_row(y, x, x));
                    assert_eq!(d.octagons[i], octagon, "case {case} at {start:?}");
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
            walked > 2000 && with_holes > 100,
            "{walked} components walked, {with_holes} with holes"
        );
    }

    /// The area bounds of [`RunDetector::area_rejects`] hold for the
    /// polygon of the hole-free component whose first run is `root`: the
    /// squares of four white pixels <= its area <= the box's; the area
    /// filter set to either bound's far side rejects it, set just inside
    /// both it does not.
    fn check_area_bounds(d: &RunDetector, root: usize, border: &[[i32; 2]]) {
        let area = Moments::of_polygon(border).m00;
        let Octagon { x, y, .. } = d.octagons[root];
        let most = (x[1] - x[0]) as f64 * (y[1] - y[0]) as f64;
        let least = f64::from(d.blocks[root]);
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
    fn issue21_runs_cover_exactly_the_pixels_above_the_level() {
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
