//! PCA and standardisation against theory: orthonormal components, whitened
//! training data with identity covariance, explained variance equal to the
//! eigenvalue ratio of an independent (Jacobi) eigen solve.
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_learn::{Components, PcScaling, Pca, Standardiser};

/// Correlated data: `n x dim`, built from a few latent factors plus noise.
fn correlated(n: usize, dim: usize, seed: u64) -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mix: Vec<f32> = (0..4 * dim).map(|_| rng.random_range(-1.0..1.0)).collect();
    let mut x = Vec::with_capacity(n * dim);
    for _ in 0..n {
        let z: Vec<f32> = (0..4)
            .map(|k| rng.random_range(-1.0..1.0) * (4 - k) as f32)
            .collect();
        for j in 0..dim {
            let v: f32 = (0..4).map(|k| z[k] * mix[k * dim + j]).sum();
            x.push(3.0 * v + 0.05 * rng.random_range(-1.0..1.0) + j as f32);
        }
    }
    x
}

fn covariance(x: &[f64], n: usize, dim: usize) -> Vec<f64> {
    let mean: Vec<f64> = (0..dim)
        .map(|j| (0..n).map(|i| x[i * dim + j]).sum::<f64>() / n as f64)
        .collect();
    let mut c = vec![0.0; dim * dim];
    for i in 0..n {
        for p in 0..dim {
            for q in 0..dim {
                c[p * dim + q] +=
                    (x[i * dim + p] - mean[p]) * (x[i * dim + q] - mean[q]) / n as f64;
            }
        }
    }
    c
}

/// Eigenvalues of a symmetric matrix by cyclic Jacobi rotations, descending.
fn jacobi_eigenvalues(mut a: Vec<f64>, d: usize) -> Vec<f64> {
    for _ in 0..100 {
        let off: f64 = (0..d)
            .flat_map(|p| (0..d).filter(move |&q| q != p).map(move |q| (p, q)))
            .map(|(p, q)| a[p * d + q].powi(2))
            .sum();
        if off < 1e-22 {
            break;
        }
        for p in 0..d {
            for q in p + 1..d {
                let apq = a[p * d + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * d + q] - a[p * d + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
                for k in 0..d {
                    let (akp, akq) = (a[k * d + p], a[k * d + q]);
                    a[k * d + p] = c * akp - s * akq;
                    a[k * d + q] = s * akp + c * akq;
                }
                for k in 0..d {
                    let (apk, aqk) = (a[p * d + k], a[q * d + k]);
                    a[p * d + k] = c * apk - s * aqk;
                    a[q * d + k] = s * apk + c * aqk;
                }
            }
        }
    }
    let mut ev: Vec<f64> = (0..d).map(|i| a[i * d + i]).collect();
    ev.sort_by(|x, y| y.total_cmp(x));
    ev
}

#[test]
fn components_are_orthonormal() {
    let (n, dim) = (300, 12);
    let x = correlated(n, dim, 1);
    let z = Standardiser::fit(&x, n, dim).unwrap().transform(&x);
    let pca = Pca::fit(&z, n, dim, Components::Count(6), PcScaling::Raw).unwrap();
    let w = pca.components();
    for a in 0..6 {
        for b in 0..6 {
            let dot: f64 = (0..dim).map(|j| w[a * dim + j] * w[b * dim + j]).sum();
            let expected = if a == b { 1.0 } else { 0.0 };
            assert!((dot - expected).abs() < 1e-10, "w{a} . w{b} = {dot}");
        }
    }
}

#[test]
fn whitened_training_data_has_identity_covariance() {
    let (n, dim) = (400, 10);
    let x = correlated(n, dim, 2);
    let z = Standardiser::fit(&x, n, dim).unwrap().transform(&x);
    let k = 4;
    let pca = Pca::fit(&z, n, dim, Components::Count(k), PcScaling::Whiten).unwrap();
    let c = covariance(&pca.transform(&z), n, k);
    for p in 0..k {
        for q in 0..k {
            let expected = if p == q { 1.0 } else { 0.0 };
            assert!(
                (c[p * k + q] - expected).abs() < 1e-9,
                "cov[{p}][{q}] = {}",
                c[p * k + q]
            );
        }
    }
}

#[test]
fn unit_mean_scaling_keeps_the_shape_and_averages_unit_variance() {
    let (n, dim) = (400, 10);
    let x = correlated(n, dim, 2);
    let z = Standardiser::fit(&x, n, dim).unwrap().transform(&x);
    let k = 5;
    let raw = Pca::fit(&z, n, dim, Components::Count(k), PcScaling::Raw).unwrap();
    let unit = Pca::fit(&z, n, dim, Components::Count(k), PcScaling::UnitMean).unwrap();
    let (cr, cu) = (
        covariance(&raw.transform(&z), n, k),
        covariance(&unit.transform(&z), n, k),
    );
    let mean_var: f64 = (0..k).map(|p| cu[p * k + p]).sum::<f64>() / k as f64;
    assert!((mean_var - 1.0).abs() < 1e-9, "mean variance {mean_var}");
    // One common factor: the ratios between components are the raw ones.
    let f = cu[0] / cr[0];
    for p in 0..k {
        assert!(
            (cu[p * k + p] / cr[p * k + p] - f).abs() < 1e-9,
            "component {p}"
        );
        assert!((cr[p * k + p] - raw.eigenvalues()[p]).abs() < 1e-9);
    }
}

#[test]
fn explained_variance_equals_independent_eigenvalue_ratio() {
    let (n, dim) = (250, 9);
    let x = correlated(n, dim, 3);
    let z = Standardiser::fit(&x, n, dim).unwrap().transform(&x);
    let pca = Pca::fit(&z, n, dim, Components::Count(dim), PcScaling::Raw).unwrap();
    let ev = jacobi_eigenvalues(covariance(&z, n, dim), dim);
    let total: f64 = ev.iter().sum();
    // Standardised data: the covariance trace is the dimension.
    assert!((total - dim as f64).abs() < 1e-9);
    for (r, e) in pca.explained_variance_ratio().iter().zip(&ev) {
        assert!((r - e / total).abs() < 1e-10, "{r} vs {}", e / total);
    }
}

#[test]
fn variance_target_picks_the_fewest_components() {
    let (n, dim) = (300, 12);
    let x = correlated(n, dim, 4);
    let z = Standardiser::fit(&x, n, dim).unwrap().transform(&x);
    let pca = Pca::fit(&z, n, dim, Components::Variance(0.95), PcScaling::Raw).unwrap();
    let r = pca.explained_variance_ratio();
    let kept: f64 = r.iter().sum();
    assert!(kept >= 0.95 - 1e-12, "kept {kept}");
    assert!(
        kept - r[r.len() - 1] < 0.95,
        "one fewer would also reach 0.95"
    );
    assert!(Pca::fit(&z, n, dim, Components::Variance(1.5), PcScaling::Raw).is_err());
    assert!(Pca::fit(&z, n, dim, Components::Count(0), PcScaling::Raw).is_err());
}

#[test]
fn standardiser_handles_constant_features() {
    let x = [1.0f32, 5.0, 2.0, 5.0, 3.0, 5.0];
    let s = Standardiser::fit(&x, 3, 2).unwrap();
    assert_eq!(s.std()[1], 1.0);
    let z = s.transform(&x);
    assert!(z.iter().all(|v| v.is_finite()));
    assert!((z[0] + 1.224_744_871).abs() < 1e-6 && z[1] == 0.0);
}
