//! Drawing pins into a frame: anti-aliased white discs on black, touching
//! only each disc's bounding box so a 127-pin frame takes microseconds.
use crate::Frame;

use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Draw a disc of radius `r` px centred at `c` (pixel (x, y) has its centre
/// at (x, y)); coverage is the clipped distance ramp `r + 1/2 - d`, and
/// overlapping discs keep the brighter value.
pub(crate) fn draw_disc(frame: &mut Frame, c: [f64; 2], r: f64) {
    let (w, h) = frame.dimensions();
    if !(c[0].is_finite() && c[1].is_finite() && r > 0.0) {
        return;
    }
    let x0 = floor_i64(c[0] - r - 1.0).max(0);
    let y0 = floor_i64(c[1] - r - 1.0).max(0);
    let x1 = ceil_i64(c[0] + r + 1.0).min(w as i64 - 1);
    let y1 = ceil_i64(c[1] + r + 1.0).min(h as i64 - 1);
    let width = w as usize;
    let buf: &mut [u8] = frame;
    // Pixels with d <= r - 1/2 are fully covered and those with
    // d >= r + 1/2 not at all: only the ring between needs a square root.
    let outer2 = (r + 0.5) * (r + 0.5);
    let inner2 = if r > 0.5 { (r - 0.5) * (r - 0.5) } else { -1.0 };
    for y in y0..=y1 {
        let dy = y as f64 - c[1];
        let dy2 = dy * dy;
        if dy2 >= outer2 {
            continue;
        }
        let half = (outer2 - dy2).sqrt();
        let xa = floor_i64(c[0] - half).max(x0);
        let xb = ceil_i64(c[0] + half).min(x1);
        // Fully covered span of this row (any pixel misplaced by rounding
        // at its ends has coverage 1 - eps, which also rounds to 255).
        let (fa, fb) = if dy2 < inner2 {
            let inner = (inner2 - dy2).sqrt();
            (
                ceil_i64(c[0] - inner).max(xa),
                floor_i64(c[0] + inner).min(xb),
            )
        } else {
            (xb + 1, xb)
        };
        let row = &mut buf[y as usize * width..(y as usize + 1) * width];
        if fa <= fb {
            row[fa as usize..=fb as usize].fill(255);
        }
        let edge = (xa..fa.min(xb + 1)).chain((fb + 1).max(xa)..=xb);
        for x in edge {
            let dx = x as f64 - c[0];
            let d2 = dx * dx + dy2;
            if d2 >= outer2 {
                continue;
            }
            let cover = (r + 0.5 - d2.sqrt()).clamp(0.0, 1.0);
            if cover <= 0.0 {
                continue;
            }
            let v = (255.0 * cover + 0.5) as u8;
            let px = &mut row[x as usize];
            *px = (*px).max(v);
        }
    }
}

/// `x.floor() as i64` without the libm call (baseline x86-64 has no
/// rounding instruction); identical for every input, NaN giving 0.
#[inline]
pub(crate) fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `x.ceil() as i64` without the libm call; identical for every input.
#[inline]
pub(crate) fn ceil_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) < x {
        t.saturating_add(1)
    } else {
        t
    }
}

/// Add zero-mean Gaussian noise of standard deviation `std` grey levels.
pub(crate) fn add_noise(frame: &mut Frame, std: f64, rng: &mut ChaCha8Rng) {
    let Ok(normal) = Normal::new(0.0, std) else {
        return;
    };
    for px in frame.iter_mut() {
        let v = *px as f64 + normal.sample(rng);
        *px = v.round().clamp(0.0, 255.0) as u8;
    }
}

/// Shift each pin by independent Gaussian jitter of `std` px per axis.
pub(crate) fn jitter(pins: &[[f64; 2]], std: f64, rng: &mut ChaCha8Rng) -> Vec<[f64; 2]> {
    match Normal::new(0.0, std) {
        Ok(normal) if std > 0.0 => pins
            .iter()
            .map(|p| [p[0] + normal.sample(rng), p[1] + normal.sample(rng)])
            .collect(),
        _ => pins.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plain per-pixel definition the fast span-based drawing must match.
    fn draw_disc_reference(frame: &mut Frame, c: [f64; 2], r: f64) {
        let (w, h) = frame.dimensions();
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as f64 - c[0], y as f64 - c[1]);
                let cover = (r + 0.5 - (dx * dx + dy * dy).sqrt()).clamp(0.0, 1.0);
                if cover > 0.0 {
                    let v = (255.0 * cover + 0.5) as u8;
                    let px = &mut frame.get_pixel_mut(x, y)[0];
                    *px = (*px).max(v);
                }
            }
        }
    }

    #[test]
    fn integer_floor_and_ceil_match_the_float_ones() {
        let xs = [
            -3.5,
            -3.0,
            -2.9999999,
            -0.5,
            -0.0,
            0.0,
            0.2,
            1.0,
            2.5,
            1e15 + 0.5,
            -1e15 - 0.5,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "floor {x}");
            assert_eq!(ceil_i64(x), x.ceil() as i64, "ceil {x}");
        }
    }

    #[test]
    fn span_drawing_matches_the_per_pixel_definition() {
        let mut k = 0u64;
        let mut next = || {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (k >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..40 {
            let (mut fast, mut slow) = (Frame::new(40, 30), Frame::new(40, 30));
            for _ in 0..6 {
                let c = [-6.0 + 52.0 * next(), -6.0 + 42.0 * next()];
                let r = 0.2 + 7.0 * next();
                draw_disc(&mut fast, c, r);
                draw_disc_reference(&mut slow, c, r);
            }
            assert_eq!(fast, slow);
        }
    }
}
