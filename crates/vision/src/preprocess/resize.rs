//! Resizing with OpenCV's semantics: pixel-area averaging (`INTER_AREA`,
//! each output pixel the mean of the input area it covers, fractional
//! pixels weighted by their overlap) and bilinear interpolation
//! (`INTER_LINEAR`, pixel centres aligned: output pixel `i` samples input
//! position `(i + 0.5) scale - 0.5`, clamped to the frame). Both separable;
//! weights per output pixel sum to one, so a constant frame stays constant.
//! Against cv2 5.0.0: area averaging is the same bit for bit; where
//! OpenCV blends two pixels (bilinear, and area when enlarging) it works in
//! 11-bit fixed point and this in `f64`, so a pixel may differ by one grey
//! level.

use super::ResizeMethod;
use crate::blob::Frame;

/// `frame` resized to `size` = `[width, height]` (identity when equal).
/// Area averaging when neither side grows; when one does, OpenCV's
/// `INTER_AREA` takes its enlarging form on both axes (a bilinear blend
/// only across the boundaries between source pixels), and so does this.
pub fn resize(frame: &Frame, size: [u32; 2], method: ResizeMethod) -> Frame {
    let (sw, sh) = (frame.width() as usize, frame.height() as usize);
    let (dw, dh) = (size[0] as usize, size[1] as usize);
    if (sw, sh) == (dw, dh) || sw == 0 || sh == 0 || dw == 0 || dh == 0 {
        return frame.clone();
    }
    let shrinking = dw <= sw && dh <= sh;
    let taps = |src: usize, dst: usize| match method {
        ResizeMethod::Area if shrinking => area_taps(src, dst),
        ResizeMethod::Area => area_up_taps(src, dst),
        ResizeMethod::Bilinear => linear_taps(src, dst),
    };
    let (tx, ty) = (taps(sw, dw), taps(sh, dh));
    let raw = frame.as_raw();
    let mut rows = vec![0.0f64; dw * sh];
    for y in 0..sh {
        let line = &raw[y * sw..(y + 1) * sw];
        for (x, t) in tx.iter().enumerate() {
            rows[y * dw + x] = t.iter().map(|&(i, f)| f * f64::from(line[i])).sum();
        }
    }
    let mut out = vec![0u8; dw * dh];
    for (y, t) in ty.iter().enumerate() {
        for x in 0..dw {
            let v: f64 = t.iter().map(|&(j, f)| f * rows[j * dw + x]).sum();
            out[y * dw + x] = v.round().clamp(0.0, 255.0) as u8;
        }
    }
    Frame::from_raw(dw as u32, dh as u32, out).unwrap_or_else(|| frame.clone())
}

/// Per output index, the input indices it covers and their shares (the
/// overlap of `[o s, (o + 1) s)` with each input pixel, over `s`).
fn area_taps(src: usize, dst: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = src as f64 / dst as f64;
    (0..dst)
        .map(|o| {
            let (start, end) = (o as f64 * scale, (o as f64 + 1.0) * scale);
            let mut taps = Vec::new();
            let mut i = start.floor() as usize;
            while (i as f64) < end && i < src {
                let overlap = end.min(i as f64 + 1.0) - start.max(i as f64);
                if overlap > 1e-12 {
                    taps.push((i, overlap));
                }
                i += 1;
            }
            let total: f64 = taps.iter().map(|t| t.1).sum();
            taps.iter().map(|&(i, f)| (i, f / total)).collect()
        })
        .collect()
}

/// OpenCV's `INTER_AREA` when enlarging: output `o` blends source `s =
/// floor(o src / dst)` and `s + 1` with weight `f = frac((o + 1) - (s + 1)
/// dst / src)` (0 when that is not positive) on the second, clamped at
/// the borders.
fn area_up_taps(src: usize, dst: usize) -> Vec<Vec<(usize, f64)>> {
    let (scale, inverse) = (src as f64 / dst as f64, dst as f64 / src as f64);
    (0..dst)
        .map(|o| {
            let i = (o as f64 * scale).floor() as usize;
            let f = (o + 1) as f64 - (i + 1) as f64 * inverse;
            let f = if f <= 0.0 { 0.0 } else { f - f.floor() };
            if i + 1 < src && f > 0.0 {
                vec![(i, 1.0 - f), (i + 1, f)]
            } else {
                vec![(i.min(src - 1), 1.0)]
            }
        })
        .collect()
}

/// Per output index, the two input indices and weights of bilinear
/// interpolation with aligned pixel centres, clamped at the borders.
fn linear_taps(src: usize, dst: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = src as f64 / dst as f64;
    (0..dst)
        .map(|o| {
            let at = ((o as f64 + 0.5) * scale - 0.5).clamp(0.0, (src - 1) as f64);
            let i = at.floor() as usize;
            let f = at - i as f64;
            if i + 1 < src && f > 0.0 {
                vec![(i, 1.0 - f), (i + 1, f)]
            } else {
                vec![(i, 1.0)]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Halving averages 2 x 2 blocks exactly; doubling bilinearly puts each
    /// input pixel's value between its neighbours.
    #[test]
    fn halving_averages_blocks_and_linear_interpolates() {
        let frame = Frame::from_raw(4, 2, vec![0, 100, 50, 50, 100, 0, 50, 50]).expect("frame");
        let half = resize(&frame, [2, 1], ResizeMethod::Area);
        assert_eq!(half.as_raw(), &vec![50, 50]);
        let line = Frame::from_raw(2, 1, vec![0, 200]).expect("frame");
        let wide = resize(&line, [4, 1], ResizeMethod::Bilinear);
        // Samples at -0.25 (clamped to 0), 0.25, 0.75, 1.25 (clamped to 1).
        assert_eq!(wide.as_raw(), &vec![0, 50, 150, 200]);
    }
}
