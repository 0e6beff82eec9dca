//! The blob detector's contours of a binary frame (report ch. 4.1) found
//! without the raster scan of border following. The white pixels are read
//! as horizontal runs (16 pixels a compare) and joined into 8-connected
//! components by union-find. A component whose Euler number (its runs
//! minus its pairs of touching runs in adjacent rows) is 1 has no hole, so
//! OpenCV's `findContours` gives it exactly one contour, its outer border,
//! started at its first pixel in raster order: that border is walked
//! directly from there (`ContourScanner::outer_border_at`, the tracer's own
//! walk). A component with holes (the rim, specks) is traced in a window
//! of its own as before. Every contour is measured by the same functions,
//! so the blobs are the full-frame tracer's, bit for bit (the tests here,
//! in `binary.rs` and `tests/runs.rs`).

use crate::blob::{colour_passes, measure_shape, Scratch};
use crate::contour::ContourScanner;
use crate::grouping::Centre;
use crate::params::BlobParams;

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
        // The binary frame, for the border walks: blank it (only the last
        // frame's runs were written, walks mark white pixels only), then
        // write this frame's runs.
        if self.frame.size() == (width, height) {
            for r in &self.runs {
                self.frame
                    .set_labels(r.y as usize, r.x0 as usize, r.x1 as usize, 0);
            }
        } else {
            self.frame.clear(width, height);
        }
        white_runs(pixels, width, height, level, &mut self.runs);
        self.join();
        for r in &self.runs {
            self.frame
                .set_labels(r.y as usize, r.x0 as usize, r.x1 as usize, 1);
        }
        self.found.clear();
        for i in 0..self.runs.len() {
            if self.parent[i] as usize != i {
                continue;
            }
            // Euler number (runs minus touching pairs, for 8-connected
            // white; the tests check it against the tracer's hole borders)
            // 1: no hole, so the outer border is the only contour.
            if self.count[i] == self.touching[i] + 1 {
                let (x, y) = (self.runs[i].x0 as usize, self.runs[i].y as usize);
                let points = self.frame.outer_border_at(x, y);
                if let Some(c) = measure_shape(points, p, &mut self.shape) {
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

    /// Joins the runs into 8-connected components (union-find over runs
    /// of adjacent rows): afterwards a component's first run (its root) is
    /// the only run that is its own `parent`, and the root's `count` and
    /// `touching` are the component's.
    fn join(&mut self) {
        let runs = &self.runs;
        self.parent.clear();
        self.parent.extend(0..runs.len() as u32);
        self.touching.clear();
        self.touching.resize(runs.len(), 0);
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
            }
        }
        // Roots are first runs; count each root's runs and touching pairs.
        self.count.clear();
        self.count.resize(runs.len(), 0);
        for i in 0..runs.len() {
            let root = find(&mut self.parent, i);
            self.count[root] += 1;
            if root != i {
                self.touching[root] += self.touching[i];
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

/// The runs of pixels above `level` (at least -1), row by row: each row is
/// read 64 pixels at a time into a bit mask ([`above_mask`]), whose runs
/// of ones are found by bit counting.
fn white_runs(pixels: &[u8], width: usize, height: usize, level: i16, runs: &mut Vec<Run>) {
    runs.clear();
    if width == 0 || level >= 255 {
        return;
    }
    // v > level for u8 v: all when level < 0.
    let (lvl, all) = (level.max(0) as u8, level < 0);
    for (y, row) in pixels.chunks_exact(width).take(height).enumerate() {
        let mut open: Option<usize> = None;
        for (c, block) in row.chunks(64).enumerate() {
            let mask = if all {
                u64::MAX >> (64 - block.len())
            } else {
                above_mask(block, lvl)
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

/// Bit `i` set where `block[i] > lvl` (`block` at most 64 pixels): 16
/// pixels a vector compare on x86_64 (SSE2, part of its baseline), one at
/// a time elsewhere and for the tail.
fn above_mask(block: &[u8], lvl: u8) -> u64 {
    let mut mask = 0u64;
    #[cfg(target_arch = "x86_64")]
    let done = {
        use std::arch::x86_64::{
            _mm_cmpeq_epi8, _mm_loadu_si128, _mm_max_epu8, _mm_movemask_epi8, _mm_set1_epi8,
        };
        for (c, chunk) in block.chunks_exact(16).enumerate() {
            // SAFETY: SSE2 is in the x86_64 baseline, so these intrinsics
            // exist on every x86_64 CPU; `chunk` holds the 16 bytes loaded
            // (no alignment needed). v > lvl <=> max(v, lvl + 1) == v
            // (lvl < 255: checked by the caller).
            let hits = unsafe {
                let v = _mm_loadu_si128(chunk.as_ptr().cast());
                let bound = _mm_set1_epi8((lvl + 1) as i8);
                _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_max_epu8(v, bound), v))
            };
            mask |= u64::from(hits as u16) << (16 * c);
        }
        block.len() / 16 * 16
    };
    #[cfg(not(target_arch = "x86_64"))]
    let done = 0;
    for (i, &v) in block.iter().enumerate().skip(done) {
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
            white_runs(&px, w, h, 127, &mut d.runs);
            d.join();
            d.frame.clear(w, h);
            for r in &d.runs {
                d.frame
                    .set_labels(r.y as usize, r.x0 as usize, r.x1 as usize, 1);
            }
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
                let got = d.frame.outer_border_at(first.x0 as usize, first.y as usize);
                assert_eq!(got, &want.1[..], "case {case} component at {start:?}");
                // Holes: as many as the Euler number says.
                let holes = (d.touching[i] + 1 - d.count[i]) as usize;
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

    /// Runs at every level, including -1 (all white) and rows of any
    /// width, are the pixels above the level.
    #[test]
    fn issue21_runs_cover_exactly_the_pixels_above_the_level() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut runs = Vec::new();
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
            white_runs(&px, w, h, level, &mut runs);
            let mut mask = vec![false; w * h];
            for r in &runs {
                for x in r.x0..=r.x1 {
                    mask[r.y as usize * w + x as usize] = true;
                }
            }
            let want: Vec<bool> = px.iter().map(|&v| i16::from(v) > level).collect();
            assert_eq!(mask, want);
        }
    }
}
