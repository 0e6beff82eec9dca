//! A layer's step after its matrix product, in one pass over its values
//! (the bias add, the potentials and the rates used to be three passes
//! and a fill): row by row (one row a channel, `nb x positions` long),
//! `p += b(l)`, `s = p + e` and, below the output, `a = phi(s)` (the
//! dendritic prediction and the soma of `crate::pass`). In the free phase
//! the errors are zero and are written as zero, so `s = p + 0`, the same
//! numbers as the separate passes gave, bit for bit.
use crate::activation::{sigmoid_fast, tanh_fast};
use crate::config::Activation;
use crate::simd::dispatched;

/// The layer's errors `e` while it settles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Errors {
    /// Zero (a free equilibrium, the feed-forward pass): written as zero.
    Zero,
    /// As they are (a clamped phase's sweep).
    Held,
}

/// One layer's values to settle, and how (see [`settle`]).
#[derive(Debug)]
pub struct Settle<'a> {
    /// The rate function `phi`.
    pub activation: Activation,
    /// One bias a row (rows of `p.len() / bias.len()` values), added to
    /// `p` first; `None` adds nothing.
    pub bias: Option<&'a [f32]>,
    /// What the errors are.
    pub errors: Errors,
    /// The layer's product, then its prediction `p`.
    pub p: &'a mut [f32],
    /// The errors `e` (at least as long as `p`).
    pub e: &'a mut [f32],
    /// The potentials `s = p + e` (at least as long as `p`).
    pub s: &'a mut [f32],
    /// The rates `phi(s)` (at least as long as `p`); `None` at the output.
    pub a: Option<&'a mut [f32]>,
}

dispatched! {
    /// `p += b`, `e = 0` (with [`Errors::Zero`]), `s = p + e` and, with
    /// rates, `a = phi(s)`, in one pass; in the widest build the processor
    /// runs. Panics when `e`, `s` or `a` is shorter than `p`.
    pub fn settle(step: Settle<'_>) => settle_portable;
}

/// The body of [`settle`]: the activation and the two choices are taken
/// out of the loop, so each of its builds is one straight vector loop.
#[inline(always)]
pub(crate) fn settle_portable(step: Settle<'_>) {
    let Settle {
        activation,
        bias,
        errors,
        p,
        e,
        s,
        a,
    } = step;
    let len = p.len();
    let (e, s) = (&mut e[..len], &mut s[..len]);
    let Some(a) = a else {
        // The output layer: no rates, few values.
        let n = bias.map_or(len, |b| len / b.len().max(1)).max(1);
        let chunks = p.chunks_mut(n).zip(e.chunks_mut(n)).zip(s.chunks_mut(n));
        for (r, ((p, e), s)) in chunks.enumerate() {
            for ((p, e), s) in p.iter_mut().zip(e.iter_mut()).zip(s.iter_mut()) {
                if let Some(b) = bias {
                    *p += b[r];
                }
                if errors == Errors::Zero {
                    *e = 0.0;
                }
                *s = *p + *e;
            }
        }
        return;
    };
    let a = &mut a[..len];
    match activation {
        Activation::Tanh => rows(tanh_fast, bias, errors, p, e, s, a),
        Activation::Sigmoid => rows(sigmoid_fast, bias, errors, p, e, s, a),
        Activation::Relu => rows(|v: f32| v.max(0.0), bias, errors, p, e, s, a),
    }
}

/// [`settle_portable`] for one rate function, split by row.
#[inline(always)]
fn rows(
    phi: impl Fn(f32) -> f32 + Copy,
    bias: Option<&[f32]>,
    errors: Errors,
    p: &mut [f32],
    e: &mut [f32],
    s: &mut [f32],
    a: &mut [f32],
) {
    let Some(bias) = bias.filter(|b| !b.is_empty()) else {
        match errors {
            Errors::Zero => row::<false, true>(phi, 0.0, p, e, s, a),
            Errors::Held => row::<false, false>(phi, 0.0, p, e, s, a),
        }
        return;
    };
    let n = p.len() / bias.len();
    let chunks = p
        .chunks_exact_mut(n)
        .zip(e.chunks_exact_mut(n))
        .zip(s.chunks_exact_mut(n).zip(a.chunks_exact_mut(n)));
    for (&b, ((p, e), (s, a))) in bias.iter().zip(chunks) {
        match errors {
            Errors::Zero => row::<true, true>(phi, b, p, e, s, a),
            Errors::Held => row::<true, false>(phi, b, p, e, s, a),
        }
    }
}

/// One row: `p += b` (`BIAS`), `e = 0` (`ZERO`), `s = p + e`, `a = phi(s)`.
#[inline(always)]
fn row<const BIAS: bool, const ZERO: bool>(
    phi: impl Fn(f32) -> f32,
    b: f32,
    p: &mut [f32],
    e: &mut [f32],
    s: &mut [f32],
    a: &mut [f32],
) {
    for (((p, e), s), a) in p.iter_mut().zip(e.iter_mut()).zip(s.iter_mut()).zip(a) {
        if BIAS {
            *p += b;
        }
        if ZERO {
            *e = 0.0;
        }
        let v = *p + *e;
        *s = v;
        *a = phi(v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The separate passes `settle` replaces: the bias add, the fill, the
    /// potentials, the rates.
    fn separate(
        act: Activation,
        bias: Option<&[f32]>,
        errors: Errors,
        p: &mut [f32],
        e: &mut [f32],
    ) -> (Vec<f32>, Vec<f32>) {
        if let Some(b) = bias {
            let n = p.len() / b.len();
            for (row, &b) in p.chunks_exact_mut(n).zip(b) {
                row.iter_mut().for_each(|v| *v += b);
            }
        }
        if errors == Errors::Zero {
            e.fill(0.0);
        }
        let s: Vec<f32> = p.iter().zip(e.iter()).map(|(p, e)| p + e).collect();
        let mut a = vec![0.0; s.len()];
        act.apply(&s, &mut a);
        (s, a)
    }

    #[test]
    fn settle_equals_the_separate_passes_bit_for_bit() {
        let (rows, n) = (5, 37);
        let values =
            |k: f32| -> Vec<f32> { (0..rows * n).map(|i| (i as f32 * k).sin() * 3.0).collect() };
        let bias: Vec<f32> = (0..rows).map(|r| r as f32 * 0.3 - 0.7).collect();
        for act in [Activation::Sigmoid, Activation::Tanh, Activation::Relu] {
            for b in [Some(&bias[..]), None] {
                for errors in [Errors::Zero, Errors::Held] {
                    let (mut p1, mut e1) = (values(0.37), values(0.11));
                    let (mut p2, mut e2) = (p1.clone(), e1.clone());
                    let (want_s, want_a) = separate(act, b, errors, &mut p1, &mut e1);
                    let (mut s, mut a) = (vec![9.0; rows * n], vec![9.0; rows * n]);
                    settle(Settle {
                        activation: act,
                        bias: b,
                        errors,
                        p: &mut p2,
                        e: &mut e2,
                        s: &mut s,
                        a: Some(&mut a),
                    });
                    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(&p1), bits(&p2), "{act:?} {errors:?}");
                    assert_eq!(bits(&e1), bits(&e2));
                    assert_eq!(bits(&want_s), bits(&s));
                    assert_eq!(bits(&want_a), bits(&a));
                    let (mut p3, mut e3) = (values(0.37), values(0.11));
                    let mut s3 = vec![9.0; rows * n];
                    settle_portable(Settle {
                        activation: act,
                        bias: b,
                        errors,
                        p: &mut p3,
                        e: &mut e3,
                        s: &mut s3,
                        a: None,
                    });
                    assert_eq!(bits(&want_s), bits(&s3), "no rates");
                }
            }
        }
    }
}
