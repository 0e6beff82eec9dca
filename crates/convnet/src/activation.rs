//! The rate function `phi` of the hidden units and its slope, the slope
//! taken from the rate itself (`phi' = phi (1 - phi)` for the sigmoid,
//! `1 - phi^2` for tanh, `[phi > 0]` for the rectifier), so a layer keeps
//! only its potentials and rates. The sigmoid and tanh are built on a
//! polynomial exponential that the compiler vectorises (the library's
//! `exp` and `tanh` are scalar calls, and cost as much as a layer's
//! matrix product), each built for AVX-512, AVX2 and the baseline
//! (`crate::simd`). [`settle`] is a layer's whole step after its product,
//! in one pass: bias, potentials and rates.
use crate::config::Activation;
use crate::simd::dispatched;

/// `e^x` (x clamped to +-87), relative error below 3e-7: `x = n ln 2 + f`
/// with `n` the nearest integer to `x / ln 2` and `|f| <= ln 2 / 2`
/// (`n ln 2` taken off in two parts, the first exact in f32, so `f` keeps
/// its digits); `e^f` by its Taylor series to degree 7 (remainder below
/// `(ln 2 / 2)^8 / 8! = 5e-9`); `2^n` written into the exponent bits, `n`
/// read as an integer from the low mantissa bits of `x / ln 2 + 1.5 *
/// 2^23` (a float-to-integer cast saturates, which the compiler does lane
/// by lane).
#[inline(always)]
pub(crate) fn exp_fast(x: f32) -> f32 {
    // 1.5 * 2^23: adding and subtracting it rounds to the nearest integer.
    const ROUND: f32 = 12_582_912.0;
    // ln 2 = LN2_HI + LN2_LO, LN2_HI with its low 12 mantissa bits zero.
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    let x = x.clamp(-87.0, 87.0);
    let shifted = x * std::f32::consts::LOG2_E + ROUND;
    // |n| <= 126, so the difference of the bit patterns is n itself.
    let n_int = shifted.to_bits() as i32 - ROUND.to_bits() as i32;
    let n = shifted - ROUND;
    let f = (x - n * LN2_HI) - n * LN2_LO;
    let p = 1.0
        + f * (1.0
            + f * (1.0 / 2.0
                + f * (1.0 / 6.0
                    + f * (1.0 / 24.0
                        + f * (1.0 / 120.0 + f * (1.0 / 720.0 + f * (1.0 / 5040.0)))))));
    p * f32::from_bits(((n_int + 127) as u32) << 23)
}

/// `tanh x = 1 - 2 / (e^(2x) + 1)` (exactly +-1 in f32 beyond +-10).
#[inline(always)]
pub(crate) fn tanh_fast(x: f32) -> f32 {
    1.0 - 2.0 / (exp_fast(2.0 * x.clamp(-10.0, 10.0)) + 1.0)
}

/// `1 / (1 + e^-x)`.
#[inline(always)]
pub(crate) fn sigmoid_fast(x: f32) -> f32 {
    1.0 / (1.0 + exp_fast(-x))
}

dispatched! {
    /// `out = phi(s)`, in the widest build the processor runs.
    fn apply_dispatched(activation: Activation, s: &[f32], out: &mut [f32]) => apply_portable;
}

dispatched! {
    /// `g *= phi'(s)` with `rate = phi(s)`, in the widest build.
    fn times_slope_dispatched(activation: Activation, rate: &[f32], g: &mut [f32]) => times_slope_portable;
}

#[inline(always)]
fn apply_portable(activation: Activation, s: &[f32], out: &mut [f32]) {
    match activation {
        Activation::Sigmoid => out
            .iter_mut()
            .zip(s)
            .for_each(|(o, &s)| *o = sigmoid_fast(s)),
        Activation::Tanh => out.iter_mut().zip(s).for_each(|(o, &s)| *o = tanh_fast(s)),
        Activation::Relu => out.iter_mut().zip(s).for_each(|(o, &s)| *o = s.max(0.0)),
    }
}

#[inline(always)]
pub(crate) fn times_slope_portable(activation: Activation, rate: &[f32], g: &mut [f32]) {
    match activation {
        Activation::Sigmoid => g
            .iter_mut()
            .zip(rate)
            .for_each(|(g, &p)| *g *= p * (1.0 - p)),
        Activation::Tanh => g.iter_mut().zip(rate).for_each(|(g, &p)| *g *= 1.0 - p * p),
        Activation::Relu => g
            .iter_mut()
            .zip(rate)
            .for_each(|(g, &p)| *g = if p > 0.0 { *g } else { 0.0 }),
    }
}

impl Activation {
    /// `out = phi(s)`.
    #[inline]
    pub(crate) fn apply(self, s: &[f32], out: &mut [f32]) {
        apply_dispatched(self, s, out)
    }

    /// `g *= phi'(s)`, with `rate = phi(s)`.
    #[inline]
    pub(crate) fn times_slope(self, rate: &[f32], g: &mut [f32]) {
        times_slope_dispatched(self, rate, g)
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

/// `out = phi(s)` for `activation` (for the bench: the rate step of a
/// layer's forward pass).
pub fn rates(activation: Activation, s: &[f32], out: &mut [f32]) {
    activation.apply(s, out);
}

/// `g *= phi'(s)` with `rate = phi(s)` (for the bench: the slope step of
/// a layer's down pass).
pub fn times_slope(activation: Activation, rate: &[f32], g: &mut [f32]) {
    activation.times_slope(rate, g);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_exponential_and_rates_match_the_library() {
        let mut worst = [0.0f64; 3];
        for i in -160_000..=160_000 {
            let x = i as f32 * 5e-4;
            let e = (exp_fast(x) as f64 - (x as f64).exp()).abs() / (x as f64).exp();
            let t = (tanh_fast(x) as f64 - (x as f64).tanh()).abs();
            let s = (sigmoid_fast(x) as f64 - 1.0 / (1.0 + (-x as f64).exp())).abs();
            for (w, v) in worst.iter_mut().zip([e, t, s]) {
                *w = w.max(v);
            }
        }
        assert!(worst[0] < 5e-7, "exp relative error {}", worst[0]);
        assert!(
            worst[1] < 5e-7 && worst[2] < 5e-7,
            "tanh, sigmoid: {worst:?}"
        );
        assert_eq!(tanh_fast(30.0), 1.0);
        assert_eq!(tanh_fast(-30.0), -1.0);
        assert!(exp_fast(-200.0) > 0.0 && exp_fast(200.0).is_finite());
    }

    #[test]
    fn dispatched_rates_and_slopes_equal_the_portable_ones_bit_for_bit() {
        let s: Vec<f32> = (-4000..4000).map(|i| i as f32 * 7e-3 + 1e-4).collect();
        let rate: Vec<f32> = s.iter().map(|v| (v * 0.2).sin()).collect();
        for act in [Activation::Sigmoid, Activation::Tanh, Activation::Relu] {
            let (mut a, mut b) = (vec![0.0; s.len()], vec![0.0; s.len()]);
            act.apply(&s, &mut a);
            apply_portable(act, &s, &mut b);
            assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
            let (mut g, mut h) = (s.clone(), s.clone());
            act.times_slope(&rate, &mut g);
            times_slope_portable(act, &rate, &mut h);
            assert!(g.iter().zip(&h).all(|(x, y)| x.to_bits() == y.to_bits()));
        }
    }
}
