//! The (mu/mu_w, lambda)-CMA-ES of N. Hansen, "The CMA Evolution Strategy:
//! A Tutorial" (arXiv:1604.00772), with the tutorial's default strategy
//! parameters (its Table 1) and notation: mean m, step size sigma,
//! covariance C = B D^2 B^T, evolution paths p_sigma and p_c.
//!
//! Minimises; a NaN cost ranks last. The caller asks for a generation,
//! evaluates it and tells the costs back, in the order asked.
use crate::OptimError;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// The largest population accepted (the tutorial's default for 13
/// dimensions is 11).
pub const MAX_POPULATION: usize = 100_000;

/// Start point, spread and population.
#[derive(Debug, Clone, PartialEq)]
pub struct CmaesConfig {
    /// The initial mean m.
    pub start: Vec<f64>,
    /// The initial step size sigma (same units as `start`).
    pub sigma: f64,
    /// Population lambda; `None`: 4 + floor(3 ln n) (the tutorial's).
    pub population: Option<usize>,
    /// Seed of every sample.
    pub seed: u64,
}

/// The strategy's constants, fixed by n and lambda (tutorial, Table 1).
#[derive(Debug, Clone)]
struct Constants {
    weights: Vec<f64>,
    mu_eff: f64,
    c_sigma: f64,
    d_sigma: f64,
    c_c: f64,
    c_1: f64,
    c_mu: f64,
    /// E||N(0, I)||.
    chi_n: f64,
}

impl Constants {
    fn new(n: usize, lambda: usize) -> Self {
        let nf = n as f64;
        let mu = lambda / 2;
        let raw: Vec<f64> = (1..=mu)
            .map(|i| ((lambda as f64 + 1.0) / 2.0).ln() - (i as f64).ln())
            .collect();
        let sum: f64 = raw.iter().sum();
        let weights: Vec<f64> = raw.iter().map(|w| w / sum).collect();
        let mu_eff = 1.0 / weights.iter().map(|w| w * w).sum::<f64>();
        let c_sigma = (mu_eff + 2.0) / (nf + mu_eff + 5.0);
        let d_sigma = 1.0 + 2.0 * (((mu_eff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + c_sigma;
        let c_c = (4.0 + mu_eff / nf) / (nf + 4.0 + 2.0 * mu_eff / nf);
        let c_1 = 2.0 / ((nf + 1.3).powi(2) + mu_eff);
        let c_mu =
            (2.0 * (mu_eff - 2.0 + 1.0 / mu_eff) / ((nf + 2.0).powi(2) + mu_eff)).min(1.0 - c_1);
        let chi_n = nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));
        Self {
            weights,
            mu_eff,
            c_sigma,
            d_sigma,
            c_c,
            c_1,
            c_mu,
            chi_n,
        }
    }
}

/// A running CMA-ES: ask for points, tell their costs, repeat.
#[derive(Debug, Clone)]
pub struct Cmaes {
    k: Constants,
    lambda: usize,
    mean: DVector<f64>,
    sigma: f64,
    cov: DMatrix<f64>,
    /// Eigenvectors B and the square roots of the eigenvalues D of C.
    basis: DMatrix<f64>,
    scales: DVector<f64>,
    p_sigma: DVector<f64>,
    p_c: DVector<f64>,
    generation: usize,
    rng: ChaCha8Rng,
    /// The points of the generation asked last (x, and y = (x - m) / sigma).
    asked: Vec<(DVector<f64>, DVector<f64>)>,
    best: Option<(Vec<f64>, f64)>,
}

impl Cmaes {
    /// A strategy at `cfg.start` with spread `cfg.sigma`.
    pub fn new(cfg: &CmaesConfig) -> Result<Self, OptimError> {
        let n = cfg.start.len();
        if n == 0 {
            return Err(OptimError::Config(
                "nothing to optimise (no parameters)".into(),
            ));
        }
        if cfg.start.iter().any(|v| !v.is_finite()) {
            return Err(OptimError::Config("the start point is not finite".into()));
        }
        if !(cfg.sigma.is_finite() && cfg.sigma > 0.0) {
            return Err(OptimError::Config(format!(
                "sigma = {} must be a positive number",
                cfg.sigma
            )));
        }
        let lambda = cfg
            .population
            .unwrap_or(4 + (3.0 * (n as f64).ln()).floor() as usize);
        if lambda < 2 {
            return Err(OptimError::Config(format!(
                "population {lambda} is too small (at least 2)"
            )));
        }
        if lambda > MAX_POPULATION {
            // The weights alone take lambda / 2 numbers: 1e12 aborted.
            return Err(OptimError::Config(format!(
                "population {lambda} is too large (at most {MAX_POPULATION})"
            )));
        }
        Ok(Self {
            k: Constants::new(n, lambda),
            lambda,
            mean: DVector::from_column_slice(&cfg.start),
            sigma: cfg.sigma,
            cov: DMatrix::identity(n, n),
            basis: DMatrix::identity(n, n),
            scales: DVector::from_element(n, 1.0),
            p_sigma: DVector::zeros(n),
            p_c: DVector::zeros(n),
            generation: 0,
            rng: ChaCha8Rng::seed_from_u64(cfg.seed),
            asked: Vec::new(),
            best: None,
        })
    }

    /// The population lambda: points per generation.
    pub fn population(&self) -> usize {
        self.lambda
    }

    /// Generations told so far.
    pub fn generation(&self) -> usize {
        self.generation
    }

    /// The current mean m.
    pub fn mean(&self) -> Vec<f64> {
        self.mean.iter().copied().collect()
    }

    /// The current step size sigma.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }

    /// The best point told so far and its cost.
    pub fn best(&self) -> Option<(&[f64], f64)> {
        self.best.as_ref().map(|(x, f)| (x.as_slice(), *f))
    }

    /// The next generation's lambda points, x = m + sigma B D z.
    pub fn ask(&mut self) -> Vec<Vec<f64>> {
        let n = self.mean.len();
        self.asked = (0..self.lambda)
            .map(|_| {
                let z = DVector::from_fn(n, |_, _| self.rng.sample::<f64, _>(StandardNormal));
                let y = &self.basis * z.component_mul(&self.scales);
                (&self.mean + &y * self.sigma, y)
            })
            .collect();
        self.asked
            .iter()
            .map(|(x, _)| x.iter().copied().collect())
            .collect()
    }

    /// The costs of the points of the last [`Cmaes::ask`], in its order;
    /// updates m, sigma, C and the paths (tutorial, eq. 39-47).
    pub fn tell(&mut self, costs: &[f64]) -> Result<(), OptimError> {
        if costs.len() != self.asked.len() || costs.is_empty() {
            return Err(OptimError::Generation {
                expected: self.asked.len(),
                got: costs.len(),
            });
        }
        let key = |f: f64| if f.is_nan() { f64::INFINITY } else { f };
        let mut order: Vec<usize> = (0..costs.len()).collect();
        order.sort_by(|&a, &b| key(costs[a]).total_cmp(&key(costs[b])));
        let best = order[0];
        if self
            .best
            .as_ref()
            .is_none_or(|(_, f)| key(costs[best]) < *f)
        {
            let x = self.asked[best].0.iter().copied().collect();
            self.best = Some((x, key(costs[best])));
        }
        let n = self.mean.len();
        let k = &self.k;
        let mut y_w = DVector::zeros(n);
        for (w, &i) in k.weights.iter().zip(&order) {
            y_w += &self.asked[i].1 * *w;
        }
        self.mean += &y_w * self.sigma;
        // C^(-1/2) y_w = B D^-1 B^T y_w.
        let inv_sqrt_y = &self.basis * (self.basis.transpose() * &y_w).component_div(&self.scales);
        self.p_sigma = &self.p_sigma * (1.0 - k.c_sigma)
            + inv_sqrt_y * (k.c_sigma * (2.0 - k.c_sigma) * k.mu_eff).sqrt();
        let g = (self.generation + 1) as f64;
        let norm = self.p_sigma.norm() / (1.0 - (1.0 - k.c_sigma).powf(2.0 * g)).sqrt();
        let h_sigma = norm < (1.4 + 2.0 / (n as f64 + 1.0)) * k.chi_n;
        let h = if h_sigma { 1.0 } else { 0.0 };
        self.p_c =
            &self.p_c * (1.0 - k.c_c) + &y_w * (h * (k.c_c * (2.0 - k.c_c) * k.mu_eff).sqrt());
        let mut rank_mu = DMatrix::zeros(n, n);
        for (w, &i) in k.weights.iter().zip(&order) {
            let y = &self.asked[i].1;
            rank_mu += y * y.transpose() * *w;
        }
        let delta_h = (1.0 - h) * k.c_c * (2.0 - k.c_c);
        self.cov = &self.cov * (1.0 - k.c_1 - k.c_mu)
            + (&self.p_c * self.p_c.transpose() + &self.cov * delta_h) * k.c_1
            + rank_mu * k.c_mu;
        self.sigma *= ((k.c_sigma / k.d_sigma) * (self.p_sigma.norm() / k.chi_n - 1.0)).exp();
        self.decompose();
        self.generation += 1;
        Ok(())
    }

    /// B and D from C, kept symmetric and positive.
    fn decompose(&mut self) {
        let sym = (&self.cov + self.cov.transpose()) * 0.5;
        let eig = SymmetricEigen::new(sym);
        let floor = 1e-20;
        self.scales = eig.eigenvalues.map(|v| v.max(floor).sqrt());
        self.basis = eig.eigenvectors;
        self.cov = &self.basis
            * DMatrix::from_diagonal(&self.scales.map(|d| d * d))
            * self.basis.transpose();
    }
}
