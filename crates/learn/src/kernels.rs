//! The few dense f32 kernels the training hot loop needs (axpy-style matrix
//! products on row-major weights, rank-one updates, a vectorisable sigmoid),
//! written so LLVM vectorises them; `FMA` picks fused multiply-adds, which are
//! only used when the caller runs under the `fma` target feature.

/// `a * b + c`, fused when `FMA` (only instantiate `FMA = true` inside a
/// function compiled with the `fma` target feature, or it becomes a libm call).
#[inline(always)]
pub fn madd<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
    if FMA {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `y += a * x`.
#[inline(always)]
pub fn axpy<const FMA: bool>(y: &mut [f32], a: f32, x: &[f32]) {
    for (y, &x) in y.iter_mut().zip(x) {
        *y = madd::<FMA>(a, x, *y);
    }
}

/// Dot product with eight independent accumulators (vectorisable).
#[inline(always)]
pub fn dot<const FMA: bool>(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0.0f32; 8];
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f32 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..8 {
            acc[k] = madd::<FMA>(x[k], y[k], acc[k]);
        }
    }
    acc.iter().sum::<f32>() + tail
}

/// `sum_i a_i b_i c_i` with eight independent accumulators.
#[inline(always)]
pub fn dot3<const FMA: bool>(a: &[f32], b: &[f32], c: &[f32]) -> f32 {
    let mut acc = [0.0f32; 8];
    let (ca, cb, cc) = (a.chunks_exact(8), b.chunks_exact(8), c.chunks_exact(8));
    let tail: f32 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .zip(cc.remainder())
        .map(|((x, y), z)| x * y * z)
        .sum();
    for ((x, y), z) in ca.zip(cb).zip(cc) {
        for k in 0..8 {
            acc[k] = madd::<FMA>(x[k] * y[k], z[k], acc[k]);
        }
    }
    acc.iter().sum::<f32>() + tail
}

/// `out = b + W^T v` for row-major `W` (`v.len()` rows of `out.len()`
/// columns): a sweep of row axpys, four rows at a time so `out` is loaded and
/// stored once per four rows.
#[inline(always)]
pub fn affine_rows<const FMA: bool>(w: &[f32], v: &[f32], b: &[f32], out: &mut [f32]) {
    let cols = out.len();
    out.copy_from_slice(b);
    let mut blocks = w.chunks_exact(4 * cols);
    let mut vs = v.chunks_exact(4);
    for (block, vb) in (&mut blocks).zip(&mut vs) {
        let (r0, rest) = block.split_at(cols);
        let (r1, rest) = rest.split_at(cols);
        let (r2, r3) = rest.split_at(cols);
        for ((((o, &a0), &a1), &a2), &a3) in out.iter_mut().zip(r0).zip(r1).zip(r2).zip(r3) {
            let s = madd::<FMA>(vb[0], a0, *o);
            let s = madd::<FMA>(vb[1], a1, s);
            let s = madd::<FMA>(vb[2], a2, s);
            *o = madd::<FMA>(vb[3], a3, s);
        }
    }
    for (row, &vi) in blocks.remainder().chunks_exact(cols).zip(vs.remainder()) {
        axpy::<FMA>(out, vi, row);
    }
}

/// `out = b + W^T v` with `W` stored transposed (`out.len()` rows of
/// `v.len()`): one contiguous dot per output unit.
#[inline(always)]
pub fn affine_cols<const FMA: bool>(wt: &[f32], v: &[f32], b: &[f32], out: &mut [f32]) {
    for ((o, row), &bj) in out.iter_mut().zip(wt.chunks_exact(v.len())).zip(b) {
        *o = bj + dot::<FMA>(row, v);
    }
}

/// `g = W e` for row-major `W` (`g.len()` rows of `e.len()` columns).
#[inline(always)]
pub fn back_rows<const FMA: bool>(w: &[f32], e: &[f32], g: &mut [f32]) {
    for (gi, row) in g.iter_mut().zip(w.chunks_exact(e.len())) {
        *gi = dot::<FMA>(row, e);
    }
}

/// `g = W e` with `W` stored transposed (`e.len()` rows of `g.len()`).
#[inline(always)]
pub fn back_cols<const FMA: bool>(wt: &[f32], e: &[f32], g: &mut [f32]) {
    g.iter_mut().for_each(|g| *g = 0.0);
    for (row, &ej) in wt.chunks_exact(g.len()).zip(e) {
        axpy::<FMA>(g, ej, row);
    }
}

/// `W += u v^T` for row-major `W` (`u.len()` rows of `v.len()` columns).
#[inline(always)]
pub fn rank1_rows<const FMA: bool>(w: &mut [f32], u: &[f32], v: &[f32]) {
    for (row, &ui) in w.chunks_exact_mut(v.len()).zip(u) {
        axpy::<FMA>(row, ui, v);
    }
}

/// `W += u v^T` with `W` stored transposed (`v.len()` rows of `u.len()`).
#[inline(always)]
pub fn rank1_cols<const FMA: bool>(wt: &mut [f32], u: &[f32], v: &[f32]) {
    for (row, &vj) in wt.chunks_exact_mut(u.len()).zip(v) {
        axpy::<FMA>(row, vj, u);
    }
}

/// Fused `W += u v^T` then `out = b + W^T next` in one sweep over row-major
/// `W` (each row is read and written once): the first-layer update of one
/// sample and the first-layer drive of the next. `b` must already be updated.
#[inline(always)]
pub fn rank1_then_affine_rows<const FMA: bool>(
    w: &mut [f32],
    u: &[f32],
    v: &[f32],
    next: &[f32],
    b: &[f32],
    out: &mut [f32],
) {
    let cols = v.len();
    out.copy_from_slice(b);
    let mut blocks = w.chunks_exact_mut(2 * cols);
    let (mut us, mut ns) = (u.chunks_exact(2), next.chunks_exact(2));
    for ((block, ub), nb) in (&mut blocks).zip(&mut us).zip(&mut ns) {
        let (r0, r1) = block.split_at_mut(cols);
        for (((o, a0), a1), &vj) in out.iter_mut().zip(r0.iter_mut()).zip(r1.iter_mut()).zip(v) {
            *a0 = madd::<FMA>(ub[0], vj, *a0);
            *a1 = madd::<FMA>(ub[1], vj, *a1);
            let s = madd::<FMA>(nb[0], *a0, *o);
            *o = madd::<FMA>(nb[1], *a1, s);
        }
    }
    for ((row, &ui), &ni) in blocks
        .into_remainder()
        .chunks_exact_mut(cols)
        .zip(us.remainder())
        .zip(ns.remainder())
    {
        axpy::<FMA>(row, ui, v);
        axpy::<FMA>(out, ni, row);
    }
}

/// The logistic sigmoid `1 / (1 + exp(-x))` of every element, through a
/// branch-free `exp` (Cody-Waite range reduction, degree-6 polynomial,
/// relative error about 2e-7) that vectorises.
#[inline(always)]
pub fn sigmoid_into(src: &[f32], dst: &mut [f32]) {
    for (d, &x) in dst.iter_mut().zip(src) {
        *d = 1.0 / (1.0 + exp_approx(-x));
    }
}

/// Branch-free `exp(x)` for f32, saturating outside [-87, 88].
#[inline(always)]
pub fn exp_approx(x: f32) -> f32 {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    // Adding and removing 1.5 * 2^23 rounds to nearest without a libm call.
    const ROUNDER: f32 = 12_582_912.0;
    let x = x.clamp(-87.0, 88.0);
    let n = (x * LOG2E + ROUNDER) - ROUNDER;
    let r = x - n * LN2_HI - n * LN2_LO;
    let p = 1.0 / 720.0;
    let p = p * r + 1.0 / 120.0;
    let p = p * r + 1.0 / 24.0;
    let p = p * r + 1.0 / 6.0;
    let p = p * r + 0.5;
    let p = p * r + 1.0;
    let p = p * r + 1.0;
    let scale = f32::from_bits(((n as i32 + 127) as u32) << 23);
    p * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_approx_matches_std_within_3e_7_relative() {
        let mut worst = 0.0f64;
        for k in -8000..=8000 {
            let x = k as f32 * 0.01;
            let rel = ((exp_approx(x) as f64) - (x as f64).exp()).abs() / (x as f64).exp();
            worst = worst.max(rel);
        }
        assert!(worst < 3e-7, "worst relative error {worst}");
    }

    #[test]
    fn affine_forms_agree_with_naive_product() {
        let (rows, cols) = (7, 19);
        let w: Vec<f32> = (0..rows * cols)
            .map(|k| ((k * 37 % 11) as f32 - 5.0) * 0.1)
            .collect();
        let v: Vec<f32> = (0..rows).map(|k| k as f32 * 0.3 - 1.0).collect();
        let b: Vec<f32> = (0..cols).map(|k| k as f32 * 0.01).collect();
        let naive: Vec<f32> = (0..cols)
            .map(|j| b[j] + (0..rows).map(|i| w[i * cols + j] * v[i]).sum::<f32>())
            .collect();
        let wt: Vec<f32> = (0..cols * rows)
            .map(|k| w[(k % rows) * cols + k / rows])
            .collect();
        let (mut wide, mut narrow) = (vec![0.0; cols], vec![0.0; cols]);
        affine_rows::<false>(&w, &v, &b, &mut wide);
        affine_cols::<false>(&wt, &v, &b, &mut narrow);
        for j in 0..cols {
            assert!((wide[j] - naive[j]).abs() < 1e-5 && (narrow[j] - naive[j]).abs() < 1e-5);
        }
        let e: Vec<f32> = (0..cols).map(|k| 0.2 - k as f32 * 0.05).collect();
        let (mut g1, mut g2) = (vec![0.0; rows], vec![0.0; rows]);
        back_rows::<false>(&w, &e, &mut g1);
        back_cols::<false>(&wt, &e, &mut g2);
        for i in 0..rows {
            let naive: f32 = (0..cols).map(|j| w[i * cols + j] * e[j]).sum();
            assert!((g1[i] - naive).abs() < 1e-5 && (g2[i] - naive).abs() < 1e-5);
        }
    }

    #[test]
    fn fused_update_equals_update_then_affine() {
        let (rows, cols) = (5, 9);
        let mut w1: Vec<f32> = (0..rows * cols)
            .map(|k| ((k * 13 % 7) as f32 - 3.0) * 0.1)
            .collect();
        let mut w2 = w1.clone();
        let u: Vec<f32> = (0..rows).map(|k| k as f32 * 0.5 - 1.0).collect();
        let next: Vec<f32> = (0..rows).map(|k| 1.0 - k as f32 * 0.25).collect();
        let v: Vec<f32> = (0..cols).map(|k| k as f32 * 0.01).collect();
        let b = vec![0.1; cols];
        let (mut o1, mut o2) = (vec![0.0; cols], vec![0.0; cols]);
        rank1_rows::<false>(&mut w1, &u, &v);
        affine_rows::<false>(&w1, &next, &b, &mut o1);
        rank1_then_affine_rows::<false>(&mut w2, &u, &v, &next, &b, &mut o2);
        assert!(w1.iter().zip(&w2).all(|(a, b)| (a - b).abs() < 1e-6));
        assert!(o1.iter().zip(&o2).all(|(a, b)| (a - b).abs() < 1e-5));
    }
}
