//! The preprocessing's pixel filters, with OpenCV's semantics: grey
//! conversion (`cvtColor` `BGR2GRAY` weights), median blur and the
//! adaptive threshold (`adaptiveThreshold` with `THRESH_BINARY`), borders
//! replicated as OpenCV's `BORDER_REPLICATE`. Each gives the same pixels
//! as cv2 5.0.0 (checked on random smoothed colour and grey frames, blocks
//! 3-61, `C` of -5, 0 and 2.5; the script is kept outside the repository).

use image::DynamicImage;

use crate::blob::Frame;

/// Grey frame of an image: grey input as it is (16-bit scaled to 8), colour
/// by `(9798 R + 19235 G + 3735 B + 2^14) >> 15` (0.299 / 0.587 / 0.114 in
/// the 15-bit fixed point OpenCV's vectorised `cvtColor` uses: the same as
/// cv2 5.0.0 bit for bit), alpha ignored.
pub fn grey_of(image: &DynamicImage) -> Frame {
    match image {
        DynamicImage::ImageLuma8(grey) => grey.clone(),
        DynamicImage::ImageLuma16(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageLumaA16(_) => image.to_luma8(),
        DynamicImage::ImageRgb8(rgb) => weighted(rgb.as_raw(), 3, rgb.width(), rgb.height()),
        DynamicImage::ImageRgba8(rgba) => weighted(rgba.as_raw(), 4, rgba.width(), rgba.height()),
        other => {
            let rgb = other.to_rgb8();
            weighted(rgb.as_raw(), 3, rgb.width(), rgb.height())
        }
    }
}

fn weighted(raw: &[u8], channels: usize, width: u32, height: u32) -> Frame {
    let grey = raw
        .chunks_exact(channels)
        .map(|p| {
            let (r, g, b) = (u32::from(p[0]), u32::from(p[1]), u32::from(p[2]));
            ((r * 9798 + g * 19235 + b * 3735 + (1 << 14)) >> 15) as u8
        })
        .collect();
    Frame::from_raw(width, height, grey).unwrap_or_else(|| Frame::new(width, height))
}

/// Index `i` clamped into `0..len` (replicated border).
fn clamp(i: i64, len: usize) -> usize {
    i.clamp(0, len as i64 - 1) as usize
}

/// Median of each `k` x `k` neighbourhood (odd `k`), borders replicated
/// (OpenCV `medianBlur`).
pub fn median_blur(frame: &Frame, k: u32) -> Frame {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    if w == 0 || h == 0 || k < 3 {
        return frame.clone();
    }
    let r = i64::from(k / 2);
    let raw = frame.as_raw();
    let mut out = vec![0u8; w * h];
    let mut histogram = [0u32; 256];
    let half = k * k / 2;
    for y in 0..h {
        histogram.fill(0);
        for dy in -r..=r {
            let row = clamp(y as i64 + dy, h) * w;
            for dx in -r..=r {
                histogram[usize::from(raw[row + clamp(dx, w)])] += 1;
            }
        }
        for x in 0..w {
            if x > 0 {
                // Slide right: drop column x - 1 - r, add column x + r.
                let (gone, come) = (clamp(x as i64 - 1 - r, w), clamp(x as i64 + r, w));
                for dy in -r..=r {
                    let row = clamp(y as i64 + dy, h) * w;
                    histogram[usize::from(raw[row + gone])] -= 1;
                    histogram[usize::from(raw[row + come])] += 1;
                }
            }
            let mut seen = 0;
            for (v, &n) in histogram.iter().enumerate() {
                seen += n;
                if seen > half {
                    out[y * w + x] = v as u8;
                    break;
                }
            }
        }
    }
    Frame::from_raw(w as u32, h as u32, out).unwrap_or_else(|| frame.clone())
}

/// OpenCV's `adaptiveThreshold(src, 255, method, THRESH_BINARY, block, c)`:
/// white where `v - mean > -ceil(c)`, `mean` the neighbourhood mean as a
/// grey level, borders replicated. The box mean (`gaussian` false) is the
/// exact block sum over the block's area, rounded (never a tie: the area
/// is odd); the Gaussian mean is computed as OpenCV does, in `f32` with
/// the kernel of `gaussian_weights`, symmetric taps paired, rounded half
/// to even. `block` odd and >= 3 (checked by the caller). On a constant
/// frame `v - mean = 0`: all white when `c > 0`, else black.
pub fn adaptive_threshold(frame: &Frame, block: u32, c: f64, gaussian: bool) -> Frame {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    if w == 0 || h == 0 {
        return frame.clone();
    }
    let mean = if gaussian {
        gaussian_mean(frame.as_raw(), w, h, &gaussian_weights(block))
    } else {
        box_mean(frame.as_raw(), w, h, block as usize)
    };
    let delta = c.ceil();
    let out = frame
        .as_raw()
        .iter()
        .zip(&mean)
        .map(|(&v, &m)| {
            if f64::from(v) - f64::from(m) > -delta {
                255
            } else {
                0
            }
        })
        .collect();
    Frame::from_raw(w as u32, h as u32, out).unwrap_or_else(|| frame.clone())
}

/// OpenCV's `getGaussianKernel(k, 0, CV_32F)`: its fixed kernels for k =
/// 3, 5, 7, else sampled with sigma `0.3 ((k - 1) / 2 - 1) + 0.8`; each tap
/// rounded to `f32`, then scaled by the inverse of their (double) sum.
fn gaussian_weights(k: u32) -> Vec<f32> {
    let raw: Vec<f64> = match k {
        3 => vec![0.25, 0.5, 0.25],
        5 => vec![0.0625, 0.25, 0.375, 0.25, 0.0625],
        7 => vec![
            0.03125, 0.109375, 0.21875, 0.28125, 0.21875, 0.109375, 0.03125,
        ],
        _ => {
            let sigma = 0.3 * ((f64::from(k) - 1.0) * 0.5 - 1.0) + 0.8;
            let centre = (f64::from(k) - 1.0) * 0.5;
            (0..k)
                .map(|i| (-(f64::from(i) - centre).powi(2) / (2.0 * sigma * sigma)).exp())
                .collect()
        }
    };
    let taps: Vec<f32> = raw.iter().map(|&t| t as f32).collect();
    let scale = 1.0 / taps.iter().map(|&t| f64::from(t)).sum::<f64>();
    taps.iter()
        .map(|&t| (f64::from(t) * scale) as f32)
        .collect()
}

/// The exact `block` x `block` box mean, rounded (replicated borders).
fn box_mean(raw: &[u8], w: usize, h: usize, block: usize) -> Vec<u8> {
    let r = (block / 2) as i64;
    let mut rows = vec![0u32; w * h];
    for y in 0..h {
        let line = &raw[y * w..(y + 1) * w];
        for x in 0..w {
            rows[y * w + x] = (-r..=r)
                .map(|d| u32::from(line[clamp(x as i64 + d, w)]))
                .sum();
        }
    }
    let area = (block * block) as f64;
    let mut out = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let sum: u32 = (-r..=r).map(|d| rows[clamp(y as i64 + d, h) * w + x]).sum();
            out[y * w + x] = (f64::from(sum) / area).round() as u8;
        }
    }
    out
}

/// The separable Gaussian mean in `f32` (rows, then columns; replicated
/// borders; each pair of symmetric taps summed before weighting),
/// rounded half to even (OpenCV's `GaussianBlur` on a `CV_32F` copy, then
/// `convertTo` back to 8 bits).
fn gaussian_mean(raw: &[u8], w: usize, h: usize, weights: &[f32]) -> Vec<u8> {
    let r = weights.len() / 2;
    let symmetric = |at: &dyn Fn(i64) -> f32| -> f32 {
        let mut s = weights[r] * at(0);
        for k in 1..=r {
            s += weights[r + k] * (at(-(k as i64)) + at(k as i64));
        }
        s
    };
    let mut rows = vec![0.0f32; w * h];
    for y in 0..h {
        let line = &raw[y * w..(y + 1) * w];
        for x in 0..w {
            rows[y * w + x] = symmetric(&|d| f32::from(line[clamp(x as i64 + d, w)]));
        }
    }
    let mut out = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let v = symmetric(&|d| rows[clamp(y as i64 + d, h) * w + x]);
            out[y * w + x] = v.round_ties_even().clamp(0.0, 255.0) as u8;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_uses_opencv_weights_and_ignores_alpha() {
        let rgb = image::RgbImage::from_pixel(2, 1, image::Rgb([200, 100, 50]));
        let rgba = image::RgbaImage::from_pixel(2, 1, image::Rgba([200, 100, 50, 0]));
        let want = (200.0f64 * 0.299 + 100.0 * 0.587 + 50.0 * 0.114).round() as u8;
        assert_eq!(
            grey_of(&DynamicImage::ImageRgb8(rgb)).as_raw(),
            &vec![want; 2]
        );
        assert_eq!(
            grey_of(&DynamicImage::ImageRgba8(rgba)).as_raw(),
            &vec![want; 2]
        );
    }

    /// The sliding-histogram median equals a sort of each window.
    #[test]
    fn median_blur_matches_sorting_each_window() {
        let frame = Frame::from_fn(13, 9, |x, y| image::Luma([((x * 37 + y * 91) % 251) as u8]));
        for k in [3u32, 5] {
            let out = median_blur(&frame, k);
            let r = i64::from(k / 2);
            for (x, y, v) in out.enumerate_pixels() {
                let mut window = Vec::new();
                for dy in -r..=r {
                    for dx in -r..=r {
                        let (xx, yy) = (clamp(i64::from(x) + dx, 13), clamp(i64::from(y) + dy, 9));
                        window.push(frame.get_pixel(xx as u32, yy as u32)[0]);
                    }
                }
                window.sort_unstable();
                assert_eq!(v[0], window[window.len() / 2], "k {k} at ({x}, {y})");
            }
        }
    }

    /// One pixel of 8 on black, block 3, C = 1: the Gaussian mean is 2 at
    /// the pixel, 1 beside it and exactly 0.5 on its diagonals, which
    /// OpenCV rounds half to even (to 0: white, as `v - 0 > -1`); cv2 5.0.0
    /// gives this very frame.
    #[test]
    fn adaptive_gaussian_rounds_its_mean_half_to_even_as_opencv() {
        let mut frame = Frame::new(7, 7);
        frame.put_pixel(3, 3, image::Luma([8]));
        let out = adaptive_threshold(&frame, 3, 1.0, true);
        for (x, y, v) in out.enumerate_pixels() {
            let beside = (x as i32 - 3).abs() + (y as i32 - 3).abs() == 1;
            assert_eq!(v[0], if beside { 0 } else { 255 }, "({x}, {y})");
        }
    }

    #[test]
    fn gaussian_weights_sum_to_one_and_peak_in_the_middle() {
        for k in [3u32, 5, 7, 9, 61] {
            let g = gaussian_weights(k);
            let total: f64 = g.iter().map(|&v| f64::from(v)).sum();
            assert!((total - 1.0).abs() < 1e-6, "{k}");
            assert!(g[k as usize / 2] > g[0], "{k}");
        }
    }
}
