//! The three matrix products of a layer, on row-major slices, through
//! faer's single-threaded GEMM (its packing buffers are thread-local and
//! reused, so a product allocates nothing; the parallelism is over frames,
//! one chunk a thread). Measured against matrixmultiply on this crate's
//! shapes, faer was as fast or faster on all but two (docs/learning.md).
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

/// `c (m x n) = a (m x k) * b (k x n)`. Here and below, panics when a
/// slice is shorter than its shape.
pub fn product(c: &mut [f32], a: &[f32], b: &[f32], m: usize, k: usize, n: usize) {
    let a = MatRef::from_row_major_slice(&a[..m * k], m, k);
    let b = MatRef::from_row_major_slice(&b[..k * n], k, n);
    let c = MatMut::from_row_major_slice_mut(&mut c[..m * n], m, n);
    matmul(c, Accum::Replace, a, b, 1.0f32, Par::Seq);
}

/// `c (k x n) = a^T b` with `a` stored `m x k` and `b` `m x n`.
pub fn product_tn(c: &mut [f32], a: &[f32], b: &[f32], m: usize, k: usize, n: usize) {
    let a = MatRef::from_row_major_slice(&a[..m * k], m, k);
    let b = MatRef::from_row_major_slice(&b[..m * n], m, n);
    let c = MatMut::from_row_major_slice_mut(&mut c[..k * n], k, n);
    matmul(c, Accum::Replace, a.transpose(), b, 1.0f32, Par::Seq);
}

/// `c (m x k) += alpha a b^T` with `a` stored `m x n` and `b` `k x n`.
pub fn add_product_nt(
    c: &mut [f32],
    alpha: f32,
    a: &[f32],
    b: &[f32],
    m: usize,
    k: usize,
    n: usize,
) {
    let a = MatRef::from_row_major_slice(&a[..m * n], m, n);
    let b = MatRef::from_row_major_slice(&b[..k * n], k, n);
    let c = MatMut::from_row_major_slice_mut(&mut c[..m * k], m, k);
    matmul(c, Accum::Add, a, b.transpose(), alpha, Par::Seq);
}
