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
    let n = nb * s.positions();
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
    grad[..s.cin * nb * plane].fill(0.0);
    for c in 0..s.cin {
        for ky in 0..s.kh {
            for kx in 0..s.kw {
                let row = &cols[((c * s.kh + ky) * s.kw + kx) * n..][..n];
                let (lo, hi) = valid_columns(s, kx);
                if lo == hi {
                    continue;
                }
                for b in 0..nb {
                    let dst_plane = &mut grad[(c * nb + b) * plane..][..plane];
                    for oy in 0..s.hout {
                        let iy = oy * s.stride + ky;
                        if iy < s.pad || iy - s.pad >= s.hin {
                            continue;
                        }
                        let src = &row[(b * s.hout + oy) * s.wout..][..s.wout];
                        let dst = &mut dst_plane[(iy - s.pad) * s.win..][..s.win];
                        let first = lo * s.stride + kx - s.pad;
                        if s.stride == 1 {
                            for (d, v) in dst[first..first + hi - lo].iter_mut().zip(&src[lo..hi]) {
                                *d += *v;
                            }
                        } else {
                            scatter_add(&mut dst[first..], &src[lo..hi], s.stride);
                        }
                    }
                }
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

/// `dst[i * stride] += src[i]`.
#[inline(always)]
fn scatter_add(dst: &mut [f32], src: &[f32], stride: usize) {
    if stride == 2 {
        // Whole pairs (the odd lane gets + 0.0, which leaves it as it
        // is), so the compiler can load, add and store vectors.
        let full = src.len().min(dst.len() / 2);
        for (pair, v) in dst.chunks_exact_mut(2).zip(&src[..full]) {
            pair[0] += *v;
            pair[1] += 0.0;
        }
        if full < src.len() {
            dst[2 * full] += src[full];
        }
        return;
    }
    for (c, v) in dst.chunks_mut(stride).zip(src) {
        c[0] += *v;
    }
}
