//! The training cost of one target ([`Cost`]): the squared cost of eq.
//! 3.16 (the default, aiming at the conditional mean), or a cost that
//! grows like the absolute error far from the target (log-cosh, Huber),
//! which aims nearer the conditional median, what a mean absolute error
//! rewards.
//!
//! With the residual `r = y - t` of an output (in the net's scaled units),
//! the cost `C(r)` enters equilibrium propagation only through the nudge:
//! the weakly clamped phase holds the output at `y - beta C'(r)` in place
//! of `y + beta (t - y)` (docs/learning.md, "The cost"), and the backprop
//! twin's output error is `-C'(r)` in place of `t - y`. Both are the
//! squared cost's with the target `t` replaced by `y - C'(r)`, which is
//! how [`nudge_target`] hooks in. The costs and their slopes, with the
//! scale `a`:
//!
//! - squared: `C = r^2 / 2`, `C' = r`;
//! - log-cosh: `C = a^2 ln cosh(r / a)`, `C' = a tanh(r / a)`: `r^2 / 2`
//!   for `|r| << a`, `a |r|` (less a constant) for `|r| >> a`;
//! - Huber: `C = r^2 / 2` for `|r| <= a`, else `a (|r| - a / 2)`;
//!   `C' = clamp(r, -a, a)`.
//!
//! Both tend to the squared cost as `a` grows (the slope exactly, not
//! scaled), so a large scale is today's training.
use crate::error::LearnError;
use crate::targets::{linear_column, ModelTarget};
use serde::{Deserialize, Serialize};

/// Which cost ([`Cost::kind`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CostKind {
    /// `r^2 / 2` (eq. 3.16): the default.
    Squared,
    /// `a^2 ln cosh(r / a)`.
    LogCosh,
    /// `r^2 / 2` within `a`, linear beyond.
    Huber,
}

/// The cost of one target in training (`[cost]` of a model's
/// configuration); the other targets keep the squared cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cost {
    /// The cost.
    pub kind: CostKind,
    /// The target it applies to (a dataset's target name, e.g. `pose_2`;
    /// the edge task's `r`); not a circular one.
    pub target: String,
    /// The scale `a`, in the target's unit (mm or deg): residuals well
    /// under it cost as the squared cost, those above it about linearly.
    /// Ignored by `squared`.
    pub scale: f64,
}

impl Cost {
    /// Check the scale: finite and positive.
    pub fn validate(&self) -> Result<(), LearnError> {
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(cost_err(format!(
                "scale {} must be finite and above 0",
                self.scale
            )));
        }
        Ok(())
    }

    /// The cost as a net sees it: the output of the net that predicts
    /// encoded columns `cols` (of targets `outputs`, scaled by `std`
    /// column by column) that carries the target, with the scale in the
    /// net's units. `None` when the net does not predict the target or the
    /// cost is the squared one (today's training, unchanged). Error when
    /// the target is not one of `outputs` or is circular.
    pub(crate) fn for_net(
        &self,
        outputs: &[ModelTarget],
        cols: &[usize],
        std: &[f64],
    ) -> Result<Option<NetCost>, LearnError> {
        let column = self.column(outputs)?;
        let Some(output) = cols.iter().position(|&c| c == column) else {
            return Ok(None);
        };
        if self.kind == CostKind::Squared {
            return Ok(None);
        }
        Ok(Some(NetCost {
            output,
            kind: self.kind,
            scale: (self.scale / std[column]) as f32,
        }))
    }

    /// The encoded column of the cost's target.
    fn column(&self, outputs: &[ModelTarget]) -> Result<usize, LearnError> {
        let why = "its sine and cosine keep the squared cost";
        linear_column(outputs, &self.target, why).map_err(cost_err)
    }
}

/// A cost on one output of a net, its scale in the net's (scaled) units
/// ([`crate::EpConfig::cost`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NetCost {
    /// The output (from 0) the cost applies to; the others: squared.
    pub output: usize,
    /// The cost.
    pub kind: CostKind,
    /// The scale `a` in the output's units.
    pub scale: f32,
}

impl NetCost {
    /// `C'(r)`, the slope of the cost at the residual `r = y - t`.
    pub fn slope(&self, r: f32) -> f32 {
        let a = self.scale;
        match self.kind {
            CostKind::Squared => r,
            CostKind::LogCosh => a * (r / a).tanh(),
            CostKind::Huber => r.clamp(-a, a),
        }
    }

    /// `C(r)`, the cost at the residual `r = y - t` (f64: for checks).
    pub fn value(&self, r: f64) -> f64 {
        let a = f64::from(self.scale);
        match self.kind {
            CostKind::Squared => 0.5 * r * r,
            // ln cosh z = |z| + ln(1 + e^(-2|z|)) - ln 2, stable for large |z|.
            CostKind::LogCosh => {
                let z = (r / a).abs();
                a * a * (z + (-2.0 * z).exp().ln_1p() - std::f64::consts::LN_2)
            }
            CostKind::Huber if r.abs() <= a => 0.5 * r * r,
            CostKind::Huber => a * (r.abs() - 0.5 * a),
        }
    }
}

/// The target output `p` is nudged toward: `t` itself under the squared
/// cost (bit for bit), else `y - C'(y - t)`, so that the squared cost's
/// nudge `beta (t' - y)` is `-beta C'(y - t)` (eq. 3.16's gradient with
/// the cost in place of `(y - t)^2 / 2`).
#[inline(always)]
pub(crate) fn nudge_target(cost: Option<&NetCost>, p: usize, y: f32, t: f32) -> f32 {
    match cost {
        Some(c) if c.output == p => y - c.slope(y - t),
        _ => t,
    }
}

/// [`nudge_target`] of every output: `t` itself (borrowed) unless a cost
/// applies.
pub(crate) fn nudge_targets<'a>(
    cost: Option<&NetCost>,
    y: &[f32],
    t: &'a [f32],
) -> std::borrow::Cow<'a, [f32]> {
    match cost {
        None => std::borrow::Cow::Borrowed(t),
        Some(_) => (y.iter().zip(t).enumerate())
            .map(|(p, (&y, &t))| nudge_target(cost, p, y, t))
            .collect(),
    }
}

fn cost_err(reason: String) -> LearnError {
    LearnError::Config {
        field: "cost",
        reason,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cost(kind: CostKind, scale: f32) -> NetCost {
        NetCost {
            output: 0,
            kind,
            scale,
        }
    }

    /// The slope is the cost's derivative (central differences).
    #[test]
    fn slope_is_the_derivative_of_the_cost() {
        for kind in [CostKind::Squared, CostKind::LogCosh, CostKind::Huber] {
            let c = cost(kind, 0.3);
            for r in [-2.0f32, -0.31, -0.1, 0.0, 0.05, 0.29, 0.7, 3.0] {
                let h = 1e-5;
                let d = (c.value(f64::from(r) + h) - c.value(f64::from(r) - h)) / (2.0 * h);
                assert!((d - f64::from(c.slope(r))).abs() < 1e-5, "{kind:?} at {r}");
            }
        }
    }

    /// Far out, log-cosh and Huber grow like `a |r|`; near 0 like `r^2 / 2`.
    #[test]
    fn robust_costs_are_quadratic_near_and_linear_far() {
        for kind in [CostKind::LogCosh, CostKind::Huber] {
            let c = cost(kind, 0.5);
            assert!((c.value(0.01) - 0.5e-4).abs() < 1e-8, "{kind:?}");
            let far = c.value(101.0) - c.value(100.0);
            assert!((far - 0.5).abs() < 1e-6, "{kind:?}: {far}");
            assert!((c.slope(50.0) - 0.5).abs() < 1e-6);
        }
    }

    /// The squared cost and an absent one nudge toward `t` itself.
    #[test]
    fn squared_cost_nudges_toward_the_target_itself() {
        let (y, t) = (0.123_456_7f32, -1.234_567f32);
        assert_eq!(nudge_target(None, 0, y, t).to_bits(), t.to_bits());
        let huber = cost(CostKind::Huber, 0.5);
        assert_eq!(nudge_target(Some(&huber), 1, y, t).to_bits(), t.to_bits());
        assert_eq!(nudge_target(Some(&huber), 0, y, t), y - 0.5);
    }
}
