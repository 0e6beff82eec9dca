//! A grey frame brought to a model's input size by area averaging: each
//! output pixel is the mean of the source pixels its box covers, partly
//! covered pixels weighted by the covered fraction (exact for an integer
//! factor, e.g. 256 -> 64 px averages 4 x 4 blocks). The same function
//! makes a dataset's `frames.npy` and a model's input from a live frame,
//! so both see the same pixels.

/// The `height x width` frame `src` (row-major) area-averaged to
/// `out_height x out_width`, rounded to the nearest grey level. An empty
/// frame or size gives an empty result.
pub fn area_resample(
    src: &[u8],
    (height, width): (usize, usize),
    (out_height, out_width): (usize, usize),
) -> Vec<u8> {
    if height == 0 || width == 0 || out_height == 0 || out_width == 0 {
        return Vec::new();
    }
    debug_assert_eq!(src.len(), height * width);
    let rows = spans(height, out_height);
    let cols = spans(width, out_width);
    let mut out = Vec::with_capacity(out_height * out_width);
    for row in &rows {
        for col in &cols {
            let (mut sum, mut weight) = (0.0f64, 0.0f64);
            for &(y, wy) in row {
                let line = &src[y * width..(y + 1) * width];
                for &(x, wx) in col {
                    sum += wy * wx * line[x] as f64;
                    weight += wy * wx;
                }
            }
            out.push((sum / weight).round().clamp(0.0, 255.0) as u8);
        }
    }
    out
}

/// For each of `n` output cells over `len` source pixels: the source
/// pixels it covers with the fraction of each it covers.
fn spans(len: usize, n: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = len as f64 / n as f64;
    (0..n)
        .map(|i| {
            let (a, b) = (i as f64 * scale, (i + 1) as f64 * scale);
            let first = a.floor() as usize;
            let last = (b.ceil() as usize).min(len);
            (first..last)
                .map(|p| {
                    let covered = (b.min(p as f64 + 1.0) - a.max(p as f64)).max(0.0);
                    (p, covered)
                })
                .filter(|&(_, w)| w > 1e-12)
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_integer_factor_averages_blocks() {
        // 4 x 4 -> 2 x 2: each output the mean of a 2 x 2 block.
        let src = [
            0, 2, 10, 10, //
            4, 6, 10, 12, //
            255, 255, 0, 0, //
            255, 255, 0, 1,
        ];
        assert_eq!(area_resample(&src, (4, 4), (2, 2)), vec![3, 11, 255, 0]);
        // Same size: unchanged.
        assert_eq!(area_resample(&src, (4, 4), (4, 4)), src.to_vec());
    }

    #[test]
    fn a_fractional_factor_weights_partly_covered_pixels() {
        // 3 px -> 2 px: [a, b/2] and [b/2, c], each over 1.5 px.
        let src = [0, 90, 180];
        assert_eq!(area_resample(&src, (1, 3), (1, 2)), vec![30, 150]);
        // A constant frame stays constant at any size.
        let flat = vec![77u8; 7 * 5];
        assert!(area_resample(&flat, (7, 5), (3, 4))
            .iter()
            .all(|&v| v == 77));
    }
}
