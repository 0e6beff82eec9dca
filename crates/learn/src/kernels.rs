//! The few dense f32 kernels the training hot loop needs (matrix products on
//! weights stored in column panels or transposed, rank-one updates, a
//! vectorisable sigmoid), written so LLVM vectorises them; `FMA` picks fused
//! multiply-adds, which are only used when the caller runs under the `fma`
//! target feature.

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

/// Independent accumulators of the reductions: four ymm registers, enough
/// to hide the add/FMA latency (one register would be one serial chain).
pub(crate) const LANES: usize = 32;

/// Dot product with [`LANES`] independent accumulators (vectorisable).
#[inline(always)]
pub fn dot<const FMA: bool>(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0.0f32; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let tail: f32 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..LANES {
            acc[k] = madd::<FMA>(x[k], y[k], acc[k]);
        }
    }
    reduce(acc) + tail
}

/// `sum_i a_i b_i c_i` with [`LANES`] independent accumulators.
#[inline(always)]
pub fn dot3<const FMA: bool>(a: &[f32], b: &[f32], c: &[f32]) -> f32 {
    let mut acc = [0.0f32; LANES];
    let (ca, cb, cc) = (
        a.chunks_exact(LANES),
        b.chunks_exact(LANES),
        c.chunks_exact(LANES),
    );
    let tail: f32 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .zip(cc.remainder())
        .map(|((x, y), z)| x * y * z)
        .sum();
    for ((x, y), z) in ca.zip(cb).zip(cc) {
        for k in 0..LANES {
            acc[k] = madd::<FMA>(x[k] * y[k], z[k], acc[k]);
        }
    }
    reduce(acc) + tail
}

/// Sum of the accumulators, pairwise (vector adds, then one short chain).
#[inline(always)]
pub(crate) fn reduce(mut acc: [f32; LANES]) -> f32 {
    let mut half = LANES / 2;
    while half >= 8 {
        for k in 0..half {
            acc[k] += acc[k + half];
        }
        half /= 2;
    }
    acc[..8].iter().sum()
}

/// `sum_i v_i^2` in f64, with 16 independent accumulators (vectorises; a
/// plain iterator sum is one serial chain of f64 additions).
#[inline(always)]
pub fn sum_squares_f64(v: &[f32]) -> f64 {
    let mut acc = [0.0f64; 16];
    let chunks = v.chunks_exact(16);
    let tail: f64 = chunks
        .remainder()
        .iter()
        .map(|&x| (x as f64) * (x as f64))
        .sum();
    for c in chunks {
        for k in 0..16 {
            let x = c[k] as f64;
            acc[k] += x * x;
        }
    }
    acc.iter().sum::<f64>() + tail
}

/// Width of the column panels in which wide weight matrices are stored: 32
/// f32 accumulators (four ymm registers) stay in registers while a sweep
/// walks down a panel.
pub const PANEL: usize = 32;

/// The panels of a `rows x cols` matrix: `(first column, width)`; panel
/// `(j0, width)` occupies `rows * j0 .. rows * (j0 + width)` of the storage,
/// row-major within the panel (`rows x width`). Every panel is [`PANEL`]
/// wide but the last.
#[inline(always)]
pub fn panels(cols: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..cols)
        .step_by(PANEL)
        .map(move |j0| (j0, PANEL.min(cols - j0)))
}

/// Row-major `rows x cols` to panel storage (see [`panels`]).
pub fn to_panels(w: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    let mut out = Vec::with_capacity(rows * cols);
    for (j0, width) in panels(cols) {
        for row in w.chunks_exact(cols) {
            out.extend_from_slice(&row[j0..j0 + width]);
        }
    }
    out
}

/// Panel storage (see [`panels`]) back to row-major `rows x cols`.
pub fn from_panels(p: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    let mut out = vec![0.0; rows * cols];
    for (j0, width) in panels(cols) {
        let panel = &p[rows * j0..rows * (j0 + width)];
        for (row, prow) in out.chunks_exact_mut(cols).zip(panel.chunks_exact(width)) {
            row[j0..j0 + width].copy_from_slice(prow);
        }
    }
    out
}

/// Calls `block::<FMA, B>(args.., (width, k))` over the columns `k..k + B`
/// of a panel of `width`: one block of [`PANEL`], or blocks of 8 then single
/// columns for the narrower last panel.
macro_rules! blocks {
    ($width:expr, $block:ident :: <$fma:ident>, ($($arg:expr),*)) => {{
        let width = $width;
        if width == PANEL {
            $block::<$fma, PANEL>($($arg,)* (PANEL, 0));
        } else {
            let mut k = 0;
            while k + 8 <= width {
                $block::<$fma, 8>($($arg,)* (width, k));
                k += 8;
            }
            while k < width {
                $block::<$fma, 1>($($arg,)* (width, k));
                k += 1;
            }
        }
    }};
}

/// `out = b + W^T v` for `W` in panels (`v.len()` rows of `out.len()`
/// columns). For each block of columns the partial sums stay in registers
/// while the sweep walks down the (contiguous) panel, so each element of `W`
/// is loaded once and `out` is written once. Rows are accumulated in order
/// (the same rounding as a sweep of row axpys).
#[inline(always)]
pub fn affine_panels<const FMA: bool>(w: &[f32], v: &[f32], b: &[f32], out: &mut [f32]) {
    let rows = v.len();
    for (j0, width) in panels(out.len()) {
        let panel = &w[rows * j0..rows * (j0 + width)];
        let (b, out) = (&b[j0..j0 + width], &mut out[j0..j0 + width]);
        blocks!(width, affine_block::<FMA>, (panel, v, b, &mut *out));
    }
}

/// Columns `k..k + B` of a panel of `width` for [`affine_panels`].
#[inline(always)]
fn affine_block<const FMA: bool, const B: usize>(
    panel: &[f32],
    v: &[f32],
    b: &[f32],
    out: &mut [f32],
    (width, k): (usize, usize),
) {
    let mut acc: [f32; B] = b[k..k + B].try_into().expect("block of b");
    for (row, &vi) in panel.chunks_exact(width).zip(v) {
        let a: &[f32; B] = row[k..k + B].try_into().expect("block of W");
        for t in 0..B {
            acc[t] = madd::<FMA>(vi, a[t], acc[t]);
        }
    }
    out[k..k + B].copy_from_slice(&acc);
}

/// `out = b + W^T v` with `W` stored transposed (`out.len()` rows of
/// `v.len()`): one contiguous dot per output unit.
#[inline(always)]
pub fn affine_cols<const FMA: bool>(wt: &[f32], v: &[f32], b: &[f32], out: &mut [f32]) {
    for ((o, row), &bj) in out.iter_mut().zip(wt.chunks_exact(v.len())).zip(b) {
        *o = bj + dot::<FMA>(row, v);
    }
}

/// `g = W e` for `W` in panels (`g.len()` rows of `e.len()` columns): an
/// axpy of the panel's columns into `g` per column.
#[inline(always)]
pub fn back_panels<const FMA: bool>(w: &[f32], e: &[f32], g: &mut [f32]) {
    let rows = g.len();
    g.iter_mut().for_each(|g| *g = 0.0);
    for (j0, width) in panels(e.len()) {
        let panel = &w[rows * j0..rows * (j0 + width)];
        let e = &e[j0..j0 + width];
        for (gi, row) in g.iter_mut().zip(panel.chunks_exact(width)) {
            let mut s = *gi;
            for (&a, &ej) in row.iter().zip(e) {
                s = madd::<FMA>(a, ej, s);
            }
            *gi = s;
        }
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

/// `W += u v^T` for `W` in panels (`u.len()` rows of `v.len()` columns),
/// with each block of `v` held in registers down the panel.
#[inline(always)]
pub fn rank1_panels<const FMA: bool>(w: &mut [f32], u: &[f32], v: &[f32]) {
    let rows = u.len();
    for (j0, width) in panels(v.len()) {
        let panel = &mut w[rows * j0..rows * (j0 + width)];
        let v = &v[j0..j0 + width];
        blocks!(width, rank1_block::<FMA>, (&mut *panel, u, v));
    }
}

/// Columns `k..k + B` of a panel of `width` for [`rank1_panels`].
#[inline(always)]
fn rank1_block<const FMA: bool, const B: usize>(
    panel: &mut [f32],
    u: &[f32],
    v: &[f32],
    (width, k): (usize, usize),
) {
    let vb: [f32; B] = v[k..k + B].try_into().expect("block of v");
    for (row, &ui) in panel.chunks_exact_mut(width).zip(u) {
        let a: &mut [f32; B] = (&mut row[k..k + B]).try_into().expect("block of W");
        for t in 0..B {
            a[t] = madd::<FMA>(ui, vb[t], a[t]);
        }
    }
}

/// `W += u v^T` with `W` stored transposed (`v.len()` rows of `u.len()`).
#[inline(always)]
pub fn rank1_cols<const FMA: bool>(wt: &mut [f32], u: &[f32], v: &[f32]) {
    for (row, &vj) in wt.chunks_exact_mut(u.len()).zip(v) {
        axpy::<FMA>(row, vj, u);
    }
}

/// Fused `W += u v^T`, `b += g v`, then `out = b + W^T next` in one sweep over
/// `W` in panels: the first-layer update of one sample and the first-layer
/// drive of the next. For each block of columns, `v` and the drive's partial
/// sums stay in registers while the sweep walks down the (contiguous) panel,
/// so each element of `W` is loaded, updated, stored and multiplied once.
/// The same numbers as [`rank1_panels`], the bias step, then
/// [`affine_panels`]. (`g` lets a caller pass `W += (g x) e^T`, `b += g e`
/// without forming `g e`; `g = 1` is the plain update, bit for bit.)
#[inline(always)]
pub fn rank1_then_affine_panels<const FMA: bool>(
    w: &mut [f32],
    u: &[f32],
    (v, g): (&[f32], f32),
    next: &[f32],
    b: &mut [f32],
    out: &mut [f32],
) {
    let rows = u.len();
    for (j0, width) in panels(v.len()) {
        let panel = &mut w[rows * j0..rows * (j0 + width)];
        let (v, b) = (&v[j0..j0 + width], &mut b[j0..j0 + width]);
        let out = &mut out[j0..j0 + width];
        blocks!(
            width,
            rank1_affine_block::<FMA>,
            (&mut *panel, u, (v, g), next, &mut *b, &mut *out)
        );
    }
}

/// Columns `k..k + B` of a panel of `width` for [`rank1_then_affine_panels`].
#[inline(always)]
fn rank1_affine_block<const FMA: bool, const B: usize>(
    panel: &mut [f32],
    u: &[f32],
    (v, g): (&[f32], f32),
    next: &[f32],
    b: &mut [f32],
    out: &mut [f32],
    (width, k): (usize, usize),
) {
    let vb: [f32; B] = v[k..k + B].try_into().expect("block of v");
    let bb: &mut [f32; B] = (&mut b[k..k + B]).try_into().expect("block of b");
    for t in 0..B {
        bb[t] = madd::<FMA>(g, vb[t], bb[t]);
    }
    let mut acc = *bb;
    for ((row, &ui), &ni) in panel.chunks_exact_mut(width).zip(u).zip(next) {
        let a: &mut [f32; B] = (&mut row[k..k + B]).try_into().expect("block of W");
        for t in 0..B {
            a[t] = madd::<FMA>(ui, vb[t], a[t]);
            acc[t] = madd::<FMA>(ni, a[t], acc[t]);
        }
    }
    out[k..k + B].copy_from_slice(&acc);
}

/// The logistic sigmoid `1 / (1 + exp(-x))` of every element, through a
/// branch-free `exp` (Cody-Waite range reduction, degree-6 polynomial,
/// relative error about 2e-7) that vectorises. `FMA` as for [`madd`]; the
/// FMA build also replaces the division (8 cycles a vector on the Zen 1
/// machine measured) by the reciprocal estimate and one Newton step
/// (relative error about 1e-7 more).
#[inline(always)]
pub fn sigmoid<const FMA: bool>(src: &[f32], dst: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    if FMA {
        // SAFETY: `FMA` is true only inside functions compiled for AVX2 and
        // FMA, which are called only after runtime detection (`has_fma`).
        unsafe { sigmoid_rcp(src, dst) };
        return;
    }
    for (d, &x) in dst.iter_mut().zip(src) {
        *d = 1.0 / (1.0 + exp_approx::<FMA>(-x));
    }
}

/// [`sigmoid`] for the AVX2 + FMA build: `exp` as usual (vectorised by the
/// compiler, 32 at a time), then `1 / (1 + e)` by `rcp` and one Newton step.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
unsafe fn sigmoid_rcp(src: &[f32], dst: &mut [f32]) {
    use std::arch::x86_64::*;
    let n = src.len().min(dst.len());
    let body = n - n % LANES;
    let two = _mm256_set1_ps(2.0);
    let mut e = [0.0f32; LANES];
    for c in (0..body).step_by(LANES) {
        let x = &src[c..c + LANES];
        for k in 0..LANES {
            e[k] = 1.0 + exp_approx::<true>(-x[k]);
        }
        for v in 0..LANES / 8 {
            let den = _mm256_loadu_ps(e.as_ptr().add(8 * v));
            let r = _mm256_rcp_ps(den);
            // r (2 - den r): one Newton step towards 1 / den.
            let r = _mm256_mul_ps(r, _mm256_fnmadd_ps(den, r, two));
            _mm256_storeu_ps(dst.as_mut_ptr().add(c + 8 * v), r);
        }
    }
    for i in body..n {
        dst[i] = 1.0 / (1.0 + exp_approx::<true>(-src[i]));
    }
}

/// [`sigmoid`] without fused multiply-adds (callable anywhere).
#[inline(always)]
pub fn sigmoid_into(src: &[f32], dst: &mut [f32]) {
    sigmoid::<false>(src, dst);
}

/// Branch-free `exp(x)` for f32, saturating outside [-87, 88]; the range
/// reduction and the Horner steps use [`madd`].
#[inline(always)]
pub fn exp_approx<const FMA: bool>(x: f32) -> f32 {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    // Adding and removing 1.5 * 2^23 rounds to nearest without a libm call.
    const ROUNDER: f32 = 12_582_912.0;
    let x = x.clamp(-87.0, 88.0);
    // `t` holds `n = round(x log2 e)` in its low mantissa bits, so the scale
    // `2^n` is built with integer ops alone (no float-to-int conversion).
    let t = madd::<FMA>(x, LOG2E, ROUNDER);
    let n = t - ROUNDER;
    let r = madd::<FMA>(-n, LN2_HI, x);
    let r = madd::<FMA>(-n, LN2_LO, r);
    let p = madd::<FMA>(1.0 / 720.0, r, 1.0 / 120.0);
    let p = madd::<FMA>(p, r, 1.0 / 24.0);
    let p = madd::<FMA>(p, r, 1.0 / 6.0);
    let p = madd::<FMA>(p, r, 0.5);
    let p = madd::<FMA>(p, r, 1.0);
    let p = madd::<FMA>(p, r, 1.0);
    let scale = f32::from_bits(t.to_bits().wrapping_add(127) << 23);
    p * scale
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Worst relative error of `exp` over [-80, 80].
    fn exp_worst(exp: impl Fn(f32) -> f32) -> f64 {
        let mut worst = 0.0f64;
        for k in -8000..=8000 {
            let x = k as f32 * 0.01;
            let rel = ((exp(x) as f64) - (x as f64).exp()).abs() / (x as f64).exp();
            worst = worst.max(rel);
        }
        worst
    }

    #[test]
    fn exp_approx_matches_std_within_3e_7_relative() {
        let worst = exp_worst(exp_approx::<false>);
        assert!(worst < 3e-7, "worst relative error {worst}");
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    fn exp_worst_fma() -> f64 {
        exp_worst(exp_approx::<true>)
    }

    #[test]
    fn fused_exp_approx_matches_std_within_3e_7_relative() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports FMA (checked just above).
            let worst = unsafe { exp_worst_fma() };
            assert!(worst < 3e-7, "worst relative error {worst}");
            return;
        }
        eprintln!("skipped: no FMA on this CPU");
    }

    /// Worst relative error of the sigmoid of `FMA` over [-30, 30].
    fn sigmoid_worst<const FMA: bool>() -> f64 {
        let xs: Vec<f32> = (0..=60_000).map(|i| -30.0 + i as f32 * 1e-3).collect();
        let mut out = vec![0.0f32; xs.len()];
        sigmoid::<FMA>(&xs, &mut out);
        xs.iter()
            .zip(&out)
            .map(|(&x, &y)| {
                let exact = 1.0 / (1.0 + (-(x as f64)).exp());
                ((y as f64 - exact) / exact).abs()
            })
            .fold(0.0, f64::max)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn sigmoid_worst_fma() -> f64 {
        sigmoid_worst::<true>()
    }

    #[test]
    fn sigmoid_matches_the_exact_logistic_within_5e_7_relative() {
        let worst = sigmoid_worst::<false>();
        assert!(worst < 5e-7, "worst relative error {worst}");
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            let worst = unsafe { sigmoid_worst_fma() };
            assert!(worst < 5e-7, "fused build: worst relative error {worst}");
        }
    }

    #[test]
    fn panel_storage_round_trips() {
        let (rows, cols) = (3, 45);
        let w: Vec<f32> = (0..rows * cols).map(|k| k as f32).collect();
        let p = to_panels(&w, rows, cols);
        // Second panel (columns 32..45, width 13), row 1, column 33.
        assert_eq!(p[rows * 32 + 13 + 1], w[cols + 33]);
        assert_eq!(from_panels(&p, rows, cols), w);
    }

    #[test]
    fn affine_forms_agree_with_naive_product() {
        // 45 columns: one panel of 32, one of 13 (a block of 8, five single
        // columns).
        let (rows, cols) = (7, 45);
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
        let wp = to_panels(&w, rows, cols);
        let (mut wide, mut narrow) = (vec![0.0; cols], vec![0.0; cols]);
        affine_panels::<false>(&wp, &v, &b, &mut wide);
        affine_cols::<false>(&wt, &v, &b, &mut narrow);
        for j in 0..cols {
            assert!((wide[j] - naive[j]).abs() < 1e-5 && (narrow[j] - naive[j]).abs() < 1e-5);
        }
        let e: Vec<f32> = (0..cols).map(|k| 0.2 - k as f32 * 0.05).collect();
        let (mut g1, mut g2) = (vec![0.0; rows], vec![0.0; rows]);
        back_panels::<false>(&wp, &e, &mut g1);
        back_cols::<false>(&wt, &e, &mut g2);
        for i in 0..rows {
            let naive: f32 = (0..cols).map(|j| w[i * cols + j] * e[j]).sum();
            assert!((g1[i] - naive).abs() < 1e-5 && (g2[i] - naive).abs() < 1e-5);
        }
        let mut wr = w.clone();
        let mut wp2 = wp.clone();
        for (i, row) in wr.chunks_exact_mut(cols).enumerate() {
            row.iter_mut().zip(&e).for_each(|(a, ej)| *a += v[i] * ej);
        }
        rank1_panels::<false>(&mut wp2, &v, &e);
        assert_eq!(from_panels(&wp2, rows, cols), wr);
    }

    #[test]
    fn sum_squares_matches_serial_sum() {
        let v: Vec<f32> = (0..1003).map(|k| (k as f32 * 0.37).sin() * 3.0).collect();
        let serial: f64 = v.iter().map(|&x| (x as f64).powi(2)).sum();
        assert!((sum_squares_f64(&v) - serial).abs() < 1e-12 * serial);
    }

    #[test]
    fn fused_update_equals_update_then_affine() {
        let (rows, cols) = (5, 45);
        let mut w1: Vec<f32> = (0..rows * cols)
            .map(|k| ((k * 13 % 7) as f32 - 3.0) * 0.1)
            .collect();
        let mut w2 = w1.clone();
        let u: Vec<f32> = (0..rows).map(|k| k as f32 * 0.5 - 1.0).collect();
        let next: Vec<f32> = (0..rows).map(|k| 1.0 - k as f32 * 0.25).collect();
        let v: Vec<f32> = (0..cols).map(|k| k as f32 * 0.01).collect();
        let mut b1: Vec<f32> = (0..cols).map(|k| 0.1 - k as f32 * 0.003).collect();
        let mut b2 = b1.clone();
        let (mut o1, mut o2) = (vec![0.0; cols], vec![0.0; cols]);
        rank1_panels::<false>(&mut w1, &u, &v);
        b1.iter_mut().zip(&v).for_each(|(b, v)| *b += v);
        affine_panels::<false>(&w1, &next, &b1, &mut o1);
        rank1_then_affine_panels::<false>(&mut w2, &u, (&v, 1.0), &next, &mut b2, &mut o2);
        // Same operations in the same order: bitwise equal.
        assert_eq!(w1, w2);
        assert_eq!(b1, b2);
        assert_eq!(o1, o2);
    }
}
