//! The dendritic neural network (DenNN) trained by equilibrium propagation,
//! report ch. 3.3-3.5 with the corrections of ERRATA.md:
//! - free phase: the feed-forward pass (the exact fixed point of eq. 3.12,
//!   default) or `n_I` Euler steps of `ds/dt = -dE/ds` (eqs. 3.12-3.15 with
//!   the lateral term `phi'(s(l)) . W(l+1) e(l+1)`);
//! - nudge towards the target, `y_nudged = y + beta (t - y)`;
//! - weakly clamped phase with the output held at `y_nudged`: hidden layers
//!   relax to equilibrium (closed form for one hidden layer, or Euler);
//! - local update `W(l) += eta phi(s(l-1)) e(l)^T`, `b(l) += eta e(l)`
//!   (eqs. 3.21-3.22 with the sign fixed together with the nudge).
use crate::cost::NetCost;
use crate::dataset::Dataset;
use crate::ep::step;
use crate::error::LearnError;
use crate::kernels::sigmoid_into;
use crate::net::{has_fma, Layers, States};
use serde::{Deserialize, Serialize};

/// How the free phase finds its equilibrium.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum FreePhase {
    /// The feed-forward pass. Default: with no target every error of eq.
    /// 3.15 vanishes, so the feed-forward state *is* the fixed point of eq.
    /// 3.12; computing it directly is exact and costs one pass, whereas Euler
    /// with `dt = 1` only converges while `sum_i W2_i^2 phi'(h_i)^2 < 0.5`.
    FeedForward,
    /// The report's faithful mode: `n_i` Euler steps of eq. 3.12 of size `dt`
    /// from zero potentials (report: `n_i = 5`, `dt = 1`).
    Euler { n_i: usize, dt: f64 },
}

/// How the weakly clamped phase relaxes the hidden layers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ClampedPhase {
    /// Closed-form equilibrium for one hidden layer, linearising the sigmoid
    /// about the free state (exact to first order in beta): with
    /// `D = diag(phi'(h))`, `A = W2^T D^2 W2`, the output error is
    /// `e(2) = (I + A)^-1 beta (t - y)` and `e(1) = D W2 e(2)`. The updates
    /// of W1, b1 and b2 are then exactly `-eta beta (I + A)^-1` times the
    /// backprop gradient; W2's gets a second-order term `eta2 c^2 delta^2 D u`
    /// (c = beta / (1 + a), one output) from the clamped activity
    /// `phi + D e(1)` (docs/learning.md; `tests/it/ep_beta.rs`). Any other depth
    /// or output count takes the same closed form through every hidden
    /// layer, `(I + sum_l G(l) G(l)^T) e(N) = beta (t - y)` with
    /// `G(l) = dy/ds(l)` (`crate::deep_clamp`).
    Linearised,
    /// `n_i` Euler steps of eq. 3.12 for the hidden layers, output held.
    Euler { n_i: usize, dt: f64 },
}

/// How the learning rate `eta` of eq. 3.21 is applied to each layer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LrScaling {
    /// The same `eta` for every layer (the report's rule).
    #[default]
    None,
    /// `eta / d(l-1)` for layer `l` (its fan-in). Per-sample SGD on a layer
    /// moves the output by about `eta ||phi(s(l-1))||^2` times the error, and
    /// `||phi||^2` grows with the layer's width: with a plain `eta` a
    /// 1000-unit hidden layer turns `eta = 0.01` into a step of about 2.5
    /// (unstable for backprop) while the first layer barely learns. Dividing
    /// by the fan-in makes `eta` mean the same for any width or input count,
    /// which keeps one default (and one search grid) valid for all nets.
    FanIn,
}

impl LrScaling {
    /// The rate for a layer with `fan_in` inputs.
    #[inline(always)]
    pub fn rate(self, eta: f32, fan_in: usize) -> f32 {
        match self {
            LrScaling::None => eta,
            LrScaling::FanIn => eta / fan_in.max(1) as f32,
        }
    }
}

/// Hyper-parameters of one equilibrium-propagation step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EpConfig {
    /// `eta` of eq. 3.21 (every layer, unless `output_learning_rate`).
    pub learning_rate: f64,
    /// `eta` of the output layer, if different (default: `learning_rate`).
    #[serde(default)]
    pub output_learning_rate: Option<f64>,
    /// Per-layer application of `eta`.
    #[serde(default)]
    pub lr_scaling: LrScaling,
    /// Nudging coefficient `beta` (eq. 3.16).
    pub beta: f64,
    pub free_phase: FreePhase,
    pub clamped_phase: ClampedPhase,
    pub epochs: usize,
    pub seed: u64,
    /// A cost other than the squared one on an output ([`NetCost`]),
    /// entering through the nudge; none (the default, not written): eq.
    /// 3.16's squared cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cost: Option<NetCost>,
}

impl Default for EpConfig {
    fn default() -> Self {
        EpConfig {
            learning_rate: 0.001,
            output_learning_rate: None,
            lr_scaling: LrScaling::None,
            beta: 1.0,
            free_phase: FreePhase::FeedForward,
            clamped_phase: ClampedPhase::Linearised,
            epochs: 200,
            seed: 0,
            cost: None,
        }
    }
}

/// What one training step saw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleStats {
    /// Eq. 3.16 with `beta = 1` at the free-phase output: `0.5 ||y - t||^2`.
    pub loss: f64,
    /// Eq. 3.17 at the weakly clamped equilibrium (output at `y_nudged`).
    pub energy: f64,
}

/// A dendritic network of any layer sizes (sigmoid hidden layers).
#[derive(Debug, Clone)]
pub struct DenNN {
    layers: Layers,
    st: States,
}

impl DenNN {
    /// Random weights from `seed` (see [`Layers::new`]).
    pub fn new(sizes: &[usize], seed: u64) -> Result<Self, LearnError> {
        Ok(Self::from_layers(Layers::new(sizes, seed)?))
    }

    /// Wrap existing parameters (e.g. to compare with an [`crate::Mlp`]).
    pub fn from_layers(layers: Layers) -> Self {
        let st = States::new(&layers.sizes);
        DenNN { layers, st }
    }

    /// The parameters.
    pub fn layers(&self) -> &Layers {
        &self.layers
    }

    /// Input dimension `d(0)`.
    pub fn input_dim(&self) -> usize {
        self.layers.sizes[0]
    }

    /// Output dimension `d(N)`.
    pub fn output_dim(&self) -> usize {
        self.layers.sizes[self.layers.depth()]
    }

    /// The free phase's fixed point (feed-forward pass) for input `x` into
    /// `out`; wrong lengths are errors.
    pub fn predict(&self, x: &[f32], out: &mut [f32]) -> Result<(), LearnError> {
        self.layers.predict(x, out)
    }

    /// Total energy, eq. 3.17, of the potentials `states` (`states[0] = x`,
    /// `states[l] = s(l)`): `0.5 sum_l ||s(l) - W(l)^T phi(s(l-1)) - b(l)||^2
    /// + beta/2 ||s(N) - t||^2`. Without a target it is the free energy 3.10.
    pub fn energy(&self, states: &[Vec<f32>], target: Option<&[f32]>, beta: f64) -> f64 {
        let n = self.layers.depth();
        let mut total = 0.0;
        let mut ff = Vec::new();
        for l in 1..=n.min(states.len().saturating_sub(1)) {
            let pre: Vec<f32> = if l == 1 {
                states[0].clone()
            } else {
                sigmoid_vec(&states[l - 1])
            };
            ff.resize(self.layers.sizes[l], 0.0);
            self.layers.affine::<false>(l, &pre, &mut ff);
            total += 0.5
                * states[l]
                    .iter()
                    .zip(&ff)
                    .map(|(s, f)| ((s - f) as f64).powi(2))
                    .sum::<f64>();
        }
        if let (Some(t), Some(y)) = (target, states.get(n)) {
            total += 0.5
                * beta
                * y.iter()
                    .zip(t)
                    .map(|(y, t)| ((y - t) as f64).powi(2))
                    .sum::<f64>();
        }
        total
    }

    /// One equilibrium-propagation step on sample `(x, t)` (free phase, nudge,
    /// weakly clamped phase, local update). Wrong lengths are errors.
    pub fn train_sample(
        &mut self,
        x: &[f32],
        t: &[f32],
        cfg: &EpConfig,
    ) -> Result<SampleStats, LearnError> {
        check_dims(&self.layers, x, t)?;
        if has_fma() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return Ok(unsafe { train_sample_fma(self, x, t, cfg) });
        }
        Ok(train_sample_impl::<false>(self, x, t, cfg))
    }

    /// One epoch of EP steps over the samples `order` of `data`, in that
    /// order (fusing each first-layer update with the next sample's drive;
    /// the same arithmetic as calling [`Self::train_sample`] in turn).
    /// Returns the mean loss and energy. Out-of-range rows are errors.
    pub fn train_sequence(
        &mut self,
        data: &Dataset,
        order: &[usize],
        cfg: &EpConfig,
    ) -> Result<SampleStats, LearnError> {
        check_sequence(&self.layers, data, order)?;
        if has_fma() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return Ok(unsafe { train_sequence_fma(self, data, order, cfg) });
        }
        Ok(train_sequence_impl::<false>(self, data, order, cfg))
    }

    /// The potentials of the last training step (`s(0) = x` .. `s(N)`), after
    /// its weakly clamped phase.
    pub fn last_states(&self) -> &[Vec<f32>] {
        &self.st.s
    }

    /// The errors `e(l)` used by the last update (`e(0)` unused).
    pub fn last_errors(&self) -> &[Vec<f32>] {
        &self.st.e
    }
}

/// Input and output/target lengths against the layer sizes.
pub(crate) fn check_dims(layers: &Layers, x: &[f32], y: &[f32]) -> Result<(), LearnError> {
    let sizes = layers.sizes();
    if x.len() != sizes[0] {
        return Err(LearnError::DimensionMismatch {
            expected: sizes[0],
            got: x.len(),
        });
    }
    let out = sizes[sizes.len() - 1];
    if y.len() != out {
        return Err(LearnError::Shape {
            what: "output/target",
            expected: out,
            got: y.len(),
        });
    }
    Ok(())
}

/// A dataset and sample order against the layer sizes.
pub(crate) fn check_sequence(
    layers: &Layers,
    data: &Dataset,
    order: &[usize],
) -> Result<(), LearnError> {
    let sizes = layers.sizes();
    if data.dim_x != sizes[0] {
        return Err(LearnError::DimensionMismatch {
            expected: sizes[0],
            got: data.dim_x,
        });
    }
    if data.dim_y != sizes[sizes.len() - 1] {
        return Err(LearnError::Shape {
            what: "targets per sample",
            expected: sizes[sizes.len() - 1],
            got: data.dim_y,
        });
    }
    match order.iter().find(|&&i| i >= data.n) {
        Some(&i) => Err(LearnError::Shape {
            what: "sample index",
            expected: data.n,
            got: i,
        }),
        None => Ok(()),
    }
}

fn sigmoid_vec(s: &[f32]) -> Vec<f32> {
    let mut out = vec![0.0; s.len()];
    sigmoid_into(s, &mut out);
    out
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn train_sample_fma(net: &mut DenNN, x: &[f32], t: &[f32], cfg: &EpConfig) -> SampleStats {
    train_sample_impl::<true>(net, x, t, cfg)
}

#[inline(always)]
fn train_sample_impl<const F: bool>(
    net: &mut DenNN,
    x: &[f32],
    t: &[f32],
    cfg: &EpConfig,
) -> SampleStats {
    net.layers.affine::<F>(1, x, &mut net.st.drive);
    step::<F>(&mut net.layers, &mut net.st, x, t, cfg, None)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn train_sequence_fma(
    net: &mut DenNN,
    data: &Dataset,
    order: &[usize],
    cfg: &EpConfig,
) -> SampleStats {
    train_sequence_impl::<true>(net, data, order, cfg)
}

/// Train on `order` in turn; each first-layer update is fused with the next
/// sample's first-layer drive. Returns mean loss and energy.
#[inline(always)]
fn train_sequence_impl<const F: bool>(
    net: &mut DenNN,
    data: &Dataset,
    order: &[usize],
    cfg: &EpConfig,
) -> SampleStats {
    let mut total = SampleStats {
        loss: 0.0,
        energy: 0.0,
    };
    let Some(&first) = order.first() else {
        return total;
    };
    net.layers
        .affine::<F>(1, data.x_row(first), &mut net.st.drive);
    for (k, &i) in order.iter().enumerate() {
        let next = order.get(k + 1).map(|&j| data.x_row(j));
        let stats = step::<F>(
            &mut net.layers,
            &mut net.st,
            data.x_row(i),
            data.y_row(i),
            cfg,
            next,
        );
        total.loss += stats.loss;
        total.energy += stats.energy;
    }
    let n = order.len() as f64;
    SampleStats {
        loss: total.loss / n,
        energy: total.energy / n,
    }
}
