//! The phases of one equilibrium-propagation step (report ch. 3.4, Algorithm
//! 1, with ERRATA.md's corrections): free phase, nudge, weakly clamped phase,
//! local weight update. Kept apart from the [`crate::DenNN`] type so the hot
//! loop reads top to bottom.
use crate::closed_form::{closed_form_outputs, step_one_output, step_two_outputs};
use crate::cost::nudge_targets;
use crate::deep_clamp::{clamp_linearised_deep, solve_in_place};
use crate::dennn::{ClampedPhase, EpConfig, FreePhase, LrScaling, SampleStats};
use crate::kernels::{dot, dot3, sigmoid, sum_squares_f64};
use crate::net::{Layers, States};

/// One EP step, given the first-layer drive `W(1)^T x + b(1)` in `st.drive`;
/// when `next` is given, leaves the next sample's drive there.
#[inline(always)]
pub(crate) fn step<const F: bool>(
    layers: &mut Layers,
    st: &mut States,
    x: &[f32],
    t: &[f32],
    cfg: &EpConfig,
    next: Option<&[f32]>,
) -> SampleStats {
    match closed_form_outputs(layers, cfg) {
        Some(1) => step_one_output::<F>(layers, st, x, t[0], cfg, next),
        Some(_) => step_two_outputs::<F>(layers, st, x, t, cfg, next),
        None => step_general::<F>(layers, st, x, t, cfg, next),
    }
}

/// [`step`] for any depth, width and phase method.
#[inline(always)]
pub(crate) fn step_general<const F: bool>(
    layers: &mut Layers,
    st: &mut States,
    x: &[f32],
    t: &[f32],
    cfg: &EpConfig,
    next: Option<&[f32]>,
) -> SampleStats {
    let n = layers.depth();
    let beta = cfg.beta as f32;
    let rates = LayerRates::of(cfg);
    match cfg.free_phase {
        FreePhase::FeedForward => {
            st.s[0].copy_from_slice(x);
            st.phi[0].copy_from_slice(x);
            st.s[1].copy_from_slice(&st.drive);
            layers.forward_from_drive::<F>(st);
        }
        FreePhase::Euler { n_i, dt } => free_euler::<F>(layers, st, x, n_i, dt as f32),
    }
    let mut loss = 0.0f64;
    for (&y, &t) in st.s[n].iter().zip(t) {
        loss += 0.5 * ((y - t) as f64).powi(2);
    }
    // The cost enters through the nudge alone: `t` in the squared cost's.
    let nudge_to = nudge_targets(cfg.cost.as_ref(), &st.s[n], t);
    let t = &*nudge_to;
    for ((yn, &y), &t) in st.nudged.iter_mut().zip(&st.s[n]).zip(t) {
        *yn = y + beta * (t - y);
    }
    match cfg.clamped_phase {
        ClampedPhase::Linearised if n == 2 && !layers.is_row_major(2) => {
            clamp_linearised::<F>(layers, st, t, beta)
        }
        ClampedPhase::Linearised => clamp_linearised_deep::<F>(layers, st, t, beta),
        ClampedPhase::Euler { n_i, dt } => clamp_euler::<F>(layers, st, n_i, dt as f32),
    }
    let mut energy = 0.5
        * cfg.beta
        * st.nudged
            .iter()
            .zip(t)
            .map(|(y, t)| ((y - t) as f64).powi(2))
            .sum::<f64>();
    for e in &st.e[1..] {
        energy += 0.5 * sum_squares_f64(e);
    }
    update::<F>(layers, st, rates, next);
    SampleStats { loss, energy }
}

/// The learning rates `eta` of eq. 3.21 for each layer: `hidden` for the
/// layers feeding hidden units, `output` for the output layer, both applied
/// per layer as `scaling` says.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LayerRates {
    hidden: f32,
    output: f32,
    scaling: LrScaling,
}

impl LayerRates {
    /// `output` defaults to `hidden` (the report's single rate).
    pub fn new(hidden: f64, output: Option<f64>, scaling: LrScaling) -> Self {
        LayerRates {
            hidden: hidden as f32,
            output: output.unwrap_or(hidden) as f32,
            scaling,
        }
    }

    /// The rates of an EP configuration.
    pub fn of(cfg: &EpConfig) -> Self {
        Self::new(cfg.learning_rate, cfg.output_learning_rate, cfg.lr_scaling)
    }

    /// The rate of layer `l` (1-based) of `layers`.
    #[inline(always)]
    pub(crate) fn rate(&self, layers: &Layers, l: usize) -> f32 {
        let eta = if l == layers.depth() {
            self.output
        } else {
            self.hidden
        };
        self.scaling.rate(eta, layers.sizes[l - 1])
    }
}

/// Eqs. 3.21-3.22 with ERRATA signs: `W(l) += eta phi(s(l-1)) e(l)^T`,
/// `b(l) += eta e(l)`, presynaptic activity taken from `st.phi`, `eta` per
/// layer from `rates`. With `next`, the first layer's update is fused with
/// the next sample's drive.
#[inline(always)]
pub(crate) fn update<const F: bool>(
    layers: &mut Layers,
    st: &mut States,
    rates: LayerRates,
    next: Option<&[f32]>,
) {
    for l in (1..=layers.depth()).rev() {
        let eta = rates.rate(layers, l);
        let scaled = &mut st.tmp[l];
        scaled
            .iter_mut()
            .zip(&st.e[l])
            .for_each(|(s, e)| *s = eta * e);
        match next {
            Some(next) if l == 1 => {
                layers.rank1_then_drive::<F>(&st.phi[0], (scaled, 1.0), next, &mut st.drive)
            }
            _ => layers.rank1::<F>(l, &st.phi[l - 1], (scaled, 1.0)),
        }
    }
}

/// Closed-form weakly clamped equilibrium of a one-hidden-layer net,
/// linearised about the free state (see [`ClampedPhase::Linearised`]).
/// Leaves `e(1)`, `e(2)` and the clamped presynaptic `phi(s(1))` in `st`.
#[inline(always)]
fn clamp_linearised<const F: bool>(layers: &Layers, st: &mut States, t: &[f32], beta: f32) {
    // The output layer is narrow, so `w2` is stored transposed (`k x d(1)`).
    let (w2, k) = (&layers.w[1], layers.sizes[2]);
    let [_, d, rhs] = &mut st.tmp[..] else { return };
    let [_, e1, e2] = &mut st.e[..] else { return };
    // d_i = phi'(h_i) = phi (1 - phi).
    d.iter_mut()
        .zip(&st.phi[1])
        .for_each(|(d, p)| *d = p * (1.0 - p));
    rhs.iter_mut()
        .zip(&st.s[2])
        .zip(t)
        .for_each(|((r, y), t)| *r = beta * (t - y));
    if k == 1 {
        // u = D W2, a = ||u||^2, e2 = beta (t - y) / (1 + a), e1 = u e2.
        e1.iter_mut()
            .zip(d.iter())
            .zip(w2)
            .for_each(|((u, d), w)| *u = d * w);
        let a = dot::<F>(e1, e1);
        e2[0] = rhs[0] / (1.0 + a);
        let e = e2[0];
        e1.iter_mut().for_each(|u| *u *= e);
    } else {
        solve_output_error::<F>(w2, d, &mut st.scratch, rhs, e2, &mut st.system);
        layers.back::<F>(2, e2, e1);
        e1.iter_mut().zip(d.iter()).for_each(|(e, d)| *e *= d);
    }
    // Clamped presynaptic activity, linearised: phi(h + e1) ~ phi(h) + D e1.
    for ((p, d), e) in st.phi[1].iter_mut().zip(d.iter()).zip(e1.iter()) {
        *p += d * e;
    }
    st.s[1].iter_mut().zip(e1.iter()).for_each(|(s, e)| *s += e);
    st.s[2].copy_from_slice(&st.nudged);
}

/// Solve `(I + W2^T D^2 W2) e2 = rhs` for `k` outputs (`w2` stored `k x h`;
/// Gaussian elimination in f64 on the small SPD system). `d2` holds
/// `phi'(h)^2` on return.
#[inline(always)]
fn solve_output_error<const F: bool>(
    w2: &[f32],
    d: &[f32],
    d2: &mut [f32],
    rhs: &[f32],
    e2: &mut [f32],
    system: &mut [f64],
) {
    let (k, h) = (e2.len(), d.len());
    let (a, b) = system.split_at_mut(k * k);
    d2.iter_mut().zip(d).for_each(|(q, d)| *q = d * d);
    for p in 0..k {
        for q in p..k {
            let v = dot3::<F>(&w2[p * h..(p + 1) * h], &w2[q * h..(q + 1) * h], d2) as f64;
            a[p * k + q] = v + if p == q { 1.0 } else { 0.0 };
            a[q * k + p] = a[p * k + q];
        }
    }
    b.iter_mut().zip(rhs).for_each(|(b, &r)| *b = r as f64);
    solve_in_place(a, b, k);
    e2.iter_mut()
        .zip(b.iter())
        .for_each(|(e, b)| *e = *b as f32);
}

/// The report's free phase: `n_i` Euler steps of eq. 3.12 from zero potentials.
#[inline(always)]
fn free_euler<const F: bool>(layers: &Layers, st: &mut States, x: &[f32], n_i: usize, dt: f32) {
    st.s[0].copy_from_slice(x);
    st.phi[0].copy_from_slice(x);
    for l in 1..st.s.len() {
        st.s[l].iter_mut().for_each(|s| *s = 0.0);
        st.phi[l].iter_mut().for_each(|p| *p = 0.5);
    }
    for _ in 0..n_i {
        euler_step::<F>(layers, st, dt, false);
    }
    errors::<F>(layers, st);
}

/// Weakly clamped phase by Euler: output held at `y_nudged`, hidden layers
/// relaxed `n_i` steps from the free state.
#[inline(always)]
fn clamp_euler<const F: bool>(layers: &Layers, st: &mut States, n_i: usize, dt: f32) {
    let n = layers.depth();
    st.s[n].copy_from_slice(&st.nudged);
    for _ in 0..n_i {
        euler_step::<F>(layers, st, dt, true);
    }
    errors::<F>(layers, st);
}

/// `e(l) = s(l) - (W(l)^T phi(s(l-1)) + b(l))` for every layer.
#[inline(always)]
fn errors<const F: bool>(layers: &Layers, st: &mut States) {
    for l in 1..=layers.depth() {
        if l == 1 {
            st.tmp[1].copy_from_slice(&st.drive);
        } else {
            layers.affine::<F>(l, &st.phi[l - 1], &mut st.tmp[l]);
        }
        for ((e, s), f) in st.e[l].iter_mut().zip(&st.s[l]).zip(&st.tmp[l]) {
            *e = s - f;
        }
    }
}

/// One Euler step of eq. 3.12 (ERRATA form):
/// `ds(l) = -e(l) + phi'(s(l)) . W(l+1) e(l+1)`, simultaneously for all
/// layers; the output layer is skipped when `clamp_output`.
#[inline(always)]
fn euler_step<const F: bool>(layers: &Layers, st: &mut States, dt: f32, clamp_output: bool) {
    let n = layers.depth();
    errors::<F>(layers, st);
    let last = if clamp_output { n - 1 } else { n };
    for l in 1..=last {
        if l < n {
            let (lower, upper) = st.e.split_at_mut(l + 1);
            layers.back::<F>(l + 1, &upper[0], &mut st.tmp[l]);
            for (((s, e), g), p) in st.s[l]
                .iter_mut()
                .zip(&lower[l])
                .zip(&st.tmp[l])
                .zip(&st.phi[l])
            {
                *s += dt * (-e + p * (1.0 - p) * g);
            }
        } else {
            st.s[l]
                .iter_mut()
                .zip(&st.e[l])
                .for_each(|(s, e)| *s -= dt * e);
        }
    }
    for l in 1..n {
        let (s, phi) = (&st.s[l], &mut st.phi[l]);
        sigmoid::<F>(s, phi);
    }
}
