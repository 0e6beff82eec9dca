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
    let x0 = (c[0] - r - 1.0).floor().max(0.0) as i64;
    let y0 = (c[1] - r - 1.0).floor().max(0.0) as i64;
    let x1 = ((c[0] + r + 1.0).ceil() as i64).min(w as i64 - 1);
    let y1 = ((c[1] + r + 1.0).ceil() as i64).min(h as i64 - 1);
    let width = w as usize;
    let buf: &mut [u8] = frame;
    for y in y0..=y1 {
        let dy = y as f64 - c[1];
        let row = y as usize * width;
        for x in x0..=x1 {
            let dx = x as f64 - c[0];
            let cover = (r + 0.5 - (dx * dx + dy * dy).sqrt()).clamp(0.0, 1.0);
            if cover > 0.0 {
                let v = (255.0 * cover + 0.5) as u8;
                let px = &mut buf[row + x as usize];
                *px = (*px).max(v);
            }
        }
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
