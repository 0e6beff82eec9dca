//! The white 8-connected components of a frame at the lowest detection
//! threshold (report ch. 4.1: pins are white blobs found over a range of
//! thresholds). Every component at a higher threshold lies inside one of
//! these, and border following never looks past a component's own pixels
//! and their background neighbours, so each threshold can be traced one
//! component at a time in a small window instead of over the whole frame,
//! and a component whose pixels all lie on the same side of two thresholds
//! need not be traced again.

use crate::contour::ContourScanner;

/// One component of the lowest-threshold binary image, with the window
/// that holds it (its buffers live in [`Components`]).
#[derive(Clone, Debug)]
struct Window {
    /// Full-image pixel (x, y) of the window's first pixel.
    origin: [i32; 2],
    width: usize,
    height: usize,
    /// Range of its grey levels in `Components::values` (row-major; -1
    /// outside the component).
    values: std::ops::Range<usize>,
    /// Range of its pixels' grey levels, ascending, in `Components::sorted`.
    sorted: std::ops::Range<usize>,
}

/// The components of one frame at one level, in raster order of their
/// first pixel.
pub struct Components {
    windows: Vec<Window>,
    values: Vec<i16>,
    sorted: Vec<u8>,
}

/// A horizontal run of white pixels `x0..=x1` in row `y`.
#[derive(Clone, Copy)]
struct Run {
    y: usize,
    x0: usize,
    x1: usize,
}

impl Components {
    /// Number of components.
    pub fn len(&self) -> usize {
        self.windows.len()
    }

    /// Number of pixels of component `k` whose grey level exceeds `level`.
    pub fn count_above(&self, k: usize, level: i16) -> usize {
        let sorted = &self.sorted[self.windows[k].sorted.clone()];
        sorted.len() - sorted.partition_point(|&v| i16::from(v) <= level)
    }

    /// Traces component `k` binarised at `level` (white above it) into
    /// `scanner`, points in full-image coordinates.
    pub fn trace(&self, k: usize, scanner: &mut ContourScanner, level: i16) {
        let w = &self.windows[k];
        scanner.reset_window(w.width, w.height, w.origin);
        scanner.binarise_levels(&self.values[w.values.clone()], level);
        scanner.trace_all();
    }
}

/// The 8-connected components of pixels above `level` (at least -1), found
/// from horizontal runs joined by union-find. A window spans the
/// component's bounding box plus, when it exists in the frame, the column
/// to its right, where a hole border of the component may be started by
/// the raster scan.
pub fn label_components(pixels: &[u8], width: usize, height: usize, level: i16) -> Components {
    let runs = white_runs(pixels, width, height, level);
    let mut parent: Vec<usize> = (0..runs.len()).collect();
    let (mut above, mut row_start) = (0, 0);
    for i in 0..runs.len() {
        if i > 0 && runs[i].y != runs[i - 1].y {
            // Runs of the row just finished become the row above.
            above = if runs[i].y == runs[i - 1].y + 1 {
                row_start
            } else {
                i
            };
            row_start = i;
        }
        let r = runs[i];
        for (j, q) in runs[above..row_start].iter().enumerate() {
            if q.x0 <= r.x1 + 1 && q.x1 + 1 >= r.x0 {
                union(&mut parent, i, above + j);
            }
        }
    }
    // Label per root in order of first run (= raster order of first pixel).
    let mut label = vec![usize::MAX; runs.len()];
    let mut owner = Vec::with_capacity(runs.len());
    let mut bbox: Vec<[usize; 5]> = Vec::new();
    for (i, r) in runs.iter().enumerate() {
        let root = find(&mut parent, i);
        if label[root] == usize::MAX {
            label[root] = bbox.len();
            bbox.push([r.x0, r.y, r.x1, r.y, 0]);
        }
        let k = label[root];
        let b = &mut bbox[k];
        *b = [
            b[0].min(r.x0),
            b[1],
            b[2].max(r.x1),
            r.y,
            b[4] + r.x1 + 1 - r.x0,
        ];
        owner.push(k);
    }
    let mut out = Components {
        windows: Vec::with_capacity(bbox.len()),
        values: Vec::new(),
        sorted: Vec::new(),
    };
    for &[x0, y0, x1, y1, count] in &bbox {
        let w = (x1 + 2).min(width) - x0;
        let h = y1 + 1 - y0;
        let (v, s) = (out.values.len(), out.sorted.len());
        out.values.resize(v + w * h, -1);
        out.sorted.resize(s + count, 0);
        out.windows.push(Window {
            origin: [x0 as i32, y0 as i32],
            width: w,
            height: h,
            values: v..v + w * h,
            sorted: s..s,
        });
    }
    for (r, &k) in runs.iter().zip(&owner) {
        let win = &mut out.windows[k];
        let row = &pixels[r.y * width + r.x0..=r.y * width + r.x1];
        let dst = win.values.start + (r.y - win.origin[1] as usize) * win.width;
        let dst = dst + r.x0 - win.origin[0] as usize;
        for (d, &p) in out.values[dst..dst + row.len()].iter_mut().zip(row) {
            *d = i16::from(p);
        }
        let end = win.sorted.end;
        out.sorted[end..end + row.len()].copy_from_slice(row);
        win.sorted.end += row.len();
    }
    for win in &out.windows {
        out.sorted[win.sorted.clone()].sort_unstable();
    }
    out
}

fn white_runs(pixels: &[u8], width: usize, height: usize, level: i16) -> Vec<Run> {
    let mut runs = Vec::new();
    for (y, row) in pixels.chunks_exact(width).take(height).enumerate() {
        let mut x = 0;
        while x < width {
            // Zero pixels are never white (level >= 0): skip them 8 at a time.
            if level >= 0 && x + 8 <= width && row[x..x + 8] == [0; 8] {
                x += 8;
                continue;
            }
            if i16::from(row[x]) <= level {
                x += 1;
                continue;
            }
            let x0 = x;
            while x < width && i16::from(row[x]) > level {
                x += 1;
            }
            runs.push(Run { y, x0, x1: x - 1 });
        }
    }
    runs
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    // The smaller index stays root, so roots are first runs.
    if ra < rb {
        parent[rb] = ra;
    } else {
        parent[ra] = rb;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Smoothed random grey image with blobs, holes and touching shapes.
    fn random_image(rng: &mut ChaCha8Rng, width: usize, height: usize) -> Vec<u8> {
        let noise: Vec<f64> = (0..width * height)
            .map(|_| rng.random_range(0.0..255.0))
            .collect();
        let mut out = vec![0u8; width * height];
        for y in 0..height {
            for x in 0..width {
                let (mut s, mut n) = (0.0, 0.0);
                for ny in y.saturating_sub(1)..=(y + 1).min(height - 1) {
                    for nx in x.saturating_sub(1)..=(x + 1).min(width - 1) {
                        s += noise[ny * width + nx];
                        n += 1.0;
                    }
                }
                out[y * width + x] = ((s / n - 127.5) * 5.0 + 127.5).clamp(0.0, 255.0) as u8;
            }
        }
        out
    }

    /// Component-by-component tracing gives exactly the contours of a
    /// full-frame pass, in the same order once sorted by starting pixel.
    #[test]
    fn per_component_tracing_matches_full_frame() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for case in 0..40 {
            let (width, height) = (rng.random_range(1..40), rng.random_range(1..40));
            let pixels = random_image(&mut rng, width, height);
            let base: i16 = rng.random_range(-1..180);
            let components = label_components(&pixels, width, height, base);
            for level in [base, base + 3, base + 15, base + 60] {
                let mut full = ContourScanner::new(width, height);
                full.binarise(&pixels, f64::from(level));
                full.trace_all();
                let expected: Vec<([i32; 2], Vec<[i32; 2]>)> = full
                    .contours_with_trigger()
                    .map(|(t, c)| (t, c.to_vec()))
                    .collect();
                let mut got = Vec::new();
                let mut scanner = ContourScanner::new(0, 0);
                for k in 0..components.len() {
                    components.trace(k, &mut scanner, level.min(255));
                    got.extend(
                        scanner
                            .contours_with_trigger()
                            .map(|(t, c)| (t, c.to_vec())),
                    );
                }
                got.sort_by_key(|(t, _)| (t[1], t[0]));
                assert_eq!(got, expected, "case {case} level {level}");
            }
        }
    }

    #[test]
    fn counts_above_a_level() {
        let pixels = [0u8, 10, 20, 30, 0, 0, 0, 40, 0];
        let components = label_components(&pixels, 3, 3, 5);
        assert_eq!(components.len(), 1, "diagonal pixels are 8-connected");
        assert_eq!(components.count_above(0, 5), 4);
        assert_eq!(components.count_above(0, 20), 2);
        assert_eq!(components.count_above(0, 40), 0);
    }
}
