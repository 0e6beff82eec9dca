//! Equilibrium propagation in the convolutional dendritic network
//! (Scellier and Bengio 2017; symmetric nudging after Laborieux et al.
//! 2021), and the backprop gradient of its twin.
//!
//! Energy of a frame, layers `l = 1..L`, `s(0) = x` held at the input:
//! `E = 1/2 sum_l ||e(l)||^2`, `e(l) = s(l) - W(l) * phi(s(l-1)) - b(l)`;
//! cost `C = 1/2 ||s(L) - t||^2`; total `F = E + beta C`. Its stationary
//! points satisfy
//! - `e(l) = phi'(s(l)) . W(l+1)^T e(l+1)` below the output (S1),
//! - `e(L) = beta (t - p(L)) / (1 + beta)` at the output (S2).
//!
//! With no target (`beta = 0`) every error vanishes: the free equilibrium
//! is the feed-forward pass. The EP estimate of `dC/dtheta` at the free
//! equilibrium is `(dF/dtheta(s+) - dF/dtheta(s-)) / (2 beta)` with `s+-`
//! the equilibria at `+-beta` (symmetric), or `(dF/dtheta(s+) -
//! dF/dtheta(s0)) / beta` (one-sided; `dF/dtheta(s0) = 0` here), where
//! `dF/dW(l) = -e(l) phi(s(l-1))^T` and `dF/db(l) = -e(l)`.
use crate::config::{ClampedPhase, EpSettings, FreePhase, Nudging};
use crate::network::Network;
use crate::pass::{
    accumulate_gradient, feed_forward, output_loss, predict_layer, send_down, settle_layer,
};
use crate::workspace::Workspace;

/// The EP estimate of the loss gradient over the chunk's frames, added to
/// `ws.grad`; returns the chunk's summed loss `0.5 ||y - t||^2` at the
/// free equilibrium.
pub(crate) fn ep_gradient(net: &Network, ws: &mut Workspace, nb: usize, ep: &EpSettings) -> f64 {
    free_phase(net, ws, nb, ep.free_phase);
    let loss = output_loss(net, ws, nb);
    let beta = ep.beta as f32;
    match ep.nudging {
        Nudging::Positive => {
            clamped_phase(net, ws, nb, beta, ep.clamped_phase);
            accumulate_gradient(net, ws, nb, -1.0 / beta);
        }
        Nudging::Symmetric => {
            ws.save();
            clamped_phase(net, ws, nb, beta, ep.clamped_phase);
            accumulate_gradient(net, ws, nb, -0.5 / beta);
            ws.restore();
            clamped_phase(net, ws, nb, -beta, ep.clamped_phase);
            accumulate_gradient(net, ws, nb, 0.5 / beta);
        }
    }
    loss
}

/// The backprop gradient of `0.5 ||y - t||^2` over the chunk's frames,
/// added to `ws.grad`; returns the summed loss. The deltas use the error
/// buffers: `e(L) = y - t`, `e(l) = phi'(s(l)) . W(l+1)^T e(l+1)`.
pub(crate) fn backprop_gradient(net: &Network, ws: &mut Workspace, nb: usize) -> f64 {
    feed_forward(net, ws, nb);
    let loss = output_loss(net, ws, nb);
    let last = net.layout.depth() - 1;
    let len = net.layout.outputs() * nb;
    let (e, s, t) = (&mut ws.e[last], &ws.s[last], &ws.t);
    for ((e, s), t) in e[..len].iter_mut().zip(&s[..len]).zip(&t[..len]) {
        *e = s - t;
    }
    for l in (1..=last).rev() {
        send_down(net, ws, nb, l, false);
    }
    accumulate_gradient(net, ws, nb, 1.0);
    loss
}

/// The free phase: the feed-forward pass, or Euler steps from zero
/// potentials.
pub(crate) fn free_phase(net: &Network, ws: &mut Workspace, nb: usize, phase: FreePhase) {
    match phase {
        FreePhase::FeedForward => feed_forward(net, ws, nb),
        FreePhase::Euler { steps, dt } => {
            for l in 0..net.layout.depth() {
                ws.s[l].fill(0.0);
                if l + 1 < net.layout.depth() {
                    let (s, a) = (&ws.s[l], &mut ws.a[l]);
                    net.activation.apply(s, a);
                }
            }
            for _ in 0..steps {
                euler_step(net, ws, nb, 0.0, dt as f32);
            }
            consistent_errors(net, ws, nb);
        }
    }
}

/// A weakly clamped phase at (signed) `beta` from the current state.
pub(crate) fn clamped_phase(
    net: &Network,
    ws: &mut Workspace,
    nb: usize,
    beta: f32,
    phase: ClampedPhase,
) {
    match phase {
        ClampedPhase::Sweeps { iterations } => {
            for _ in 0..iterations {
                sweep(net, ws, nb, beta);
            }
        }
        ClampedPhase::Euler { steps, dt } => {
            for _ in 0..steps {
                euler_step(net, ws, nb, beta, dt as f32);
            }
            consistent_errors(net, ws, nb);
        }
    }
}

/// One round of the two local sweeps. Top-down: the output's error from
/// S2 at the current prediction, then each layer's from S1 at its current
/// rate. Bottom-up: each layer's prediction from the layer below as it now
/// is, and `s(l) = p(l) + e(l)`. Afterwards `e(l) = s(l) - p(l)` holds
/// exactly; S1 and S2 hold up to the change of `phi'` and `p(L)` the
/// bottom-up sweep made (second order in beta).
pub(crate) fn sweep(net: &Network, ws: &mut Workspace, nb: usize, beta: f32) {
    let last = net.layout.depth() - 1;
    let len = net.layout.outputs() * nb;
    let k = beta / (1.0 + beta);
    let (e, p, t) = (&mut ws.e[last], &ws.p[last], &ws.t);
    for ((e, p), t) in e[..len].iter_mut().zip(&p[..len]).zip(&t[..len]) {
        *e = k * (t - p);
    }
    for l in (1..=last).rev() {
        send_down(net, ws, nb, l, false);
    }
    for l in 0..=last {
        settle_layer(net, ws, nb, l);
    }
}

/// One simultaneous Euler step of `ds/dt = -dF/ds`:
/// `s(l) += dt (-e(l) + phi'(s(l)) . W(l+1)^T e(l+1))`, and at the output
/// `s(L) += dt (-e(L) + beta (t - s(L)))`.
pub(crate) fn euler_step(net: &Network, ws: &mut Workspace, nb: usize, beta: f32, dt: f32) {
    consistent_errors(net, ws, nb);
    let last = net.layout.depth() - 1;
    for l in 1..=last {
        send_down(net, ws, nb, l, true);
    }
    for l in 0..=last {
        let len = net.layout.layers[l].out_len() * nb;
        let (s, e) = (&mut ws.s[l][..len], &ws.e[l][..len]);
        if l == last {
            for ((s, e), t) in s.iter_mut().zip(e).zip(&ws.t[..len]) {
                *s += dt * (-e + beta * (t - *s));
            }
        } else {
            for ((s, e), g) in s.iter_mut().zip(e).zip(&ws.down[l][..len]) {
                *s += dt * (-e + g);
            }
            net.activation.apply(s, &mut ws.a[l][..len]);
        }
    }
}

/// Recompute every prediction from the current states and `e = s - p`.
pub(crate) fn consistent_errors(net: &Network, ws: &mut Workspace, nb: usize) {
    for l in 0..net.layout.depth() {
        predict_layer(net, ws, nb, l);
        let len = net.layout.layers[l].out_len() * nb;
        let (e, s, p) = (&mut ws.e[l][..len], &ws.s[l][..len], &ws.p[l][..len]);
        e.iter_mut()
            .zip(s.iter().zip(p))
            .for_each(|(e, (s, p))| *e = s - p);
    }
}

/// `F = 1/2 sum_l ||e(l)||^2 + beta/2 ||s(L) - t||^2` summed over the
/// chunk, with the errors as they are in `ws`.
pub(crate) fn total_energy(net: &Network, ws: &Workspace, nb: usize, beta: f32) -> f64 {
    let mut total = beta as f64 * output_loss(net, ws, nb);
    for (l, shape) in net.layout.layers.iter().enumerate() {
        let len = shape.out_len() * nb;
        total += 0.5
            * ws.e[l][..len]
                .iter()
                .map(|&e| (e as f64).powi(2))
                .sum::<f64>();
    }
    total
}

/// `||dF/ds||`, the distance from a stationary point, with the errors as
/// they are in `ws` (uses the top-down buffers).
pub(crate) fn stationarity(net: &Network, ws: &mut Workspace, nb: usize, beta: f32) -> f64 {
    let last = net.layout.depth() - 1;
    for l in 1..=last {
        send_down(net, ws, nb, l, true);
    }
    let mut sum = 0.0f64;
    for l in 0..=last {
        let len = net.layout.layers[l].out_len() * nb;
        for j in 0..len {
            let r = if l == last {
                ws.e[l][j] + beta * (ws.s[l][j] - ws.t[j])
            } else {
                ws.e[l][j] - ws.down[l][j]
            };
            sum += (r as f64).powi(2);
        }
    }
    sum.sqrt()
}
