//! A convolution as one matrix product (im2col): the input windows laid out
//! as the columns of a `fan_in x (frames * positions)` matrix, so
//! `W(l) (cout x fan_in)` times it is the layer's output, `cout x frames x
//! hout x wout`. `col2im` is its transpose (scatter-add back onto the
//! input), used to send errors down through `W(l)^T`.
//!
//! Tensors of a chunk of `nb` frames are stored `channels x nb x h x w`, so
//! one layer's product is the next layer's input without reordering.
use crate::layout::LayerShape;

/// Output columns `ox` whose input column `ox * stride + kx - pad` lies
/// inside `0..win`.
#[inline]
fn valid_columns(s: &LayerShape, kx: usize) -> (usize, usize) {
    let lo = s.pad.saturating_sub(kx).div_ceil(s.stride);
    if s.win + s.pad <= kx {
        return (lo.min(s.wout), lo.min(s.wout));
    }
    let hi = ((s.win - 1 + s.pad - kx) / s.stride + 1).min(s.wout);
    (lo.min(hi), hi)
}

/// `cols = im2col(input)`: `input` is `cin x nb x hin x win`, `cols`
/// (at least `fan_in * nb * positions` long) becomes `fan_in x (nb *
/// positions)`, row `(c, ky, kx)`, column `(frame, oy, ox)`. Panics when
/// a slice is shorter than the shape says.
pub fn im2col(s: &LayerShape, nb: usize, input: &[f32], cols: &mut [f32]) {
    let n = nb * s.positions();
    let plane = s.hin * s.win;
    if s.is_dense() {
        for c in 0..s.cin {
            for b in 0..nb {
                let src = &input[(c * nb + b) * plane..][..plane];
                for (j, &v) in src.iter().enumerate() {
                    cols[(c * plane + j) * nb + b] = v;
                }
            }
        }
        return;
    }
    for c in 0..s.cin {
        for ky in 0..s.kh {
            for kx in 0..s.kw {
                let row = &mut cols[((c * s.kh + ky) * s.kw + kx) * n..][..n];
                let (lo, hi) = valid_columns(s, kx);
                for b in 0..nb {
                    let src_plane = &input[(c * nb + b) * plane..][..plane];
                    for oy in 0..s.hout {
                        let dst = &mut row[(b * s.hout + oy) * s.wout..][..s.wout];
                        let iy = oy * s.stride + ky;
                        if iy < s.pad || iy - s.pad >= s.hin {
                            dst.fill(0.0);
                            continue;
                        }
                        let src = &src_plane[(iy - s.pad) * s.win..][..s.win];
                        // The padding, if any (a call to fill costs more
                        // than the short copy).
                        if lo > 0 {
                            dst[..lo].fill(0.0);
                        }
                        if hi < s.wout {
                            dst[hi..].fill(0.0);
                        }
                        if lo == hi {
                            continue;
                        }
                        let first = lo * s.stride + kx - s.pad;
                        if s.stride == 1 {
                            dst[lo..hi].copy_from_slice(&src[first..first + hi - lo]);
                        } else {
                            gather(&mut dst[lo..hi], &src[first..], s.stride);
                        }
                    }
                }
            }
        }
    }
}

/// `grad = col2im(cols)`, the transpose of [`im2col`]: every column entry
/// added back onto the input pixel it was copied from. `grad` (`cin x nb
/// x hin x win`) is overwritten.
pub fn col2im(s: &LayerShape, nb: usize, cols: &[f32], grad: &mut [f32]) {
    let plane = s.hin * s.win;
    if s.is_dense() {
        for c in 0..s.cin {
            for b in 0..nb {
                let dst = &mut grad[(c * nb + b) * plane..][..plane];
                for (j, d) in dst.iter_mut().enumerate() {
                    *d = cols[(c * plane + j) * nb + b];
                }
            }
        }
        return;
    }
    if s.stride == 1 {
        col2im_planes(s, nb, cols, grad, None);
        return;
    }
    PHASES.with_borrow_mut(|phases| {
        let len = s.stride * s.hin * s.win.div_ceil(s.stride);
        if phases.len() < len {
            phases.resize(len, 0.0);
        }
        col2im_planes(s, nb, cols, grad, Some(&mut phases[..len]));
    });
}

thread_local! {
    /// One input plane split by column phase (`x % stride`), reused.
    static PHASES: std::cell::RefCell<Vec<f32>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The body of [`col2im`], one input plane at a time (it stays in the
/// first-level cache while every kernel offset adds onto it). Without
/// `phases` (stride 1) the sums go straight into the plane; with them,
/// into the plane split by column phase `x % stride`, where the columns
/// one kernel offset reaches are contiguous (a strided scatter-add would
/// store into what the next offset loads, which the processor cannot
/// forward), and the phases are interleaved into the plane at the end.
fn col2im_planes(
    s: &LayerShape,
    nb: usize,
    cols: &[f32],
    grad: &mut [f32],
    mut phases: Option<&mut [f32]>,
) {
    let n = nb * s.positions();
    let plane = s.hin * s.win;
    let wp = s.win.div_ceil(s.stride);
    for c in 0..s.cin {
        for b in 0..nb {
            let dst_plane = &mut grad[(c * nb + b) * plane..][..plane];
            let target: &mut [f32] = match phases.as_deref_mut() {
                Some(p) => p,
                None => dst_plane,
            };
            target.fill(0.0);
            for ky in 0..s.kh {
                for kx in 0..s.kw {
                    let row = &cols[((c * s.kh + ky) * s.kw + kx) * n..][..n];
                    let (lo, hi) = valid_columns(s, kx);
                    if lo == hi {
                        continue;
                    }
                    let first = lo * s.stride + kx - s.pad;
                    // Where the first valid column lands in `target`.
                    let (phase, column) = (first % s.stride, first / s.stride);
                    for oy in 0..s.hout {
                        let iy = oy * s.stride + ky;
                        if iy < s.pad || iy - s.pad >= s.hin {
                            continue;
                        }
                        let src = &row[(b * s.hout + oy) * s.wout..][lo..hi];
                        let at = if s.stride == 1 {
                            (iy - s.pad) * s.win + first
                        } else {
                            (phase * s.hin + iy - s.pad) * wp + column
                        };
                        let dst = &mut target[at..at + src.len()];
                        dst.iter_mut().zip(src).for_each(|(d, v)| *d += *v);
                    }
                }
            }
            if let Some(p) = phases.as_deref() {
                interleave(s, p, &mut grad[(c * nb + b) * plane..][..plane]);
            }
        }
    }
}

/// `plane[y][x] = phases[x % stride][y][x / stride]`.
fn interleave(s: &LayerShape, phases: &[f32], plane: &mut [f32]) {
    let wp = s.win.div_ceil(s.stride);
    for (y, row) in plane.chunks_exact_mut(s.win).enumerate() {
        for r in 0..s.stride {
            let src = &phases[(r * s.hin + y) * wp..][..wp];
            for (d, v) in row[r..].iter_mut().step_by(s.stride).zip(src) {
                *d = *v;
            }
        }
    }
}

/// `dst[i] = src[i * stride]`.
#[inline(always)]
fn gather(dst: &mut [f32], src: &[f32], stride: usize) {
    if stride == 2 {
        // Whole pairs, so the compiler loads vectors and keeps the even
        // lanes; the last pixel may have no partner.
        let full = dst.len().min(src.len() / 2);
        for (d, pair) in dst[..full].iter_mut().zip(src.chunks_exact(2)) {
            *d = pair[0];
        }
        if full < dst.len() {
            dst[full] = src[2 * full];
        }
        return;
    }
    for (d, c) in dst.iter_mut().zip(src.chunks(stride)) {
        *d = c[0];
    }
}
