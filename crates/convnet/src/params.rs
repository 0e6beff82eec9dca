//! The weights and biases of every layer (`W(l)` stored `cout x fan_in`,
//! row-major; `b(l)` one value a channel), and the same shape for
//! gradients: what the update rules produce and the optimiser consumes.
use crate::config::Activation;
use crate::layout::Layout;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One tensor a layer for weights and one for biases, input side first.
/// Used for the parameters and for gradients of the same shape.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameters {
    /// `weights[l]` is `W(l+1)`: `cout x fan_in`, row-major, fan-in index
    /// `(input channel, ky, kx)`.
    pub weights: Vec<Vec<f32>>,
    /// `biases[l]` is `b(l+1)`: one value an output channel.
    pub biases: Vec<Vec<f32>>,
}

impl Parameters {
    /// Zeros in the shape of `layout`.
    pub fn zeros(layout: &Layout) -> Self {
        Parameters {
            weights: layout
                .layers
                .iter()
                .map(|s| vec![0.0; s.weights()])
                .collect(),
            biases: layout.layers.iter().map(|s| vec![0.0; s.cout]).collect(),
        }
    }

    /// Weights uniform in `+-sqrt(3 gain / fan_in)` from `seed` (gain 2
    /// for the rectifier, 1 otherwise), biases zero. The same seed gives
    /// `conv-dennn` and `conv-mlp` the same start.
    pub fn init(layout: &Layout, activation: Activation, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut p = Self::zeros(layout);
        for (w, s) in p.weights.iter_mut().zip(&layout.layers) {
            let bound = (3.0 * activation.init_gain() / s.fan_in() as f32).sqrt();
            w.iter_mut()
                .for_each(|v| *v = rng.random_range(-bound..=bound));
        }
        p
    }

    /// Set every value to 0.
    pub fn clear(&mut self) {
        self.values_mut().for_each(|v| v.fill(0.0));
    }

    /// `self += other` (same shape).
    pub fn add(&mut self, other: &Parameters) {
        for (a, b) in self.values_mut().zip(other.values()) {
            a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
        }
    }

    /// `self = keep self + (1 - keep) other` (same shape): one step of an
    /// exponential moving average toward `other`.
    pub fn blend(&mut self, other: &Parameters, keep: f32) {
        let take = 1.0 - keep;
        for (a, b) in self.values_mut().zip(other.values()) {
            a.iter_mut()
                .zip(b)
                .for_each(|(a, &b)| *a = keep * *a + take * b);
        }
    }

    /// `self *= k`.
    pub fn scale(&mut self, k: f32) {
        self.values_mut()
            .for_each(|v| v.iter_mut().for_each(|a| *a *= k));
    }

    /// Every tensor in order (`W(1), b(1), W(2), ...`).
    pub fn values(&self) -> impl Iterator<Item = &Vec<f32>> {
        self.weights
            .iter()
            .zip(&self.biases)
            .flat_map(|(w, b)| [w, b])
    }

    /// Every tensor in order, mutable.
    pub fn values_mut(&mut self) -> impl Iterator<Item = &mut Vec<f32>> {
        self.weights
            .iter_mut()
            .zip(self.biases.iter_mut())
            .flat_map(|(w, b)| [w, b])
    }

    /// Every value in order, as f64.
    pub fn flatten(&self) -> Vec<f64> {
        self.values()
            .flat_map(|v| v.iter().map(|&x| x as f64))
            .collect()
    }

    /// Whether every value is a finite number.
    pub fn is_finite(&self) -> bool {
        self.values().all(|v| v.iter().all(|x| x.is_finite()))
    }

    /// Cosine of the angle between `self` and `other` seen as flat vectors
    /// (0 when either is zero).
    pub fn cosine(&self, other: &Parameters) -> f64 {
        let (a, b) = (self.flatten(), other.flatten());
        let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        let na: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt();
        let nb: f64 = b.iter().map(|x| x * x).sum::<f64>().sqrt();
        if na == 0.0 || nb == 0.0 {
            0.0
        } else {
            dot / (na * nb)
        }
    }
}
