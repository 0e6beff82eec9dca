//! The rate function `phi` of the hidden units and its slope, the slope
//! taken from the rate itself (`phi' = phi (1 - phi)` for the sigmoid,
//! `1 - phi^2` for tanh, `[phi > 0]` for the rectifier), so a layer keeps
//! only its potentials and rates.
use crate::config::Activation;

impl Activation {
    /// `out = phi(s)`.
    #[inline]
    pub(crate) fn apply(self, s: &[f32], out: &mut [f32]) {
        match self {
            Activation::Sigmoid => out
                .iter_mut()
                .zip(s)
                .for_each(|(o, &s)| *o = 1.0 / (1.0 + (-s).exp())),
            Activation::Tanh => out.iter_mut().zip(s).for_each(|(o, &s)| *o = s.tanh()),
            Activation::Relu => out.iter_mut().zip(s).for_each(|(o, &s)| *o = s.max(0.0)),
        }
    }

    /// `g *= phi'(s)`, with `rate = phi(s)`.
    #[inline]
    pub(crate) fn times_slope(self, rate: &[f32], g: &mut [f32]) {
        match self {
            Activation::Sigmoid => g
                .iter_mut()
                .zip(rate)
                .for_each(|(g, &p)| *g *= p * (1.0 - p)),
            Activation::Tanh => g.iter_mut().zip(rate).for_each(|(g, &p)| *g *= 1.0 - p * p),
            Activation::Relu => g.iter_mut().zip(rate).for_each(|(g, &p)| {
                if p <= 0.0 {
                    *g = 0.0
                }
            }),
        }
    }

    /// The initialisation gain: weights are uniform in
    /// `+-sqrt(3 gain / fan_in)`, variance `gain / fan_in` (He et al. 2015
    /// for the rectifier, LeCun for the others).
    pub(crate) fn init_gain(self) -> f32 {
        match self {
            Activation::Relu => 2.0,
            Activation::Sigmoid | Activation::Tanh => 1.0,
        }
    }
}
