//! Training copies of a binarised TacTip frame that keep its pose
//! (docs/learning.md, "Augmentation that keeps the pose"): applied to the
//! frame at its full size, before area averaging to the model's input.
//!
//! Whole-frame shifts are not among them: every pin moving together reads
//! as a pose change. These change what a pose change cannot:
//! - **edge flips**: each pixel on a blob's boundary (white beside black,
//!   or black beside white, 4-neighbours) flips with probability `q`, as a
//!   slightly different threshold or camera noise would; a blob's centroid
//!   moves by a fraction of a pixel, at random;
//! - **pin dropout**: each white 4-connected blob of at most `max_pin_area`
//!   pixels (a pin; the rim's arcs are larger) is erased with probability
//!   `p`, so the network cannot lean on any one pin.
use crate::error::{config_error, ConvError};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Binary level: pixels at or above it are white (a pin or the rim).
const WHITE: u8 = 128;

/// What a training copy changes; every draw is from `seed`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseKeepingJitter {
    /// Probability that a boundary pixel flips, in [0, 0.5].
    pub edge_flip: f64,
    /// Probability that a pin (a small blob) is erased, in [0, 1].
    pub pin_drop: f64,
    /// Largest blob, px, counted as a pin.
    pub max_pin_area: usize,
}

impl PoseKeepingJitter {
    /// The jitter, its probabilities checked.
    pub fn new(edge_flip: f64, pin_drop: f64, max_pin_area: usize) -> Result<Self, ConvError> {
        if !(0.0..=0.5).contains(&edge_flip) {
            return Err(config_error(
                "edge_flip",
                format!("{edge_flip} is not in [0, 0.5]"),
            ));
        }
        if !(0.0..=1.0).contains(&pin_drop) {
            return Err(config_error(
                "pin_drop",
                format!("{pin_drop} is not in [0, 1]"),
            ));
        }
        Ok(PoseKeepingJitter {
            edge_flip,
            pin_drop,
            max_pin_area,
        })
    }

    /// A copy of the `height x width` binary frame `src` (row-major, 0 or
    /// 255) with the jitter drawn from `seed`; the same seed gives the
    /// same copy.
    pub fn apply(&self, src: &[u8], (height, width): (usize, usize), seed: u64) -> Vec<u8> {
        debug_assert_eq!(src.len(), height * width);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut out = src.to_vec();
        if self.pin_drop > 0.0 {
            drop_pins(&mut out, (height, width), self, &mut rng);
        }
        if self.edge_flip > 0.0 {
            out = flip_edges(&out, (height, width), self.edge_flip, &mut rng);
        }
        out
    }
}

/// The 4-neighbours of pixel `i` inside the frame.
fn neighbours(i: usize, (height, width): (usize, usize)) -> impl Iterator<Item = usize> {
    let (y, x) = (i / width, i % width);
    [
        (y > 0).then(|| i - width),
        (y + 1 < height).then(|| i + width),
        (x > 0).then(|| i - 1),
        (x + 1 < width).then(|| i + 1),
    ]
    .into_iter()
    .flatten()
}

/// Every boundary pixel of `src` flipped with probability `q`; whether a
/// pixel is on the boundary is read from `src`, so flips do not spread.
fn flip_edges(src: &[u8], shape: (usize, usize), q: f64, rng: &mut ChaCha8Rng) -> Vec<u8> {
    let white = |v: u8| v >= WHITE;
    (0..src.len())
        .map(|i| {
            let own = white(src[i]);
            let edge = neighbours(i, shape).any(|j| white(src[j]) != own);
            match edge && rng.random_bool(q) {
                true if own => 0,
                true => 255,
                false => src[i],
            }
        })
        .collect()
}

/// Each white blob of at most `max_pin_area` px erased with probability
/// `pin_drop`; blobs are found in raster order, so the draws are too.
fn drop_pins(
    out: &mut [u8],
    shape: (usize, usize),
    jitter: &PoseKeepingJitter,
    rng: &mut ChaCha8Rng,
) {
    let mut seen = vec![false; out.len()];
    let mut stack = Vec::new();
    for start in 0..out.len() {
        if seen[start] || out[start] < WHITE {
            continue;
        }
        let mut blob = Vec::new();
        seen[start] = true;
        stack.push(start);
        while let Some(i) = stack.pop() {
            blob.push(i);
            for j in neighbours(i, shape) {
                if !seen[j] && out[j] >= WHITE {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        if blob.len() <= jitter.max_pin_area && rng.random_bool(jitter.pin_drop) {
            blob.iter().for_each(|&i| out[i] = 0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 12 x 12 frame: a 2 x 2 pin at (2, 2), a 3 x 3 pin at (7, 7) and a
    /// 12 px bar (the rim) along the last row.
    fn frame() -> Vec<u8> {
        let mut f = vec![0u8; 144];
        for (y, x) in [(2, 2), (2, 3), (3, 2), (3, 3)] {
            f[y * 12 + x] = 255;
        }
        for y in 7..10 {
            for x in 7..10 {
                f[y * 12 + x] = 255;
            }
        }
        f[132..].fill(255);
        f
    }

    fn jitter(edge_flip: f64, pin_drop: f64) -> PoseKeepingJitter {
        PoseKeepingJitter::new(edge_flip, pin_drop, 9).unwrap()
    }

    #[test]
    fn probabilities_out_of_range_are_refused() {
        for (q, p) in [(0.6, 0.0), (-0.1, 0.0), (0.0, 1.5), (f64::NAN, 0.0)] {
            let e = PoseKeepingJitter::new(q, p, 9).unwrap_err();
            assert!(matches!(e, ConvError::Config { .. }));
        }
    }

    #[test]
    fn no_jitter_is_the_frame() {
        assert_eq!(jitter(0.0, 0.0).apply(&frame(), (12, 12), 3), frame());
    }

    #[test]
    fn certain_dropout_erases_the_pins_and_keeps_the_rim() {
        let out = jitter(0.0, 1.0).apply(&frame(), (12, 12), 3);
        assert!(out[..132].iter().all(|&v| v == 0));
        assert!(out[132..].iter().all(|&v| v == 255));
    }

    #[test]
    fn flips_touch_only_boundary_pixels() {
        let src = frame();
        let out = jitter(0.5, 0.0).apply(&src, (12, 12), 7);
        assert_ne!(out, src);
        // the 3 x 3 pin's centre and far background have no other neighbour
        assert_eq!(out[8 * 12 + 8], 255);
        assert_eq!(out[5 * 12 + 10], 0);
        assert_eq!(out[0], 0);
    }

    /// The white pixels' centroid (row, column) of a 12 x 12 frame.
    fn centroid(f: &[u8]) -> (f64, f64) {
        let white: Vec<usize> = (0..f.len()).filter(|&i| f[i] >= WHITE).collect();
        let n = white.len() as f64;
        let sum = |g: fn(usize) -> usize| white.iter().map(|&i| g(i) as f64).sum::<f64>() / n;
        (sum(|i| i / 12), sum(|i| i % 12))
    }

    #[test]
    fn flips_leave_a_pin_where_it_was_on_average() {
        // a lone 3 x 3 pin centred on (8, 8): flips are symmetric about it,
        // so the centroid moves at random but not on average
        let mut f = vec![0u8; 144];
        for i in [91, 92, 93, 103, 104, 105, 115, 116, 117] {
            f[i] = 255;
        }
        let j = jitter(0.3, 0.0);
        let runs = 2000;
        let (mut y, mut x, mut moved) = (0.0, 0.0, 0);
        for seed in 0..runs {
            let (cy, cx) = centroid(&j.apply(&f, (12, 12), seed));
            moved += usize::from((cy, cx) != (8.0, 8.0));
            y += cy / runs as f64;
            x += cx / runs as f64;
        }
        assert!(moved > runs as usize / 2, "{moved} of {runs} copies moved");
        assert!((y - 8.0).abs() < 0.02 && (x - 8.0).abs() < 0.02, "{y} {x}");
    }

    #[test]
    fn dropout_erases_pins_at_its_rate() {
        let (runs, p) = (2000, 0.3);
        let j = jitter(0.0, p);
        let erased: usize = (0..runs)
            .map(|s| {
                let out = j.apply(&frame(), (12, 12), s);
                usize::from(out[2 * 12 + 2] == 0) + usize::from(out[8 * 12 + 8] == 0)
            })
            .sum();
        let rate = erased as f64 / (2 * runs) as f64;
        // binomial standard deviation sqrt(p (1 - p) / 4000) = 0.007
        assert!((rate - p).abs() < 0.03, "{rate}");
    }

    #[test]
    fn a_seed_gives_one_copy() {
        let j = jitter(0.3, 0.5);
        let a = j.apply(&frame(), (12, 12), 11);
        assert_eq!(a, j.apply(&frame(), (12, 12), 11));
        assert!((12..40).any(|s| j.apply(&frame(), (12, 12), s) != a));
    }
}
