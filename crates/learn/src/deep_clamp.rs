//! The linearised weakly clamped phase ([`crate::ClampedPhase::Linearised`])
//! of a layered net of any depth: the closed form of the one-hidden-layer
//! case (docs/learning.md, "Equations") carried through every hidden layer,
//! so two or more hidden layers learn without the Euler relaxation.
//!
//! Linearising the sigmoids about the free state (`D(l) = diag(phi'(s(l)))`),
//! the equilibrium of eq. 3.12 with the output held at `y_n` satisfies, for
//! every hidden layer `l < N`, `e(l) = D(l) W(l+1) e(l+1)`, so
//! `e(l) = G(l)^T e(N)` with `G(l) = dy/ds(l) = W(N)^T D(N-1) ... W(l+1)^T
//! D(l)` (`k x d(l)`, `k` outputs). The potentials move by `ds(1) = e(1)`,
//! `ds(l) = e(l) + W(l)^T D(l-1) ds(l-1)`, so the output's own error is
//! `e(N) = beta (t - y) - sum_l G(l) e(l)`, that is
//! `(I + sum_l G(l) G(l)^T) e(N) = beta (t - y)`: a `k x k` system. For one
//! hidden layer `G(1) G(1)^T = W2^T D^2 W2 = A`, the one-layer closed form.
//! The update then uses `e(l)` and the clamped activity `phi(s(l)) + D(l)
//! ds(l)`; its first-order part is `(I + sum_l G G^T)^-1 beta` times the
//! backprop gradient (tested in `tests/it/two_hidden_layers.rs`).
use crate::kernels::{dot, madd};
use crate::net::{Layers, States};

/// The linearised clamped equilibrium of `layers` for target `t`, from the
/// free state in `st` (`st.nudged` already set): leaves every `e(l)`, the
/// clamped potentials `s(l)` and presynaptic activities `phi(s(l))` in `st`.
#[inline(always)]
pub(crate) fn clamp_linearised_deep<const F: bool>(
    layers: &Layers,
    st: &mut States,
    t: &[f32],
    beta: f32,
) {
    let n = layers.depth();
    let k = layers.sizes[n];
    ensure_scratch(st, &layers.sizes);
    let States {
        s,
        phi,
        e,
        tmp,
        nudged,
        system,
        deep,
        ..
    } = st;
    let (slopes, gains) = deep.split_at_mut(n);
    // D(l) = phi (1 - phi) at the free state.
    for l in 1..n {
        let d = &mut slopes[l];
        d.iter_mut()
            .zip(&phi[l])
            .for_each(|(d, p)| *d = p * (1.0 - p));
    }
    output_jacobians::<F>(layers, slopes, gains, tmp, k);
    // (I + sum_l G(l) G(l)^T) e(N) = beta (t - y).
    let (a, b) = system.split_at_mut(k * k);
    for p in 0..k {
        for q in p..k {
            let mut v = if p == q { 1.0 } else { 0.0 };
            for g in gains.iter().take(n).skip(1) {
                let d = g.len() / k;
                v += dot::<F>(&g[p * d..(p + 1) * d], &g[q * d..(q + 1) * d]) as f64;
            }
            a[p * k + q] = v;
            a[q * k + p] = v;
        }
    }
    b.iter_mut()
        .zip(&s[n])
        .zip(t)
        .for_each(|((b, &y), &t)| *b = (beta * (t - y)) as f64);
    solve_in_place(a, b, k);
    e[n].iter_mut()
        .zip(b.iter())
        .for_each(|(e, b)| *e = *b as f32);
    // e(l) = G(l)^T e(N).
    let (hidden, top) = e.split_at_mut(n);
    for l in 1..n {
        let d = layers.sizes[l];
        hidden[l].iter_mut().for_each(|v| *v = 0.0);
        for (j, &ej) in top[0].iter().enumerate() {
            let col = &gains[l][j * d..(j + 1) * d];
            hidden[l]
                .iter_mut()
                .zip(col)
                .for_each(|(v, &g)| *v = madd::<F>(ej, g, *v));
        }
    }
    clamped_potentials::<F>(layers, slopes, s, phi, e, tmp);
    s[n].copy_from_slice(nudged);
}

/// Size the per-layer slopes and output Jacobians once per net.
fn ensure_scratch(st: &mut States, sizes: &[usize]) {
    let n = sizes.len() - 1;
    let k = sizes[n];
    if st.deep.len() == 2 * n {
        return;
    }
    let slopes = sizes[..n].iter().map(|&d| vec![0.0; d]);
    let gains = sizes[..n].iter().map(|&d| vec![0.0; d * k]);
    st.deep = slopes.chain(gains).collect();
}

/// `gains[l]` = `G(l)^T` for every hidden layer, stored a column (an
/// output) at a time: column `j` is `D(l) W(l+1) ... D(N-1) W(N) u_j`.
#[inline(always)]
fn output_jacobians<const F: bool>(
    layers: &Layers,
    slopes: &[Vec<f32>],
    gains: &mut [Vec<f32>],
    tmp: &mut [Vec<f32>],
    k: usize,
) {
    let n = layers.depth();
    for j in 0..k {
        let unit = &mut tmp[n];
        unit.iter_mut().for_each(|v| *v = 0.0);
        unit[j] = 1.0;
        for l in (1..n).rev() {
            let d = layers.sizes[l];
            let (below, above) = gains.split_at_mut(l + 1);
            let col = &mut below[l][j * d..(j + 1) * d];
            if l == n - 1 {
                layers.back::<F>(n, &tmp[n], col);
            } else {
                let upper = &above[0];
                let du = layers.sizes[l + 1];
                layers.back::<F>(l + 1, &upper[j * du..(j + 1) * du], col);
            }
            col.iter_mut().zip(&slopes[l]).for_each(|(g, d)| *g *= d);
        }
    }
}

/// `ds(1) = e(1)`, `ds(l) = e(l) + W(l)^T D(l-1) ds(l-1)`; the potentials
/// move by `ds` and the activities by `D ds` (linearised).
#[inline(always)]
fn clamped_potentials<const F: bool>(
    layers: &Layers,
    slopes: &[Vec<f32>],
    s: &mut [Vec<f32>],
    phi: &mut [Vec<f32>],
    e: &[Vec<f32>],
    tmp: &mut [Vec<f32>],
) {
    let n = layers.depth();
    for l in 1..n {
        if l == 1 {
            tmp[1].copy_from_slice(&e[1]);
        } else {
            // W(l)^T (D(l-1) ds(l-1)): affine then the bias taken off.
            let (lower, upper) = tmp.split_at_mut(l);
            layers.affine::<F>(l, &lower[l - 1], &mut upper[0]);
            let ds = upper[0].iter_mut().zip(layers.bias(l)).zip(&e[l]);
            ds.for_each(|((v, b), e)| *v = *v - b + e);
        }
        // tmp[l] = ds(l) -> s += ds; then tmp[l] = D ds, phi += D ds.
        s[l].iter_mut().zip(&tmp[l]).for_each(|(s, v)| *s += v);
        let dds = tmp[l].iter_mut().zip(&slopes[l]);
        dds.for_each(|(v, d)| *v *= d);
        phi[l].iter_mut().zip(&tmp[l]).for_each(|(p, v)| *p += v);
    }
}

/// Solve the symmetric positive definite `k x k` system `a x = b` in place
/// (`b` becomes `x`) by Gaussian elimination; `a` is overwritten.
pub(crate) fn solve_in_place(a: &mut [f64], b: &mut [f64], k: usize) {
    for p in 0..k {
        for r in p + 1..k {
            let f = a[r * k + p] / a[p * k + p];
            for q in p..k {
                a[r * k + q] -= f * a[p * k + q];
            }
            b[r] -= f * b[p];
        }
    }
    for p in (0..k).rev() {
        let tail: f64 = (p + 1..k).map(|q| a[p * k + q] * b[q]).sum();
        b[p] = (b[p] - tail) / a[p * k + p];
    }
}
