//! Test data for the learning crate's tests, written once: the integration
//! tests take it as `mod support;`, the library's own unit tests by path.
//! It names only outside crates (no `tactrace_learn` or `crate` paths), so
//! it compiles in both.
#![allow(dead_code)]
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `n` rows of `dim` correlated values (pin-displacement-like) and their
/// two targets, row-major: a position in mm in -5..5 and an angle in deg in
/// -45..45, each row a smooth function of them plus uniform noise of
/// +-0.2; seeded by `seed`. Returns `(x, y)` (`n * dim` and `2 * n`
/// values), for `Dataset::new(x, y, n, dim, 2)`.
pub fn correlated_rows(n: usize, dim: usize, seed: u64) -> (Vec<f32>, Vec<f32>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut x = Vec::with_capacity(n * dim);
    let mut y = Vec::with_capacity(2 * n);
    for _ in 0..n {
        let (a, b): (f32, f32) = (rng.random_range(-5.0..5.0), rng.random_range(-45.0..45.0));
        for j in 0..dim {
            let phase = j as f32 * 0.37;
            x.push(a * phase.sin() + 0.1 * b * phase.cos() + rng.random_range(-0.2..0.2));
        }
        y.extend([a, b]);
    }
    (x, y)
}

/// An input of `dim_x` and a target of `dim_y` values, each uniform in
/// -1..1, seeded by `seed`: one sample for the gradient checks.
pub fn sample(dim_x: usize, dim_y: usize, seed: u64) -> (Vec<f32>, Vec<f32>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let x = (0..dim_x).map(|_| rng.random_range(-1.0..1.0)).collect();
    let t = (0..dim_y).map(|_| rng.random_range(-1.0..1.0)).collect();
    (x, t)
}

/// The cosine of the angle between `a` and `b`.
pub fn cosine(a: &[f64], b: &[f64]) -> f64 {
    let dot: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let na: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    let nb: f64 = b.iter().map(|x| x * x).sum::<f64>().sqrt();
    dot / (na * nb)
}

/// The pin spacing (px) of [`hex_layout`].
pub const SPACING: f64 = 4.5;
/// The centre (px) of [`hex_layout`] and of [`edge_field`]'s edges.
pub const CENTRE: [f64; 2] = [63.0, 64.0];

/// A hexagonal layout of `rings` rings about `CENTRE`, its pins `SPACING`
/// px apart (331 pins for 10).
pub fn hex_layout(rings: i32) -> Vec<[f64; 2]> {
    let mut pins = Vec::new();
    for a in -rings..=rings {
        for b in -rings..=rings {
            if (a + b).abs() <= rings {
                let (a, b) = (f64::from(a), f64::from(b));
                let x = CENTRE[0] + SPACING * (a + 0.5 * b);
                let y = CENTRE[1] + SPACING * (0.75f64.sqrt() * b);
                pins.push([x, y]);
            }
        }
    }
    pins
}

/// The displacements of a toy edge: its labelled angle `theta` (deg) is
/// the image angle of its normal negated (the image's y axis points
/// down), its signed distance `r` (px here) from the centre; every pin on
/// the far side moves along the normal by its depth past the edge.
pub fn edge_field(pins: &[[f64; 2]], r: f64, theta: f64) -> Vec<f32> {
    let (s, c) = (-theta).to_radians().sin_cos();
    let n = pins.len();
    let mut d = vec![0.0f32; 2 * n];
    for (i, p) in pins.iter().enumerate() {
        let depth = (p[0] - CENTRE[0]) * c + (p[1] - CENTRE[1]) * s - r;
        if depth > 0.0 {
            d[i] = (0.1 * depth * c) as f32;
            d[n + i] = (0.1 * depth * s) as f32;
        }
    }
    d
}

/// The rows of toy edges over `pins` at `poses` (`(r, theta)`, px and
/// deg): [`edge_field`]'s displacements and the poses as targets,
/// row-major, for `Dataset::new(x, y, poses.len(), 2 * pins.len(), 2)`.
pub fn edge_rows(pins: &[[f64; 2]], poses: &[(f64, f64)]) -> (Vec<f32>, Vec<f32>) {
    let x = poses
        .iter()
        .flat_map(|&(r, t)| edge_field(pins, r, t))
        .collect();
    let y = poses
        .iter()
        .flat_map(|&(r, t)| [r as f32, t as f32])
        .collect();
    (x, y)
}
