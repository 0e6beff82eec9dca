//! The backprop twin of the dendritic network: same layers, same
//! initialisation, plain per-sample SGD on `0.5 ||y - t||^2` (or another
//! cost on an output, [`crate::NetCost`]). It is the
//! baseline the DenNN must match (report ch. 3.2).
use crate::cost::{nudge_target, NetCost};
use crate::dennn::{check_dims, LrScaling};
use crate::ep::{update, LayerRates};
use crate::error::LearnError;
use crate::net::{has_fma, Layers, States};

/// A fully connected network trained by error backpropagation.
#[derive(Debug, Clone)]
pub struct Mlp {
    layers: Layers,
    st: States,
    lr_scaling: LrScaling,
    output_lr: Option<f64>,
    cost: Option<NetCost>,
}

impl Mlp {
    /// Random weights from `seed` (identical to `DenNN::new(sizes, seed)`).
    pub fn new(sizes: &[usize], seed: u64) -> Result<Self, LearnError> {
        Ok(Self::from_layers(Layers::new(sizes, seed)?))
    }

    /// Wrap existing parameters.
    pub fn from_layers(layers: Layers) -> Self {
        let st = States::new(&layers.sizes);
        Mlp {
            layers,
            st,
            lr_scaling: LrScaling::None,
            output_lr: None,
            cost: None,
        }
    }

    /// Apply the learning rate per layer as `scaling` says (default: the
    /// same rate everywhere), exactly as the EP twin does.
    pub fn with_lr_scaling(mut self, scaling: LrScaling) -> Self {
        self.lr_scaling = scaling;
        self
    }

    /// Train the output layer with its own rate (default: the rate given to
    /// [`Mlp::train_sample`]), as [`crate::EpConfig::output_learning_rate`].
    pub fn with_output_learning_rate(mut self, lr: Option<f64>) -> Self {
        self.output_lr = lr;
        self
    }

    /// As [`Mlp::with_output_learning_rate`], in place (an annealed rate).
    pub(crate) fn set_output_learning_rate(&mut self, lr: Option<f64>) {
        self.output_lr = lr;
    }

    /// Train on `cost` in place of the squared cost on its output (as
    /// [`crate::EpConfig::cost`]): the output error is `-C'(y - t)`.
    pub fn with_cost(mut self, cost: Option<NetCost>) -> Self {
        self.cost = cost;
        self
    }

    /// The parameters.
    pub fn layers(&self) -> &Layers {
        &self.layers
    }

    /// Feed-forward prediction into `out`; wrong lengths are errors.
    pub fn predict(&self, x: &[f32], out: &mut [f32]) -> Result<(), LearnError> {
        self.layers.predict(x, out)
    }

    /// One SGD step with learning rate `lr`; returns `0.5 ||y - t||^2`
    /// before the step.
    pub fn train_sample(&mut self, x: &[f32], t: &[f32], lr: f64) -> Result<f64, LearnError> {
        check_dims(&self.layers, x, t)?;
        if has_fma() {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: the CPU supports AVX2 and FMA (checked just above).
            return Ok(unsafe { train_fma(self, x, t, lr) });
        }
        Ok(train_impl::<false>(self, x, t, lr))
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn train_fma(net: &mut Mlp, x: &[f32], t: &[f32], lr: f64) -> f64 {
    train_impl::<true>(net, x, t, lr)
}

/// Forward pass, output error `t - y` (the negative loss gradient; `-C'(y -
/// t)` under another cost), deltas
/// `e(l) = phi'(s(l)) . W(l+1) e(l+1)`, then the same rank-one update as EP.
#[inline(always)]
fn train_impl<const F: bool>(net: &mut Mlp, x: &[f32], t: &[f32], lr: f64) -> f64 {
    let Mlp {
        layers,
        st,
        lr_scaling,
        output_lr,
        cost,
    } = net;
    let n = layers.depth();
    layers.forward::<F>(x, st);
    let mut loss = 0.0f64;
    for (p, ((e, &y), &t)) in st.e[n].iter_mut().zip(&st.s[n]).zip(t).enumerate() {
        loss += 0.5 * ((y - t) as f64).powi(2);
        *e = nudge_target(cost.as_ref(), p, y, t) - y;
    }
    for l in (1..n).rev() {
        let (lower, upper) = st.e.split_at_mut(l + 1);
        layers.back::<F>(l + 1, &upper[0], &mut lower[l]);
        lower[l]
            .iter_mut()
            .zip(&st.phi[l])
            .for_each(|(e, p)| *e *= p * (1.0 - p));
    }
    update::<F>(
        layers,
        st,
        LayerRates::new(lr, *output_lr, *lr_scaling),
        None,
    );
    loss
}
