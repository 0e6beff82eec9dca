//! Local image filters with OpenCV semantics: median blur and adaptive
//! threshold (mean-C via an integral image, Gaussian-C via a separable
//! kernel), both with replicated borders as OpenCV uses them.
//!
//! The Bristol TacTip pipeline binarises each frame with
//! `adaptiveThreshold(frame, 255, ADAPTIVE_THRESH_GAUSSIAN_C, THRESH_BINARY,
//! block, C)` after a 5x5 median blur; with block 61 and C = -5 a pixel turns
//! white when it is more than 5 grey levels brighter than its neighbourhood
//! mean, giving white pins on black.
use image::GrayImage;
use serde::{Deserialize, Serialize};

/// How the neighbourhood mean of [`adaptive_threshold`] is weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ThresholdMethod {
    /// Plain block mean (OpenCV `ADAPTIVE_THRESH_MEAN_C`).
    Mean,
    /// Gaussian-weighted block mean (OpenCV `ADAPTIVE_THRESH_GAUSSIAN_C`),
    /// sigma = 0.3 ((block - 1) / 2 - 1) + 0.8 as OpenCV derives it.
    #[default]
    Gaussian,
}

/// Index clamped into 0..len: OpenCV's BORDER_REPLICATE.
fn clamp_index(i: i64, len: u32) -> u32 {
    i.clamp(0, len as i64 - 1) as u32
}

/// Median of each `ksize` x `ksize` neighbourhood (odd `ksize`), borders
/// replicated, like OpenCV `medianBlur`.
pub fn median_blur(image: &GrayImage, ksize: u32) -> GrayImage {
    let (w, h) = image.dimensions();
    if w == 0 || h == 0 || ksize < 3 {
        return image.clone();
    }
    let r = (ksize / 2) as i64;
    let mut window = Vec::with_capacity((ksize * ksize) as usize);
    GrayImage::from_fn(w, h, |x, y| {
        window.clear();
        for dy in -r..=r {
            let yy = clamp_index(y as i64 + dy, h);
            for dx in -r..=r {
                window.push(image.get_pixel(clamp_index(x as i64 + dx, w), yy)[0]);
            }
        }
        let mid = window.len() / 2;
        image::Luma([*window.select_nth_unstable(mid).1])
    })
}

/// Block mean with replicated borders from an integral image, rounded to
/// u8 as OpenCV's normalised `boxFilter` on 8-bit data.
pub fn box_mean(image: &GrayImage, block: u32) -> GrayImage {
    let (w, h) = image.dimensions();
    let r = (block / 2) as i64;
    let (pw, ph) = (w as i64 + 2 * r, h as i64 + 2 * r);
    // integral[(y * (pw + 1)) + x] = sum of padded pixels above-left of (x, y).
    let stride = (pw + 1) as usize;
    let mut integral = vec![0u64; stride * (ph as usize + 1)];
    for py in 0..ph {
        let sy = clamp_index(py - r, h);
        let mut row_sum = 0u64;
        for px in 0..pw {
            row_sum += image.get_pixel(clamp_index(px - r, w), sy)[0] as u64;
            let at = (py as usize + 1) * stride + px as usize + 1;
            integral[at] = integral[at - stride] + row_sum;
        }
    }
    let area = (block as u64) * (block as u64);
    let b = block as usize;
    GrayImage::from_fn(w, h, |x, y| {
        let (x0, y0) = (x as usize, y as usize);
        let sum = integral[(y0 + b) * stride + x0 + b] + integral[y0 * stride + x0]
            - integral[y0 * stride + x0 + b]
            - integral[(y0 + b) * stride + x0];
        image::Luma([((sum as f64) / area as f64).round() as u8])
    })
}

/// OpenCV's default Gaussian sigma for a kernel of `ksize` taps.
pub fn opencv_sigma(ksize: u32) -> f64 {
    0.3 * ((ksize as f64 - 1.0) * 0.5 - 1.0) + 0.8
}

fn gaussian_kernel(ksize: u32) -> Vec<f64> {
    let sigma = opencv_sigma(ksize);
    let c = (ksize / 2) as f64;
    let raw: Vec<f64> = (0..ksize)
        .map(|i| (-((i as f64 - c).powi(2)) / (2.0 * sigma * sigma)).exp())
        .collect();
    let total: f64 = raw.iter().sum();
    raw.into_iter().map(|v| v / total).collect()
}

/// Gaussian-weighted block mean (separable, replicated borders), rounded
/// to u8 as OpenCV's `GaussianBlur` on 8-bit data (up to its fixed-point
/// rounding, which can differ by one grey level).
pub fn gaussian_mean(image: &GrayImage, block: u32) -> GrayImage {
    let (w, h) = image.dimensions();
    let kernel = gaussian_kernel(block);
    let r = (block / 2) as i64;
    let mut rows = vec![0.0f64; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            rows[(y * w + x) as usize] = kernel
                .iter()
                .enumerate()
                .map(|(k, wk)| {
                    wk * image.get_pixel(clamp_index(x as i64 + k as i64 - r, w), y)[0] as f64
                })
                .sum();
        }
    }
    GrayImage::from_fn(w, h, |x, y| {
        let v: f64 = kernel
            .iter()
            .enumerate()
            .map(|(k, wk)| wk * rows[(clamp_index(y as i64 + k as i64 - r, h) * w + x) as usize])
            .sum();
        image::Luma([v.round().clamp(0.0, 255.0) as u8])
    })
}

/// OpenCV `adaptiveThreshold(src, 255, method, THRESH_BINARY, block, c)`:
/// a pixel becomes 255 when `src - mean > -ceil(c)`, else 0, where `mean`
/// is the 8-bit (rounded) neighbourhood mean. `block` must be odd and at
/// least 3 (checked by [`crate::PreprocessConfig::validate`]).
pub fn adaptive_threshold(
    image: &GrayImage,
    method: ThresholdMethod,
    block: u32,
    c: f64,
) -> GrayImage {
    let (w, h) = image.dimensions();
    if w == 0 || h == 0 {
        return image.clone();
    }
    let mean = match method {
        ThresholdMethod::Mean => box_mean(image, block),
        ThresholdMethod::Gaussian => gaussian_mean(image, block),
    };
    let delta = c.ceil() as i32;
    GrayImage::from_fn(w, h, |x, y| {
        let diff = image.get_pixel(x, y)[0] as i32 - mean.get_pixel(x, y)[0] as i32;
        image::Luma([if diff > -delta { 255 } else { 0 }])
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn noise(w: u32, h: u32, seed: u64) -> GrayImage {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        GrayImage::from_fn(w, h, |_, _| image::Luma([rng.random_range(0..=255u8)]))
    }

    /// Brute-force block mean with clamped coordinates.
    fn naive_mean(image: &GrayImage, block: u32, x: u32, y: u32) -> u8 {
        let r = (block / 2) as i64;
        let (w, h) = image.dimensions();
        let mut sum = 0u64;
        for dy in -r..=r {
            for dx in -r..=r {
                sum += image.get_pixel(clamp_index(x as i64 + dx, w), clamp_index(y as i64 + dy, h))
                    [0] as u64;
            }
        }
        ((sum as f64) / (block * block) as f64).round() as u8
    }

    #[test]
    fn integral_box_mean_matches_brute_force_with_replicated_borders() {
        let image = noise(23, 17, 7);
        let mean = box_mean(&image, 7);
        for (x, y, p) in mean.enumerate_pixels() {
            assert_eq!(p[0], naive_mean(&image, 7, x, y), "at ({x}, {y})");
        }
    }

    #[test]
    fn constant_image_has_constant_means() {
        let image = GrayImage::from_pixel(40, 30, image::Luma([93]));
        assert!(box_mean(&image, 61).pixels().all(|p| p[0] == 93));
        assert!(gaussian_mean(&image, 61).pixels().all(|p| p[0] == 93));
    }

    #[test]
    fn opencv_sigma_for_block_61_is_9_5() {
        assert!((opencv_sigma(61) - 9.5).abs() < 1e-12);
        let k = gaussian_kernel(61);
        assert!((k.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((k[0] - k[60]).abs() < 1e-15 && k[30] > k[29]);
    }

    #[test]
    fn threshold_picks_bright_spots_with_negative_c() {
        // Dark background 50, one 5x5 bright spot 120, a faint one 53.
        let mut image = GrayImage::from_pixel(64, 64, image::Luma([50]));
        for y in 20..25 {
            for x in 20..25 {
                image.put_pixel(x, y, image::Luma([120]));
                image.put_pixel(x + 20, y + 20, image::Luma([53]));
            }
        }
        for method in [ThresholdMethod::Mean, ThresholdMethod::Gaussian] {
            let bw = adaptive_threshold(&image, method, 61, -5.0);
            assert_eq!(bw.get_pixel(22, 22)[0], 255, "{method:?}");
            assert_eq!(bw.get_pixel(42, 42)[0], 0, "faint spot, {method:?}");
            assert_eq!(bw.get_pixel(5, 5)[0], 0, "background, {method:?}");
            let white = bw.pixels().filter(|p| p[0] == 255).count();
            assert_eq!(white, 25, "{method:?}");
        }
    }

    #[test]
    fn positive_c_keeps_flat_regions_white() {
        // OpenCV: src - mean > -ceil(c); with c = 2 a flat region (diff 0) is white.
        let image = GrayImage::from_pixel(10, 10, image::Luma([7]));
        let bw = adaptive_threshold(&image, ThresholdMethod::Mean, 3, 2.0);
        assert!(bw.pixels().all(|p| p[0] == 255));
    }

    #[test]
    fn median_removes_salt_noise_and_keeps_edges() {
        let mut image =
            GrayImage::from_fn(20, 20, |x, _| image::Luma([if x < 10 { 0 } else { 200 }]));
        image.put_pixel(4, 4, image::Luma([255]));
        let out = median_blur(&image, 5);
        assert_eq!(out.get_pixel(4, 4)[0], 0);
        assert_eq!(out.get_pixel(9, 10)[0], 0);
        assert_eq!(out.get_pixel(10, 10)[0], 200);
    }
}
