//! The tree-structured Parzen estimator (TPE) of J. Bergstra, R. Bardenet,
//! Y. Bengio and B. Kégl, "Algorithms for Hyper-Parameter Optimization"
//! (NeurIPS 2011), section 4, for spaces whose parameters are independent
//! (no conditional parameters, so the "tree" is flat).
//!
//! The trials so far are split at the gamma quantile y* of their scores
//! (lower is better): the good ones (y < y*) give a density l(x), the rest
//! g(x). Expected improvement is monotone in l(x) / g(x) (the paper's
//! eq. 6), so each parameter's next value is the candidate, among a few
//! drawn from l, with the largest log l - log g; the densities factorise
//! over the parameters, so each is chosen on its own. A continuous
//! parameter's density is a Parzen window: a Gaussian at each value, with
//! the width the larger of the gaps to its neighbours (clipped), plus a
//! Gaussian prior over the whole range, all truncated to the range (in
//! log space for log parameters); a choice's density is its count plus a
//! prior of one.
//!
//! Pure and deterministic: trial `k`'s suggestion depends only on the seed,
//! `k` and the history given, so a search resumed from its recorded
//! trials suggests exactly what the uninterrupted one did.
use crate::OptimError;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

/// One parameter's domain. Values are passed as `f64`: a float, an
/// integer's value, or a choice's index.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Domain {
    /// A real number in `[low, high]`, spaced logarithmically when `log`.
    Float { low: f64, high: f64, log: bool },
    /// An integer in `[low, high]`, spaced logarithmically when `log`.
    Int { low: i64, high: i64, log: bool },
    /// One of `n` unordered choices (index 0..n).
    Choice { n: usize },
}

impl Domain {
    /// The interval the Parzen window lives in (log-transformed when
    /// `log`; integers widened by half a step each side).
    fn interval(&self) -> (f64, f64) {
        match *self {
            Domain::Float { low, high, log } => warp(low, high, log),
            Domain::Int { low, high, log } if log => {
                warp(low as f64 - 0.5, high as f64 + 0.5, true)
            }
            Domain::Int { low, high, .. } => (low as f64 - 0.5, high as f64 + 0.5),
            Domain::Choice { n } => (0.0, n as f64),
        }
    }

    /// A value of the domain from a point of its interval.
    fn value_at(self, z: f64) -> f64 {
        match self {
            Domain::Float { low, high, log } => (if log { z.exp() } else { z }).clamp(low, high),
            Domain::Int { low, high, log } => {
                let v = if log { z.exp() } else { z };
                v.round().clamp(low as f64, high as f64)
            }
            Domain::Choice { n } => z.floor().clamp(0.0, n as f64 - 1.0),
        }
    }

    /// The point of the interval a value stands for.
    fn point_of(self, v: f64) -> f64 {
        match self {
            Domain::Float { log: true, .. } | Domain::Int { log: true, .. } => v.max(1e-300).ln(),
            _ => v,
        }
    }

    fn check(&self) -> Result<(), String> {
        let (lo, hi, log) = match *self {
            Domain::Float { low, high, log } => (low, high, log),
            Domain::Int { low, high, log } => (low as f64, high as f64, log),
            Domain::Choice { n: 0 } => return Err("a choice needs at least one value".into()),
            Domain::Choice { .. } => return Ok(()),
        };
        if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
            return Err(format!("range [{lo}, {hi}] is not a finite interval"));
        }
        if log && lo <= 0.0 {
            return Err(format!("a log range needs low > 0, got {lo}"));
        }
        Ok(())
    }
}

fn warp(low: f64, high: f64, log: bool) -> (f64, f64) {
    if log {
        (low.ln(), high.ln())
    } else {
        (low, high)
    }
}

/// TPE's settings. [`Default`]: 10 random start-up trials, gamma 0.25,
/// 24 candidates (hyperopt's defaults).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TpeConfig {
    /// Seed of every draw.
    pub seed: u64,
    /// Trials drawn from the prior before the model is used.
    pub startup: usize,
    /// Fraction of the trials (at least one) counted as good.
    pub gamma: f64,
    /// Candidates drawn from l(x) per parameter and suggestion.
    pub candidates: usize,
}

impl Default for TpeConfig {
    fn default() -> Self {
        TpeConfig {
            seed: 0,
            startup: 10,
            gamma: 0.25,
            candidates: 24,
        }
    }
}

/// One finished trial: its values (one per parameter) and score (lower is
/// better; a non-finite score counts as the worst).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    pub values: Vec<f64>,
    pub score: f64,
}

/// A TPE over a fixed list of parameters.
#[derive(Debug, Clone)]
pub struct Tpe {
    domains: Vec<Domain>,
    config: TpeConfig,
}

impl Tpe {
    /// Check the domains and settings.
    pub fn new(domains: Vec<Domain>, config: TpeConfig) -> Result<Self, OptimError> {
        if domains.is_empty() {
            return Err(OptimError::Tpe("no parameters to search".into()));
        }
        for (k, d) in domains.iter().enumerate() {
            d.check()
                .map_err(|r| OptimError::Tpe(format!("parameter {k}: {r}")))?;
        }
        if !(config.gamma > 0.0 && config.gamma < 1.0) || config.candidates == 0 {
            return Err(OptimError::Tpe(
                "gamma must lie in (0, 1) and candidates be at least 1".into(),
            ));
        }
        Ok(Tpe { domains, config })
    }

    /// The parameters' domains.
    pub fn domains(&self) -> &[Domain] {
        &self.domains
    }

    /// The values of trial `trial` (from 0) given the finished trials
    /// `history` (any order is not allowed: pass them in trial order). A
    /// random draw from the prior while fewer than `startup` trials (or
    /// fewer than two) are finished.
    pub fn suggest(&self, trial: usize, history: &[Observation]) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.config.seed);
        rng.set_stream(trial as u64);
        if history.len() < self.config.startup.max(2) {
            return self.sample_prior(&mut rng);
        }
        let (good, bad) = self.split(history);
        (0..self.domains.len())
            .map(|p| {
                let g: Vec<f64> = good.iter().map(|o| o.values[p]).collect();
                let b: Vec<f64> = bad.iter().map(|o| o.values[p]).collect();
                self.choose(p, &g, &b, &mut rng)
            })
            .collect()
    }

    /// Values drawn uniformly (log-uniformly for log parameters).
    pub fn sample_prior(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        self.domains
            .iter()
            .map(|d| {
                let (lo, hi) = d.interval();
                d.value_at(lo + (hi - lo) * rng.random::<f64>())
            })
            .collect()
    }

    /// The good (best `ceil(gamma n)`, at least one, at most n - 1) and
    /// the other observations; ties broken by trial order.
    fn split<'a>(
        &self,
        history: &'a [Observation],
    ) -> (Vec<&'a Observation>, Vec<&'a Observation>) {
        let n = history.len();
        let mut order: Vec<usize> = (0..n).collect();
        let key = |o: &Observation| {
            if o.score.is_finite() {
                o.score
            } else {
                f64::INFINITY
            }
        };
        order.sort_by(|&a, &b| {
            key(&history[a])
                .total_cmp(&key(&history[b]))
                .then(a.cmp(&b))
        });
        let n_good = ((self.config.gamma * n as f64).ceil() as usize).clamp(1, n - 1);
        let good = order[..n_good].iter().map(|&k| &history[k]).collect();
        let bad = order[n_good..].iter().map(|&k| &history[k]).collect();
        (good, bad)
    }

    /// Parameter `p`'s value: the candidate drawn from l with the largest
    /// log l - log g.
    fn choose(&self, p: usize, good: &[f64], bad: &[f64], rng: &mut ChaCha8Rng) -> f64 {
        let d = &self.domains[p];
        if let Domain::Choice { n } = *d {
            let l = Categorical::fit(n, good);
            let g = Categorical::fit(n, bad);
            let best = (0..self.config.candidates)
                .map(|_| l.sample(rng))
                .max_by(|&a, &b| {
                    (l.p[a] / g.p[a])
                        .total_cmp(&(l.p[b] / g.p[b]))
                        .then(b.cmp(&a))
                });
            return best.unwrap_or(0) as f64;
        }
        let (lo, hi) = d.interval();
        let internal = |v: &[f64]| v.iter().map(|&x| d.point_of(x)).collect::<Vec<_>>();
        let l = Parzen::fit(&internal(good), lo, hi);
        let g = Parzen::fit(&internal(bad), lo, hi);
        let mut best = (f64::NEG_INFINITY, lo);
        for _ in 0..self.config.candidates {
            let z = l.sample(rng);
            let ei = l.log_pdf(z) - g.log_pdf(z);
            if ei > best.0 {
                best = (ei, z);
            }
        }
        d.value_at(best.1)
    }
}

/// A choice's density: (count + 1) / (n + total).
struct Categorical {
    p: Vec<f64>,
}

impl Categorical {
    fn fit(n: usize, values: &[f64]) -> Self {
        let mut counts = vec![1.0; n];
        for &v in values {
            let k = (v.max(0.0) as usize).min(n - 1);
            counts[k] += 1.0;
        }
        let total: f64 = counts.iter().sum();
        Categorical {
            p: counts.into_iter().map(|c| c / total).collect(),
        }
    }

    fn sample(&self, rng: &mut ChaCha8Rng) -> usize {
        let mut u = rng.random::<f64>();
        for (k, &p) in self.p.iter().enumerate() {
            if u < p {
                return k;
            }
            u -= p;
        }
        self.p.len() - 1
    }
}

/// An equally weighted mixture of Gaussians truncated to `[lo, hi]`: one
/// per value and the prior (centred, width the whole range).
struct Parzen {
    mus: Vec<f64>,
    sigmas: Vec<f64>,
    lo: f64,
    hi: f64,
}

impl Parzen {
    /// The paper's adaptive widths: each Gaussian as wide as the larger
    /// gap to its sorted neighbours (the prior's mean and the range's ends
    /// included), clipped to [range / min(100, n + 1), range].
    fn fit(values: &[f64], lo: f64, hi: f64) -> Self {
        let range = (hi - lo).max(1e-12);
        let mut mus: Vec<f64> = values.iter().map(|v| v.clamp(lo, hi)).collect();
        mus.push(0.5 * (lo + hi));
        mus.sort_by(f64::total_cmp);
        let n = mus.len();
        let min_sigma = range / (100.0f64).min(n as f64 + 1.0);
        let sigmas = (0..n)
            .map(|k| {
                let left = if k == 0 {
                    mus[k] - lo
                } else {
                    mus[k] - mus[k - 1]
                };
                let right = if k + 1 == n {
                    hi - mus[k]
                } else {
                    mus[k + 1] - mus[k]
                };
                left.max(right).clamp(min_sigma, range)
            })
            .collect::<Vec<_>>();
        // The prior: the Gaussian at the range's centre is as wide as the range.
        let prior = mus.iter().position(|&m| m == 0.5 * (lo + hi)).unwrap_or(0);
        let mut sigmas = sigmas;
        sigmas[prior] = range;
        Parzen {
            mus,
            sigmas,
            lo,
            hi,
        }
    }

    fn sample(&self, rng: &mut ChaCha8Rng) -> f64 {
        let k = rng.random_range(0..self.mus.len());
        let (mu, sigma) = (self.mus[k], self.sigmas[k]);
        for _ in 0..64 {
            let z: f64 = rng.sample(StandardNormal);
            let x = mu + sigma * z;
            if (self.lo..=self.hi).contains(&x) {
                return x;
            }
        }
        mu
    }

    fn log_pdf(&self, x: f64) -> f64 {
        let mut sum = 0.0;
        for (&mu, &sigma) in self.mus.iter().zip(&self.sigmas) {
            let mass = phi((self.hi - mu) / sigma) - phi((self.lo - mu) / sigma);
            let z = (x - mu) / sigma;
            sum += (-0.5 * z * z).exp()
                / (sigma * (2.0 * std::f64::consts::PI).sqrt() * mass.max(1e-300));
        }
        (sum / self.mus.len() as f64).max(1e-300).ln()
    }
}

/// The standard normal distribution function, through erf (Abramowitz and
/// Stegun 7.1.26, absolute error below 1.5e-7).
fn phi(x: f64) -> f64 {
    0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2))
}

fn erf(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let y = 1.0 - poly * (-x * x).exp();
    if x >= 0.0 {
        y
    } else {
        -y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_known_values() {
        for (x, want) in [
            (0.0, 0.0),
            (0.5, 0.520_499_877_8),
            (1.0, 0.842_700_792_9),
            (-2.0, -0.995_322_265),
        ] {
            assert!((erf(x) - want).abs() < 2e-7, "erf({x})");
        }
    }

    #[test]
    fn parzen_density_integrates_to_one() {
        let p = Parzen::fit(&[0.1, 0.15, 0.8], 0.0, 1.0);
        let n = 20_000;
        let integral: f64 = (0..n)
            .map(|k| p.log_pdf((k as f64 + 0.5) / n as f64).exp() / n as f64)
            .sum();
        assert!((integral - 1.0).abs() < 1e-3, "{integral}");
    }

    #[test]
    fn suggestions_stay_in_their_domains() {
        let tpe = Tpe::new(
            vec![
                Domain::Float {
                    low: 1e-3,
                    high: 10.0,
                    log: true,
                },
                Domain::Int {
                    low: 2,
                    high: 9,
                    log: false,
                },
                Domain::Choice { n: 3 },
            ],
            TpeConfig {
                startup: 3,
                ..TpeConfig::default()
            },
        )
        .unwrap();
        let mut history = Vec::new();
        for k in 0..30 {
            let v = tpe.suggest(k, &history);
            assert!((1e-3..=10.0).contains(&v[0]));
            assert!((2.0..=9.0).contains(&v[1]) && v[1].fract() == 0.0);
            assert!([0.0, 1.0, 2.0].contains(&v[2]));
            let score = (v[0].ln() - 0.0).powi(2) + (v[1] - 4.0).abs() + v[2];
            history.push(Observation { values: v, score });
        }
    }
}
