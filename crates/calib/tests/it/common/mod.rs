//! Shared generators of the tests: seeded fields with a low-rank structure
//! like pin displacements, and a known affine distortion.
#![allow(dead_code)]
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_calib::Fields;

/// `n` fields of `dim` coordinates driven by `modes` latent factors plus a
/// little independent noise (simulated taps vary in a few directions).
pub fn sim_fields(n: usize, dim: usize, modes: usize, seed: u64) -> Fields {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let basis = DMatrix::from_fn(modes, dim, |_, _| rng.random_range(-1.0..1.0));
    let lat = DMatrix::from_fn(n, modes, |_, _| rng.random_range(-2.0..2.0));
    let noise = DMatrix::from_fn(n, dim, |_, _| rng.random_range(-0.1..0.1));
    Fields::from_matrix(lat * basis + noise, "sim").unwrap()
}

/// A distortion x -> A x + b with A = I + small dense part.
pub fn distortion(dim: usize, seed: u64) -> (DMatrix<f64>, DVector<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let a = DMatrix::identity(dim, dim)
        + DMatrix::from_fn(dim, dim, |_, _| {
            rng.random_range(-0.3..0.3) / (dim as f64).sqrt()
        });
    let b = DVector::from_fn(dim, |_, _| rng.random_range(-0.5..0.5));
    (a, b)
}

/// real = A sim + b + uniform noise of half-width `noise`.
pub fn distorted(
    sim: &Fields,
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    noise: f64,
    seed: u64,
) -> Fields {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut m = sim.matrix() * a.transpose();
    for mut row in m.row_iter_mut() {
        row += b.transpose();
    }
    if noise > 0.0 {
        m += DMatrix::from_fn(m.nrows(), m.ncols(), |_, _| rng.random_range(-noise..noise));
    }
    Fields::from_matrix(m, "real").unwrap()
}

/// `n` labelled taps (r in -5..5 mm, theta in -45..45 deg) and their
/// fields: smooth functions of the labels on `dim` coordinates, like twin
/// replays of a straight-edge tap set.
pub fn labelled_fields(n: usize, dim: usize, seed: u64) -> (Vec<(f64, f64)>, Fields) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let patterns = DMatrix::from_fn(6, dim, |_, _| rng.random_range(-1.0..1.0));
    let labels: Vec<(f64, f64)> = (0..n)
        .map(|_| (rng.random_range(-5.0..5.0), rng.random_range(-45.0..45.0)))
        .collect();
    let feats = DMatrix::from_fn(n, 6, |i, k| {
        let (r, t) = (labels[i].0 / 5.0, labels[i].1.to_radians());
        [r, t.sin(), t.cos(), r * t.cos(), (r * 1.5).tanh(), r * r][k]
    });
    let noise = DMatrix::from_fn(n, dim, |_, _| rng.random_range(-0.05..0.05));
    (
        labels,
        Fields::from_matrix(feats * patterns + noise, "sim").unwrap(),
    )
}
