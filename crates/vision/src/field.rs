//! A smooth displacement field over the reference pin layout, fitted to the
//! pins matched so far: a least-squares affine map plus a Gaussian-weighted
//! (Nadaraya-Watson) average of the residuals. The tracker uses it to predict
//! where every pin has moved before matching, and to fill in missing pins.

use nalgebra::{Matrix3, Vector3};

/// Gaussian kernel weights between reference pins for one width.
pub struct Kernel {
    n: usize,
    /// `weights[j * n + i]`: the weight pin `j`'s residual has at pin `i`.
    weights: Vec<f64>,
    /// Per source pin `j`, the range of pins `i` outside which its weight is 0.
    bands: Vec<std::ops::Range<usize>>,
}

impl Kernel {
    /// Weights `exp(-|r_i - r_j|^2 / (2 sigma^2))`, dropped below 1e-4.
    pub fn new(reference: &[[f64; 2]], sigma: f64) -> Self {
        let n = reference.len();
        let scale = -0.5 / (sigma * sigma);
        let mut weights = Vec::with_capacity(n * n);
        let mut bands = Vec::with_capacity(n);
        for b in reference {
            let row = weights.len();
            for a in reference {
                let d2 = (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
                let w = (scale * d2).exp();
                weights.push(if w >= 1e-4 { w } else { 0.0 });
            }
            let kept = |w: &f64| *w > 0.0;
            let lo = weights[row..].iter().position(kept).unwrap_or(0);
            let hi = weights[row..].iter().rposition(kept).map_or(0, |i| i + 1);
            bands.push(lo..hi.max(lo));
        }
        Self { n, weights, bands }
    }

    /// Weight of pin `j`'s residual at pin `i`.
    #[cfg(test)]
    fn at(&self, i: usize, j: usize) -> f64 {
        self.weights[j * self.n + i]
    }
}

/// Observed displacements: `Some(d)` for a matched pin, `None` otherwise.
pub type Observations = [Option<[f64; 2]>];

/// Displacement of every reference pin under the field fitted to the
/// observations; `prior` (in matched-pin units) pulls the local correction
/// towards the affine part where few neighbours are matched.
///
/// The local part at pin i is `sum_j w_ij res_j / (prior + sum_j w_ij)`
/// over the matched pins j with `w_ij > 0`, summed in pin order. The sums
/// run source by source over every pin of its band at once (vectorised);
/// a zero weight adds an exact zero, which changes no sum (the sums start
/// at +0 or `prior` and so never hold -0), so the result is the same, bit
/// for bit, as the pin-by-pin sum (checked in the tests).
pub fn smooth_field(
    reference: &[[f64; 2]],
    observed: &Observations,
    kernel: &Kernel,
    prior: f64,
) -> Vec<[f64; 2]> {
    let affine = fit_affine(reference, observed);
    // Residuals of the matched pins only, in pin order.
    let residual: Vec<(usize, [f64; 2])> = reference
        .iter()
        .zip(observed)
        .enumerate()
        .filter_map(|(j, (r, o))| {
            o.map(|d| {
                let a = affine.apply(*r);
                (j, [d[0] - a[0], d[1] - a[1]])
            })
        })
        .collect();
    let n = reference.len();
    let (mut sx, mut sy, mut sw) = (vec![0.0; n], vec![0.0; n], vec![prior; n]);
    let finite = residual
        .iter()
        .all(|(_, r)| r[0].is_finite() && r[1].is_finite());
    if finite && kernel.n == n {
        let mut blocks = residual.chunks_exact(4);
        for block in &mut blocks {
            add_sources::<4>(kernel, block, [&mut sx, &mut sy, &mut sw]);
        }
        for source in blocks.remainder() {
            add_sources::<1>(
                kernel,
                std::slice::from_ref(source),
                [&mut sx, &mut sy, &mut sw],
            );
        }
    } else {
        // Non-finite residuals: 0 * inf would not add zero; sum pin by pin.
        for i in 0..n {
            let weights = (0..n).map(|j| kernel.weights[j * kernel.n + i]);
            [sx[i], sy[i], sw[i]] = weighted_sums(weights, &residual, prior);
        }
    }
    reference
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let base = affine.apply(*r);
            let local = if sw[i] > 0.0 {
                [sx[i] / sw[i], sy[i] / sw[i]]
            } else {
                [0.0, 0.0]
            };
            [base[0] + local[0], base[1] + local[1]]
        })
        .collect()
}

/// Adds the weighted residuals of `N` sources `(pin, residual)` to the
/// sums (x, y, weight) of every pin in the union of their bands, one source
/// after the other for each pin (the order of a source-by-source pass; the
/// pin's sums stay in registers across the `N` sources).
fn add_sources<const N: usize>(
    kernel: &Kernel,
    sources: &[(usize, [f64; 2])],
    [sx, sy, sw]: [&mut [f64]; 3],
) {
    let lo = sources
        .iter()
        .map(|s| kernel.bands[s.0].start)
        .min()
        .unwrap_or(0);
    let hi = sources
        .iter()
        .map(|s| kernel.bands[s.0].end)
        .max()
        .unwrap_or(0);
    if lo >= hi {
        return;
    }
    let len = hi - lo;
    let rows: [&[f64]; N] = std::array::from_fn(|m| {
        let row = sources[m].0 * kernel.n;
        &kernel.weights[row + lo..row + hi]
    });
    let res: [[f64; 2]; N] = std::array::from_fn(|m| sources[m].1);
    let (x, y, s) = (&mut sx[lo..hi], &mut sy[lo..hi], &mut sw[lo..hi]);
    for k in 0..len {
        let (mut a, mut b, mut c) = (x[k], y[k], s[k]);
        for m in 0..N {
            let w = rows[m][k];
            a += w * res[m][0];
            b += w * res[m][1];
            c += w;
        }
        (x[k], y[k], s[k]) = (a, b, c);
    }
}

/// Kernel-weighted sums (x, y, weight) of the matched residuals
/// `(pin, residual)` at one pin, `weights` indexed by source pin, the
/// weight starting at `prior` (pins with zero weight are skipped).
fn weighted_sums(
    weights: impl Iterator<Item = f64> + Clone,
    residual: &[(usize, [f64; 2])],
    prior: f64,
) -> [f64; 3] {
    let weights: Vec<f64> = weights.collect();
    let (mut sx, mut sy, mut sw) = (0.0, 0.0, prior);
    for &(j, r) in residual {
        let w = weights[j];
        if w > 0.0 {
            sx += w * r[0];
            sy += w * r[1];
            sw += w;
        }
    }
    [sx, sy, sw]
}

/// Displacement d(r) = origin-centred affine map of the reference position.
#[derive(Clone, Copy, Debug)]
pub struct Affine {
    centre: [f64; 2],
    x: Vector3<f64>,
    y: Vector3<f64>,
}

impl Affine {
    fn zero() -> Self {
        Self {
            centre: [0.0; 2],
            x: Vector3::zeros(),
            y: Vector3::zeros(),
        }
    }

    pub fn apply(&self, r: [f64; 2]) -> [f64; 2] {
        let v = Vector3::new(r[0] - self.centre[0], r[1] - self.centre[1], 1.0);
        [self.x.dot(&v), self.y.dot(&v)]
    }
}

/// Least-squares affine displacement; a pure translation when the matched
/// pins are fewer than three or collinear; zero when none is matched.
pub fn fit_affine(reference: &[[f64; 2]], observed: &Observations) -> Affine {
    let pairs: Vec<([f64; 2], [f64; 2])> = reference
        .iter()
        .zip(observed)
        .filter_map(|(r, o)| o.map(|d| (*r, d)))
        .collect();
    if pairs.is_empty() {
        return Affine::zero();
    }
    let n = pairs.len() as f64;
    let centre = [
        pairs.iter().map(|p| p.0[0]).sum::<f64>() / n,
        pairs.iter().map(|p| p.0[1]).sum::<f64>() / n,
    ];
    let mean_d = [
        pairs.iter().map(|p| p.1[0]).sum::<f64>() / n,
        pairs.iter().map(|p| p.1[1]).sum::<f64>() / n,
    ];
    let translation = Affine {
        centre,
        x: Vector3::new(0.0, 0.0, mean_d[0]),
        y: Vector3::new(0.0, 0.0, mean_d[1]),
    };
    let mut normal = Matrix3::<f64>::zeros();
    let (mut bx, mut by) = (Vector3::zeros(), Vector3::zeros());
    for (r, d) in &pairs {
        let v = Vector3::new(r[0] - centre[0], r[1] - centre[1], 1.0);
        normal += v * v.transpose();
        bx += v * d[0];
        by += v * d[1];
    }
    let spread = normal[(0, 0)] + normal[(1, 1)];
    if pairs.len() < 3 || normal.determinant().abs() <= 1e-9 * spread * spread * n {
        return translation;
    }
    match normal.try_inverse() {
        Some(inv) => Affine {
            centre,
            x: inv * bx,
            y: inv * by,
        },
        None => translation,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Vec<[f64; 2]> {
        (0..7)
            .flat_map(|i| (0..7).map(move |j| [10.0 * f64::from(i), 10.0 * f64::from(j)]))
            .collect()
    }

    #[test]
    fn recovers_an_exact_affine_field_with_gaps() {
        let reference = grid();
        let truth = |r: [f64; 2]| {
            [
                0.1 * r[0] - 0.05 * r[1] + 3.0,
                0.02 * r[0] + 0.2 * r[1] - 1.0,
            ]
        };
        let observed: Vec<Option<[f64; 2]>> = reference
            .iter()
            .enumerate()
            .map(|(i, r)| (i % 5 != 0).then(|| truth(*r)))
            .collect();
        let field = smooth_field(&reference, &observed, &Kernel::new(&reference, 15.0), 0.1);
        for (r, d) in reference.iter().zip(&field) {
            let t = truth(*r);
            assert!((d[0] - t[0]).abs() < 1e-9 && (d[1] - t[1]).abs() < 1e-9);
        }
    }

    /// The source-by-source (vectorised) sums equal the pin-by-pin ones
    /// bit for bit, on a jittered grid with random gaps and residuals.
    #[test]
    fn banded_sums_equal_pin_by_pin_sums() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        for _ in 0..50 {
            let reference: Vec<[f64; 2]> = grid()
                .iter()
                .map(|r| {
                    [
                        r[0] + rng.random_range(-2.0..2.0),
                        r[1] + rng.random_range(-2.0..2.0),
                    ]
                })
                .collect();
            let observed: Vec<Option<[f64; 2]>> = reference
                .iter()
                .map(|_| {
                    rng.random_bool(0.8)
                        .then(|| [rng.random_range(-9.0..9.0), rng.random_range(-9.0..9.0)])
                })
                .collect();
            let kernel = Kernel::new(&reference, rng.random_range(5.0..30.0));
            let prior = rng.random_range(0.0..0.5);
            let got = smooth_field(&reference, &observed, &kernel, prior);
            let affine = fit_affine(&reference, &observed);
            let residual: Vec<(usize, [f64; 2])> = observed
                .iter()
                .enumerate()
                .filter_map(|(j, o)| {
                    o.map(|d| {
                        let a = affine.apply(reference[j]);
                        (j, [d[0] - a[0], d[1] - a[1]])
                    })
                })
                .collect();
            for (i, r) in reference.iter().enumerate() {
                let weights = (0..reference.len()).map(|j| kernel.at(i, j));
                let [sx, sy, sw] = weighted_sums(weights, &residual, prior);
                let local = if sw > 0.0 {
                    [sx / sw, sy / sw]
                } else {
                    [0.0, 0.0]
                };
                let base = affine.apply(*r);
                assert_eq!(got[i], [base[0] + local[0], base[1] + local[1]]);
            }
        }
    }

    #[test]
    fn degenerate_observations_fall_back_gracefully() {
        let reference = grid();
        let none = vec![None; reference.len()];
        let kernel = Kernel::new(&reference, 15.0);
        assert!(smooth_field(&reference, &none, &kernel, 0.1)
            .iter()
            .all(|d| d == &[0.0, 0.0]));
        let mut one = none.clone();
        one[3] = Some([2.0, -1.0]);
        let field = smooth_field(&reference, &one, &kernel, 0.1);
        assert!(field
            .iter()
            .all(|d| (d[0] - 2.0).abs() < 1e-12 && (d[1] + 1.0).abs() < 1e-12));
    }
}
