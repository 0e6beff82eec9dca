//! The prediction path in AVX-512 (see `predict.rs`): rows in blocks of
//! [`BLOCK`] (a lone row on its own), and in every kernel each vector of
//! weights loaded once feeds every row of the block, the rows' partial
//! sums held in registers. Fused multiply-adds throughout.

use std::arch::x86_64::*;

use super::{InputMap, Predictor, Scratch, BLOCK, PROJECTION_COLUMNS};
use crate::kernels::{panels, sigmoid, PANEL};
use crate::net::Layers;
use crate::pose_model::PoseModel;

/// Whether the CPU runs this path (AVX-512F, with AVX2 and FMA).
pub(super) fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
}

/// Predicts every row of `flat` into `out` (see `Predictor::predict_rows`).
#[target_feature(enable = "avx512f,avx2,fma")]
pub(super) fn rows(p: &Predictor, model: &PoseModel, flat: &[f32], out: &mut Vec<[f64; 2]>) {
    let dim = p.dim();
    let rows = if flat.len() > dim { BLOCK } else { 1 };
    let mut s = Scratch::new(p, model, rows);
    for block in flat.chunks(BLOCK * dim) {
        for (x, &v) in s.x.iter_mut().zip(block) {
            *x = f64::from(v);
        }
        let n = block.len() / dim;
        if n == 1 {
            forward::<1>(p, model, &mut s, out);
        } else {
            // A short last block is padded with zero rows, then dropped.
            s.x[block.len()..].iter_mut().for_each(|x| *x = 0.0);
            let start = out.len();
            forward::<BLOCK>(p, model, &mut s, out);
            out.truncate(start + n);
        }
    }
}

/// Rows `0..R` of `s.x` through every net, appended to `out`.
#[target_feature(enable = "avx512f,avx2,fma")]
fn forward<const R: usize>(
    p: &Predictor,
    model: &PoseModel,
    s: &mut Scratch,
    out: &mut Vec<[f64; 2]>,
) {
    let dim = p.dim();
    let (maps, net_map) = p.maps();
    for (map, values) in maps.iter().zip(&mut s.maps) {
        match map {
            InputMap::Standardised { mean, std } => {
                for r in 0..R {
                    let (x, v) = (&s.x[r * dim..][..dim], &mut values[r * dim..][..dim]);
                    for (((v, &x), m), sd) in v.iter_mut().zip(x).zip(mean).zip(std) {
                        *v = ((x - m) / sd) as f32;
                    }
                }
            }
            InputMap::Projected { at, c, .. } => project::<R>(at, c, &s.x[..R * dim], values),
        }
    }
    let mut scaled = [[0.0f64; 2]; R];
    for (net, &m) in model.nets.iter().zip(net_map) {
        let layers = &net.layers;
        let depth = layers.depth();
        let [a, b] = &mut s.act;
        let d0 = layers.sizes()[0];
        a[..R * d0].copy_from_slice(&s.maps[m][..R * d0]);
        for l in 1..=depth {
            let (d_in, d_out) = (layers.sizes()[l - 1], layers.sizes()[l]);
            layer::<R>(layers, l, &a[..R * d_in], &mut b[..R * d_out]);
            if l < depth {
                sigmoid::<true>(&b[..R * d_out], &mut a[..R * d_out]);
            } else {
                a[..R * d_out].copy_from_slice(&b[..R * d_out]);
            }
        }
        let d_last = layers.sizes()[depth];
        for (r, row) in scaled.iter_mut().enumerate() {
            for (k, &col) in net.targets.iter().enumerate() {
                row[col] += f64::from(a[r * d_last + k]);
            }
        }
    }
    for row in &scaled {
        out.push(p.unscale(model, row));
    }
}

/// `values[r][j] = a_j . x_r + c_j` (f64 sums, f32 results) for the `R`
/// rows of `x`, from `A` transposed and padded (`at`, see
/// `InputMap::Projected`): the columns along the vector lanes, so each
/// row of `at` loaded feeds every row of a group of four (one) and no
/// sum is reduced across lanes.
#[target_feature(enable = "avx512f,avx2,fma")]
fn project<const R: usize>(at: &[f64], c: &[f64], x: &[f64], values: &mut [f32]) {
    let dim = x.len() / R;
    let k = c.len();
    let kp = at.len() / dim;
    for g in (0..kp).step_by(PROJECTION_COLUMNS) {
        let columns = (at, kp, g);
        if R == 1 {
            project_group::<1>(columns, x, c, values);
            continue;
        }
        for (x, values) in x.chunks_exact(4 * dim).zip(values.chunks_exact_mut(4 * k)) {
            project_group::<4>(columns, x, c, values);
        }
    }
}

/// Columns `g..g + 40` (those below `k`) of [`project`] for the `Q` rows
/// of `x`: the sums held in `Q x 5` registers down the rows of `at`
/// (`dim x kp`).
#[target_feature(enable = "avx512f,avx2,fma")]
fn project_group<const Q: usize>(
    (at, kp, g): (&[f64], usize, usize),
    x: &[f64],
    c: &[f64],
    values: &mut [f32],
) {
    const V: usize = PROJECTION_COLUMNS / 8;
    let dim = x.len() / Q;
    let k = c.len();
    let mut acc = [[_mm512_setzero_pd(); V]; Q];
    for (i, row) in at.chunks_exact(kp).enumerate() {
        let row = &row[g..g + PROJECTION_COLUMNS];
        // SAFETY: `row` holds 8 V values.
        let w: [__m512d; V] =
            std::array::from_fn(|t| unsafe { _mm512_loadu_pd(row[8 * t..].as_ptr()) });
        for (q, acc) in acc.iter_mut().enumerate() {
            let v = _mm512_set1_pd(x[q * dim + i]);
            for (acc, w) in acc.iter_mut().zip(&w) {
                *acc = _mm512_fmadd_pd(v, *w, *acc);
            }
        }
    }
    let mut sums = [0.0f64; PROJECTION_COLUMNS];
    for (q, acc) in acc.iter().enumerate() {
        for (t, acc) in acc.iter().enumerate() {
            // SAFETY: `sums` holds 8 V values.
            unsafe { _mm512_storeu_pd(sums[8 * t..].as_mut_ptr(), *acc) };
        }
        for j in g..k.min(g + PROJECTION_COLUMNS) {
            values[q * k + j] = (sums[j - g] + c[j]) as f32;
        }
    }
}

/// `out_r = W(l)^T in_r + b(l)` for `R` rows (`R x d(l-1)` in, `R x d(l)`
/// out), in the layer's storage (panels or transposed).
#[target_feature(enable = "avx512f,avx2,fma")]
fn layer<const R: usize>(layers: &Layers, l: usize, input: &[f32], out: &mut [f32]) {
    let (w, b) = (&layers.w[l - 1], &layers.b[l - 1]);
    let (d_in, d_out) = (layers.sizes[l - 1], layers.sizes[l]);
    if !layers.is_row_major(l) {
        return narrow::<R>(w, b, input, out);
    }
    for (j0, width) in panels(d_out) {
        let panel = &w[d_in * j0..d_in * (j0 + width)];
        let mut k = 0;
        if width == PANEL {
            panel32::<R>(panel, input, &b[j0..j0 + PANEL], (out, d_out, j0));
            continue;
        }
        while k + 8 <= width {
            panel8::<R>(
                panel,
                width,
                k,
                input,
                &b[j0 + k..j0 + k + 8],
                (out, d_out, j0 + k),
            );
            k += 8;
        }
        for k in k..width {
            for r in 0..R {
                let x = &input[r * d_in..][..d_in];
                let column = panel.chunks_exact(width).map(|row| row[k]);
                let total = column.zip(x).fold(b[j0 + k], |t, (w, &v)| v.mul_add(w, t));
                out[r * d_out + j0 + k] = total;
            }
        }
    }
}

/// A full panel (`d_in x 32`) for `R` rows: columns `col..col + 32` of
/// `out` (rows of `d_out`).
#[target_feature(enable = "avx512f,avx2,fma")]
fn panel32<const R: usize>(
    panel: &[f32],
    input: &[f32],
    bias: &[f32],
    (out, d_out, col): (&mut [f32], usize, usize),
) {
    let d_in = input.len() / R;
    // SAFETY: `bias` holds 32 values.
    let (b0, b1) = unsafe {
        (
            _mm512_loadu_ps(bias[..16].as_ptr()),
            _mm512_loadu_ps(bias[16..32].as_ptr()),
        )
    };
    let (mut lo, mut hi) = ([b0; R], [b1; R]);
    for (i, row) in panel.chunks_exact(PANEL).enumerate().take(d_in) {
        // SAFETY: `row` holds 32 values.
        let (w0, w1) = unsafe {
            (
                _mm512_loadu_ps(row[..16].as_ptr()),
                _mm512_loadu_ps(row[16..].as_ptr()),
            )
        };
        for r in 0..R {
            let v = _mm512_set1_ps(input[r * d_in + i]);
            lo[r] = _mm512_fmadd_ps(v, w0, lo[r]);
            hi[r] = _mm512_fmadd_ps(v, w1, hi[r]);
        }
    }
    for r in 0..R {
        let o = &mut out[r * d_out + col..][..PANEL];
        // SAFETY: `o` holds 32 values.
        unsafe {
            _mm512_storeu_ps(o[..16].as_mut_ptr(), lo[r]);
            _mm512_storeu_ps(o[16..].as_mut_ptr(), hi[r]);
        }
    }
}

/// Columns `k..k + 8` of a narrower last panel (`d_in x width`) for `R`
/// rows: columns `col..col + 8` of `out` (rows of `d_out`).
#[target_feature(enable = "avx512f,avx2,fma")]
fn panel8<const R: usize>(
    panel: &[f32],
    width: usize,
    k: usize,
    input: &[f32],
    bias: &[f32],
    (out, d_out, col): (&mut [f32], usize, usize),
) {
    let d_in = input.len() / R;
    // SAFETY: `bias` holds 8 values.
    let mut acc = [unsafe { _mm256_loadu_ps(bias[..8].as_ptr()) }; R];
    for (i, row) in panel.chunks_exact(width).enumerate().take(d_in) {
        // SAFETY: k + 8 <= width, the length of `row`.
        let w = unsafe { _mm256_loadu_ps(row[k..k + 8].as_ptr()) };
        for (r, acc) in acc.iter_mut().enumerate() {
            *acc = _mm256_fmadd_ps(_mm256_set1_ps(input[r * d_in + i]), w, *acc);
        }
    }
    for (r, acc) in acc.iter().enumerate() {
        let o = &mut out[r * d_out + col..][..8];
        // SAFETY: `o` holds 8 values.
        unsafe { _mm256_storeu_ps(o.as_mut_ptr(), *acc) };
    }
}

/// A narrow layer stored transposed (`d_out` rows of `d_in` weights): one
/// dot product per output and row.
#[target_feature(enable = "avx512f,avx2,fma")]
fn narrow<const R: usize>(wt: &[f32], b: &[f32], input: &[f32], out: &mut [f32]) {
    let d_in = input.len() / R;
    let d_out = b.len();
    let (body, tail) = (d_in - d_in % 16, d_in % 16);
    let mask: __mmask16 = ((1u32 << tail) - 1) as u16;
    for (o, w) in wt.chunks_exact(d_in).enumerate() {
        let mut acc = [_mm512_setzero_ps(); R];
        for i in (0..body).step_by(16) {
            // SAFETY: i + 16 <= body <= d_in, the length of `w` and of each
            // row of `input`.
            let wv = unsafe { _mm512_loadu_ps(w[i..].as_ptr()) };
            for (r, acc) in acc.iter_mut().enumerate() {
                let x = unsafe { _mm512_loadu_ps(input[r * d_in + i..].as_ptr()) };
                *acc = _mm512_fmadd_ps(wv, x, *acc);
            }
        }
        if tail > 0 {
            // SAFETY: the mask reads only the last `tail` values of `w` and
            // of each row of `input`.
            let wv = unsafe { _mm512_maskz_loadu_ps(mask, w[body..].as_ptr()) };
            for (r, acc) in acc.iter_mut().enumerate() {
                let x = unsafe { _mm512_maskz_loadu_ps(mask, input[r * d_in + body..].as_ptr()) };
                *acc = _mm512_fmadd_ps(wv, x, *acc);
            }
        }
        for (r, acc) in acc.iter().enumerate() {
            out[r * d_out + o] = b[o] + _mm512_reduce_add_ps(*acc);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The projection from `A` transposed and padded, by groups of 40
    /// columns (45 columns: a full group and a short one), one row and
    /// blocks of eight, equals the plain sums `a_j . x_r + c_j` (f64) to
    /// the f32 it returns.
    #[test]
    fn projection_by_column_groups_equals_the_plain_sums() {
        if !available() {
            eprintln!("SKIPPED: no AVX-512 on this CPU");
            return;
        }
        let (k, dim) = (45, 37);
        let value = |i: usize| ((i * 7919 % 1013) as f64 / 1013.0 - 0.5) * 3.0;
        let a: Vec<f64> = (0..k * dim).map(value).collect();
        let c: Vec<f64> = (0..k).map(|j| value(j + 5)).collect();
        let x: Vec<f64> = (0..BLOCK * dim).map(|i| value(i + 11)).collect();
        let at = super::super::transposed_padded(&a, k, dim);
        assert_eq!(at.len(), dim * 2 * PROJECTION_COLUMNS);
        let plain: Vec<f32> = (0..BLOCK * k)
            .map(|rj| {
                let (r, j) = (rj / k, rj % k);
                let dot: f64 = (0..dim).map(|i| a[j * dim + i] * x[r * dim + i]).sum();
                (dot + c[j]) as f32
            })
            .collect();
        let mut block = vec![0.0f32; BLOCK * k];
        let mut one = vec![0.0f32; k];
        // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked above).
        unsafe {
            project::<BLOCK>(&at, &c, &x, &mut block);
            project::<1>(&at, &c, &x[..dim], &mut one);
        }
        let close = |u: f32, v: f32| (u - v).abs() <= 1e-6 * v.abs().max(1.0);
        assert!(block.iter().zip(&plain).all(|(&u, &v)| close(u, v)));
        assert!(one.iter().zip(&plain[..k]).all(|(&u, &v)| close(u, v)));
    }
}
