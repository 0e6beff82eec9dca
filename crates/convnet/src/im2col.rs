//! A convolution as one matrix product (im2col): the input windows laid out
//! as the columns of a `fan_in x (frames * positions)` matrix, so
//! `W(l) (cout x fan_in)` times it is the layer's output, `cout x frames x
//! hout x wout`. `col2im` is its transpose (scatter-add back onto the
//! input), used to send errors down through `W(l)^T`.
//!
//! Tensors of a chunk of `nb` frames are stored `channels x nb x h x w`, so
//! one layer's product is the next layer's input without reordering.
//!
//! Both go through one input plane at a time, zero-padded and split by
//! phase (`crate::phases`): there, what one kernel offset reads for a row
//! of outputs is `wout` contiguous values, with no bounds to test, so
//! every row is one straight vector copy (or add). Each is built for
//! AVX-512, AVX2 and the baseline (`crate::simd`); the sums of `col2im`
//! are taken in the same order as before, so the numbers are unchanged.
use crate::activation::times_slope_portable;
use crate::config::Activation;
use crate::layout::LayerShape;
use crate::phases::{add_rows, copy_rows, Phases};
use crate::simd::dispatched;

thread_local! {
    /// One padded input plane split by phase, reused.
    static PHASES: std::cell::RefCell<Vec<f32>> = const { std::cell::RefCell::new(Vec::new()) };
}

dispatched! {
    /// `cols = im2col(input)`: `input` is `cin x nb x hin x win`, `cols`
    /// (at least `fan_in * nb * positions` long) becomes `fan_in x (nb *
    /// positions)`, row `(c, ky, kx)`, column `(frame, oy, ox)`. Panics
    /// when a slice is shorter than the shape says.
    pub fn im2col(s: &LayerShape, nb: usize, input: &[f32], cols: &mut [f32]) => im2col_body;
}

dispatched! {
    /// `grad = col2im(cols) . phi'`, with the slope `phi'` of `activation`
    /// taken from `rate = phi(s)` (`rate` as long as `grad`): a layer's
    /// top-down input in one pass ([`col2im`], then the slope, pixel by
    /// pixel while its plane is in the cache).
    fn col2im_dispatched(
        s: &LayerShape,
        nb: usize,
        cols: &[f32],
        grad: &mut [f32],
        slope: Option<(Activation, &[f32])>,
    ) => col2im_body;
}

/// `grad = col2im(cols)`, the transpose of [`im2col`]: every column entry
/// added back onto the input pixel it was copied from. `grad` (`cin x nb
/// x hin x win`) is overwritten.
pub fn col2im(s: &LayerShape, nb: usize, cols: &[f32], grad: &mut [f32]) {
    col2im_dispatched(s, nb, cols, grad, None)
}

/// [`col2im`] times the slope `phi'(s)` of `activation`, read from `rate =
/// phi(s)` (as long as `grad`): `grad = col2im(cols) . phi'`, the same
/// numbers as [`col2im`] followed by the slope, in one pass.
pub fn col2im_times_slope(
    s: &LayerShape,
    nb: usize,
    cols: &[f32],
    grad: &mut [f32],
    activation: Activation,
    rate: &[f32],
) {
    col2im_dispatched(s, nb, cols, grad, Some((activation, rate)))
}

#[inline(always)]
fn im2col_body(s: &LayerShape, nb: usize, input: &[f32], cols: &mut [f32]) {
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
    let phases = Phases::new(s);
    let mut buf = PHASES.take();
    // The padding stays zero: every plane writes only the input's places.
    buf.clear();
    buf.resize(phases.len(), 0.0);
    let positions = s.positions();
    for c in 0..s.cin {
        for b in 0..nb {
            phases.split(&input[(c * nb + b) * plane..][..plane], &mut buf);
            for ky in 0..s.kh {
                for kx in 0..s.kw {
                    let row = ((c * s.kh + ky) * s.kw + kx) * n + b * positions;
                    let src = &buf[phases.tap(ky, kx)..];
                    copy_rows(&mut cols[row..][..positions], src, s.wout, phases.cols);
                }
            }
        }
    }
    PHASES.set(buf);
}

#[inline(always)]
fn col2im_body(
    s: &LayerShape,
    nb: usize,
    cols: &[f32],
    grad: &mut [f32],
    slope: Option<(Activation, &[f32])>,
) {
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
        if let Some((activation, rate)) = slope {
            let len = s.in_len() * nb;
            times_slope_portable(activation, &rate[..len], &mut grad[..len]);
        }
        return;
    }
    let phases = Phases::new(s);
    let mut kept = PHASES.take();
    kept.resize(phases.len(), 0.0);
    let buf = &mut kept[..phases.len()];
    let positions = s.positions();
    for c in 0..s.cin {
        for b in 0..nb {
            // Each pixel's terms are added in kernel-offset order, from 0.
            buf.fill(0.0);
            for ky in 0..s.kh {
                for kx in 0..s.kw {
                    let row = ((c * s.kh + ky) * s.kw + kx) * n + b * positions;
                    let dst = &mut buf[phases.tap(ky, kx)..];
                    add_rows(dst, &cols[row..][..positions], s.wout, phases.cols);
                }
            }
            let at = (c * nb + b) * plane;
            let dst = &mut grad[at..][..plane];
            phases.merge(buf, dst);
            if let Some((activation, rate)) = slope {
                times_slope_portable(activation, &rate[at..][..plane], dst);
            }
        }
    }
    PHASES.set(kept);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `cols` from the definition: row `(c, ky, kx)`, column `(b, oy, ox)`
    /// holds input pixel `(c, b, oy stride + ky - pad, ox stride + kx -
    /// pad)`, or 0 outside the input.
    fn by_definition(s: &LayerShape, nb: usize, x: &[f32]) -> Vec<f32> {
        let n = nb * s.positions();
        let mut cols = vec![0.0; s.fan_in() * n];
        for c in 0..s.cin {
            for (ky, kx) in (0..s.kh).flat_map(|ky| (0..s.kw).map(move |kx| (ky, kx))) {
                for b in 0..nb {
                    for (oy, ox) in (0..s.hout).flat_map(|oy| (0..s.wout).map(move |ox| (oy, ox))) {
                        let iy = (oy * s.stride + ky) as isize - s.pad as isize;
                        let ix = (ox * s.stride + kx) as isize - s.pad as isize;
                        if iy < 0 || ix < 0 || iy >= s.hin as isize || ix >= s.win as isize {
                            continue;
                        }
                        let src = ((c * nb + b) * s.hin + iy as usize) * s.win + ix as usize;
                        let row = (c * s.kh + ky) * s.kw + kx;
                        cols[row * n + (b * s.hout + oy) * s.wout + ox] = x[src];
                    }
                }
            }
        }
        cols
    }

    fn shapes() -> Vec<LayerShape> {
        let conv = |cin, hin, win, cout, k, stride| {
            let pad = k / 2;
            LayerShape {
                cin,
                hin,
                win,
                cout,
                hout: (hin + 2 * pad - k) / stride + 1,
                wout: (win + 2 * pad - k) / stride + 1,
                kh: k,
                kw: k,
                stride,
                pad,
                side_inputs: 0,
            }
        };
        // The default layers (rows of 32, 16 and 8), and odd sizes,
        // strides 1-3, an even kernel.
        vec![
            conv(1, 64, 64, 2, 5, 2),
            conv(2, 32, 32, 2, 3, 2),
            conv(3, 16, 16, 2, 3, 2),
            conv(2, 13, 10, 2, 5, 2),
            conv(2, 7, 9, 2, 3, 1),
            conv(1, 11, 8, 2, 4, 3),
            conv(2, 5, 6, 2, 1, 1),
        ]
    }

    fn values(len: usize, k: f32) -> Vec<f32> {
        (0..len).map(|i| (i as f32 * k).sin()).collect()
    }

    #[test]
    fn im2col_equals_its_definition_and_col2im_is_its_transpose() {
        let nb = 3;
        for s in shapes() {
            let x = values(s.in_len() * nb, 0.7);
            let mut cols = vec![f32::NAN; s.fan_in() * nb * s.positions()];
            im2col(&s, nb, &x, &mut cols);
            assert_eq!(cols, by_definition(&s, nb, &x), "{s:?}");
            // <col2im(y), x> = <y, im2col(x)>.
            let y = values(cols.len(), 0.3);
            let mut g = vec![f32::NAN; x.len()];
            col2im(&s, nb, &y, &mut g);
            let lhs: f64 = g.iter().zip(&x).map(|(a, b)| (a * b) as f64).sum();
            let rhs: f64 = y.iter().zip(&cols).map(|(a, b)| (a * b) as f64).sum();
            assert!(
                (lhs - rhs).abs() < 1e-4 * rhs.abs().max(1.0),
                "{s:?}: {lhs} {rhs}"
            );
        }
    }

    #[test]
    fn col2im_times_slope_equals_col2im_then_the_slope_bit_for_bit() {
        let nb = 2;
        for s in shapes() {
            let y = values(s.fan_in() * nb * s.positions(), 0.3);
            let rate = values(s.in_len() * nb, 0.9);
            for act in [Activation::Sigmoid, Activation::Tanh, Activation::Relu] {
                let (mut want, mut got) = (vec![0.0; rate.len()], vec![0.0; rate.len()]);
                col2im(&s, nb, &y, &mut want);
                act.times_slope(&rate, &mut want);
                col2im_times_slope(&s, nb, &y, &mut got, act, &rate);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&want), bits(&got), "{s:?} {act:?}");
            }
        }
    }
}
