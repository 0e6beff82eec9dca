//! Adam (Kingma and Ba 2015) on the parameters, fed by either learning
//! rule's gradient (the backprop gradient or its EP estimate): per-weight
//! running means of the gradient and its square, bias-corrected. Each
//! weight's state is its own, so the rule stays local.
use crate::layout::Layout;
use crate::params::Parameters;

const BETA1: f64 = 0.9;
const BETA2: f64 = 0.999;
const EPSILON: f64 = 1e-8;

/// The optimiser's state.
#[derive(Debug, Clone)]
pub(crate) struct Adam {
    m: Parameters,
    v: Parameters,
    steps: i32,
}

impl Adam {
    /// Zero moments for `layout`.
    pub fn new(layout: &Layout) -> Self {
        Adam {
            m: Parameters::zeros(layout),
            v: Parameters::zeros(layout),
            steps: 0,
        }
    }

    /// One step along the mean gradient `grad`, of size `lr * factor(l)`
    /// on layer `l` (0-based), with L2 penalty `decay` on the weights (not
    /// the biases).
    pub fn step_layers(
        &mut self,
        params: &mut Parameters,
        grad: &Parameters,
        (lr, decay): (f64, f64),
        factor: impl Fn(usize) -> f64,
    ) {
        self.steps = self.steps.saturating_add(1);
        let c1 = 1.0 - BETA1.powi(self.steps);
        let c2 = 1.0 - BETA2.powi(self.steps);
        let lr_t = lr * c2.sqrt() / c1;
        let eps = (EPSILON * c2.sqrt()) as f32;
        let (b1, b2) = (BETA1 as f32, BETA2 as f32);
        let tensors = params
            .values_mut()
            .zip(grad.values())
            .zip(self.m.values_mut().zip(self.v.values_mut()));
        for (k, ((p, g), (m, v))) in tensors.enumerate() {
            let wd = if k % 2 == 0 { decay as f32 } else { 0.0 };
            let lr_t = (lr_t * factor(k / 2)) as f32;
            for (((p, &g), m), v) in p.iter_mut().zip(g).zip(m.iter_mut()).zip(v.iter_mut()) {
                let g = g + wd * *p;
                *m = b1 * *m + (1.0 - b1) * g;
                *v = b2 * *v + (1.0 - b2) * g * g;
                *p -= lr_t * *m / (v.sqrt() + eps);
            }
        }
    }
}
