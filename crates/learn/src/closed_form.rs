//! The EP step of a one-hidden-layer net with one or two outputs (the
//! PDenNN's nets, the PCADenNN and the DisDenNN) with the feed-forward free
//! phase and the closed-form clamped phase, in three passes over the hidden
//! layer plus the fused first-layer sweep, instead of the general step's
//! dozen: the exact free phase (`phi = sigmoid(drive)`, `y = W2^T phi + b2`),
//! the nudge, the linearised clamped phase (`A = W2^T D^2 W2` with
//! `D = diag(phi')`, `(I + A) e2 = beta (t - y)`, `e1 = D W2 e2`), the energy
//! (eq. 3.17) and the update (eqs. 3.21-3.22); a cost other than the
//! squared one moves the target the output is nudged toward
//! ([`crate::NetCost`]). Every pass stores as little
//! as it can (stores, not arithmetic, bound them on the machine measured,
//! docs/learning.md "Speed"). Tested against the general step.
use crate::cost::nudge_target;
use crate::dennn::{ClampedPhase, EpConfig, FreePhase, SampleStats};
use crate::ep::LayerRates;
use crate::kernels::{madd, reduce, sigmoid, LANES};
use crate::net::{Layers, States};

/// How many outputs the closed-form step handles for this net and
/// configuration (1 or 2), or `None` for the general step.
#[inline(always)]
pub(crate) fn closed_form_outputs(layers: &Layers, cfg: &EpConfig) -> Option<usize> {
    let k = *layers.sizes.last()?;
    let applies = layers.depth() == 2
        && (k == 1 || k == 2)
        && !layers.is_row_major(2)
        && cfg.free_phase == FreePhase::FeedForward
        && cfg.clamped_phase == ClampedPhase::Linearised;
    applies.then_some(k)
}

/// One output: `a = sum u_i^2` with the gains `u = D w2`, `e2 = beta (t -
/// y) / (1 + a)`, `e1 = e2 u`. The hidden errors are never stored: the W1
/// sweep takes the update as `(eta1 e2 x) u^T`.
#[inline(always)]
pub(crate) fn step_one_output<const F: bool>(
    layers: &mut Layers,
    st: &mut States,
    x: &[f32],
    t: f32,
    cfg: &EpConfig,
    next: Option<&[f32]>,
) -> SampleStats {
    let beta = cfg.beta as f32;
    let rates = LayerRates::of(cfg);
    let (eta1, eta2) = (rates.rate(layers, 1), rates.rate(layers, 2));
    let [x_scaled, d, _] = &mut st.tmp[..] else {
        unreachable!("two layers")
    };
    // `gains` holds u = phi' w2 until the last sample turns it into e1.
    let gains = &mut st.e[1];
    sigmoid::<F>(&st.drive, &mut st.phi[1]);
    let (wphi, a) = output_slope_gain::<F>(&st.phi[1], &layers.w[1], d, gains);
    let y = wphi + layers.b[1][0];
    let loss = 0.5 * ((y - t) as f64).powi(2);
    let y_nudged = y + beta * (t - y);
    let err2 = beta * (t - y) / (1.0 + a);
    let c2 = eta2 * err2;
    output_update::<F>(&st.phi[1], d, gains, &mut layers.w[1], [err2, c2]);
    layers.b[1][0] += c2;
    // sum e1_i^2 = e2^2 sum u_i^2 = e2^2 a.
    let e2_sq = (err2 as f64).powi(2);
    let energy =
        0.5 * beta as f64 * ((y_nudged - t) as f64).powi(2) + 0.5 * e2_sq * (1.0 + a as f64);
    // W1 += eta1 x e1^T = (eta1 e2 x) u^T and b1 += eta1 e1 = (eta1 e2) u.
    let g = eta1 * err2;
    x_scaled.iter_mut().zip(x).for_each(|(s, &x)| *s = g * x);
    match next {
        Some(next) => layers.rank1_then_drive::<F>(x_scaled, (gains, g), next, &mut st.drive),
        None => {
            layers.rank1::<F>(1, x_scaled, (gains, g));
            gains.iter_mut().for_each(|u| *u *= err2);
            st.e[2][0] = err2;
            keep_clamped_state(st, x, &[y_nudged]);
        }
    }
    SampleStats { loss, energy }
}

/// Two outputs: one pass gives `y` and the 2 x 2 matrix `A`, a 2 x 2 solve
/// gives `e2`, and one pass stores `e1 = D W2 e2` and updates `W2` with the
/// clamped activity.
#[inline(always)]
pub(crate) fn step_two_outputs<const F: bool>(
    layers: &mut Layers,
    st: &mut States,
    x: &[f32],
    t: &[f32],
    cfg: &EpConfig,
    next: Option<&[f32]>,
) -> SampleStats {
    let beta = cfg.beta as f32;
    let rates = LayerRates::of(cfg);
    let (eta1, eta2) = (rates.rate(layers, 1), rates.rate(layers, 2));
    let h = layers.sizes[1];
    let [x_scaled, d, _] = &mut st.tmp[..] else {
        unreachable!("two layers")
    };
    sigmoid::<F>(&st.drive, &mut st.phi[1]);
    let (w_0, w_1) = layers.w[1].split_at_mut(h);
    let (wphi, [a00, a01, a11]) = two_output_slopes::<F>(&st.phi[1], [&*w_0, &*w_1], d);
    let (b2, mut loss, mut nudge_sq) = (&mut layers.b[1], 0.0, 0.0);
    let mut rhs = [0.0f64; 2];
    let mut y_nudged = [0.0f32; 2];
    for p in 0..2 {
        let y = wphi[p] + b2[p];
        loss += 0.5 * ((y - t[p]) as f64).powi(2);
        let t = nudge_target(cfg.cost.as_ref(), p, y, t[p]);
        y_nudged[p] = y + beta * (t - y);
        nudge_sq += ((y_nudged[p] - t) as f64).powi(2);
        rhs[p] = (beta * (t - y)) as f64;
    }
    // (I + A) e2 = rhs, A symmetric positive semi-definite: Cramer's rule.
    let (m00, m01, m11) = (1.0 + a00 as f64, a01 as f64, 1.0 + a11 as f64);
    let det = m00 * m11 - m01 * m01;
    let e2 = [
        ((m11 * rhs[0] - m01 * rhs[1]) / det) as f32,
        ((m00 * rhs[1] - m01 * rhs[0]) / det) as f32,
    ];
    let c2 = [eta2 * e2[0], eta2 * e2[1]];
    let e1 = &mut st.e[1];
    two_output_update::<F>(&st.phi[1], d, [w_0, w_1], e1, [e2, c2]);
    b2[0] += c2[0];
    b2[1] += c2[1];
    // ||e1||^2 = e2^T A e2.
    let (x0, x1) = (e2[0] as f64, e2[1] as f64);
    let e1_sq = a00 as f64 * x0 * x0 + 2.0 * a01 as f64 * x0 * x1 + a11 as f64 * x1 * x1;
    let energy = 0.5 * cfg.beta * nudge_sq + 0.5 * (e1_sq + x0 * x0 + x1 * x1);
    x_scaled.iter_mut().zip(x).for_each(|(s, &x)| *s = eta1 * x);
    match next {
        Some(next) => layers.rank1_then_drive::<F>(x_scaled, (e1, eta1), next, &mut st.drive),
        None => {
            layers.rank1::<F>(1, x_scaled, (e1, eta1));
            st.e[2].copy_from_slice(&e2);
            keep_clamped_state(st, x, &y_nudged);
        }
    }
    SampleStats { loss, energy }
}

/// Leaves the weakly clamped state of the last sample in `st` (what the
/// general step leaves there), given `e1` and `e2` already in `st.e`:
/// `s(0) = phi(0) = x`, the clamped `phi(1) += phi' e1` (`phi'` in
/// `st.tmp[1]`), `s(1) = drive + e1`, and the nudged output. The closed-form
/// steps skip these stores for all but a sequence's last sample; nothing
/// reads them in between.
fn keep_clamped_state(st: &mut States, x: &[f32], y_nudged: &[f32]) {
    st.s[0].copy_from_slice(x);
    st.phi[0].copy_from_slice(x);
    let hidden = st.e[1].iter().zip(&st.tmp[1]).zip(&st.drive);
    for (((&e, &d), &drive), (phi, s)) in hidden.zip(st.phi[1].iter_mut().zip(&mut st.s[1])) {
        *phi += d * e;
        *s = drive + e;
    }
    st.s[2].copy_from_slice(y_nudged);
    st.nudged.copy_from_slice(y_nudged);
}

/// The output and the first half of the one-output closed form in one pass
/// over the hidden activity `phi`: slopes `d_i = phi_i (1 - phi_i)`, gains
/// `u_i = d_i w_i`. Returns `(w . phi, sum u_i^2)`.
#[inline(always)]
pub(crate) fn output_slope_gain<const FMA: bool>(
    phi: &[f32],
    w: &[f32],
    d: &mut [f32],
    u: &mut [f32],
) -> (f32, f32) {
    let n = phi.len().min(w.len()).min(d.len()).min(u.len());
    let body = n - n % LANES;
    let (mut acc_y, mut acc_a) = ([0.0f32; LANES], [0.0f32; LANES]);
    // Whole chunks of LANES keep the accumulators in registers.
    for c in (0..body).step_by(LANES) {
        let (p, ww) = (&phi[c..c + LANES], &w[c..c + LANES]);
        let (dd, uu) = (&mut d[c..c + LANES], &mut u[c..c + LANES]);
        for k in 0..LANES {
            dd[k] = p[k] * (1.0 - p[k]);
            uu[k] = dd[k] * ww[k];
            acc_y[k] = madd::<FMA>(ww[k], p[k], acc_y[k]);
            acc_a[k] = madd::<FMA>(uu[k], uu[k], acc_a[k]);
        }
    }
    let (mut tail_y, mut tail_a) = (0.0f32, 0.0f32);
    for i in body..n {
        d[i] = phi[i] * (1.0 - phi[i]);
        u[i] = d[i] * w[i];
        tail_y = madd::<FMA>(w[i], phi[i], tail_y);
        tail_a = madd::<FMA>(u[i], u[i], tail_a);
    }
    (reduce(acc_y) + tail_y, reduce(acc_a) + tail_a)
}

/// The output-layer update of the one-output closed form, storing only
/// `w2`: `w2 += c2 (phi + d u e2)`, where `phi + d (u e2)` is the clamped
/// activity (`e1 = u e2`, the hidden errors over [`output_slope_gain`]'s
/// gains).
#[inline(always)]
pub(crate) fn output_update<const FMA: bool>(
    phi: &[f32],
    d: &[f32],
    u: &[f32],
    w2: &mut [f32],
    [e2, c2]: [f32; 2],
) {
    for (((w, &p), &d), &u) in w2.iter_mut().zip(phi).zip(d).zip(u) {
        let clamped = madd::<FMA>(d, u * e2, p);
        *w = madd::<FMA>(clamped, c2, *w);
    }
}

/// Width of the two-output passes' accumulators (one ymm register each:
/// five of them, so 32 lanes would not fit in the registers).
const PAIR_LANES: usize = 8;

/// The outputs' dots and `A = W2^T D^2 W2` of two outputs in one pass over
/// `phi` (slopes `d = phi (1 - phi)` stored). Returns `([w_0 . phi, w_1 .
/// phi], [A_00, A_01, A_11])`.
#[inline(always)]
fn two_output_slopes<const FMA: bool>(
    phi: &[f32],
    [w0, w1]: [&[f32]; 2],
    d: &mut [f32],
) -> ([f32; 2], [f32; 3]) {
    let n = phi.len().min(w0.len()).min(w1.len()).min(d.len());
    let body = n - n % PAIR_LANES;
    let mut acc = [[0.0f32; PAIR_LANES]; 5];
    for c in (0..body).step_by(PAIR_LANES) {
        let r = c..c + PAIR_LANES;
        let (p, a, b) = (&phi[r.clone()], &w0[r.clone()], &w1[r.clone()]);
        let dd = &mut d[r];
        for k in 0..PAIR_LANES {
            dd[k] = p[k] * (1.0 - p[k]);
            let (q0, q1) = (dd[k] * a[k], dd[k] * b[k]);
            acc[0][k] = madd::<FMA>(a[k], p[k], acc[0][k]);
            acc[1][k] = madd::<FMA>(b[k], p[k], acc[1][k]);
            acc[2][k] = madd::<FMA>(q0, q0, acc[2][k]);
            acc[3][k] = madd::<FMA>(q0, q1, acc[3][k]);
            acc[4][k] = madd::<FMA>(q1, q1, acc[4][k]);
        }
    }
    let mut sums = acc.map(|a| a.iter().sum::<f32>());
    for i in body..n {
        d[i] = phi[i] * (1.0 - phi[i]);
        let (q0, q1) = (d[i] * w0[i], d[i] * w1[i]);
        sums[0] = madd::<FMA>(w0[i], phi[i], sums[0]);
        sums[1] = madd::<FMA>(w1[i], phi[i], sums[1]);
        sums[2] = madd::<FMA>(q0, q0, sums[2]);
        sums[3] = madd::<FMA>(q0, q1, sums[3]);
        sums[4] = madd::<FMA>(q1, q1, sums[4]);
    }
    ([sums[0], sums[1]], [sums[2], sums[3], sums[4]])
}

/// The rest of the two-output closed form in one pass: hidden errors
/// `e1 = d (w_0 e2_0 + w_1 e2_1)` (stored, from the weights before the
/// update), then `w_p += c2_p (phi + d e1)` with the clamped activity.
#[inline(always)]
fn two_output_update<const FMA: bool>(
    phi: &[f32],
    d: &[f32],
    [w0, w1]: [&mut [f32]; 2],
    e1: &mut [f32],
    [e2, c2]: [[f32; 2]; 2],
) {
    let cols = w0.iter_mut().zip(w1.iter_mut());
    for (((e, (a, b)), &p), &d) in e1.iter_mut().zip(cols).zip(phi).zip(d) {
        *e = d * madd::<FMA>(*b, e2[1], *a * e2[0]);
        let clamped = madd::<FMA>(d, *e, p);
        *a = madd::<FMA>(clamped, c2[0], *a);
        *b = madd::<FMA>(clamped, c2[1], *b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dennn::LrScaling;
    use crate::ep::step_general;
    use rand::{Rng, SeedableRng};

    /// The closed-form steps give the general step's weights, next drive,
    /// last clamped state, loss and energy (up to float rounding) over a
    /// run of samples with the fused next-sample drive, for one and two
    /// outputs, in the plain and (where the CPU has it) the FMA build.
    #[test]
    fn closed_form_steps_match_the_general_step() {
        for k in [1, 2] {
            closed_form_matches_general::<false>(k);
            if crate::net::has_fma() {
                closed_form_matches_general::<true>(k);
            } else {
                eprintln!("fused variant skipped: no AVX2/FMA on this CPU");
            }
        }
    }

    /// 30 samples through a 7-70-k net (70 hidden units: two whole panels
    /// and a tail in the sweep; whole chunks and a tail in the passes).
    fn closed_form_matches_general<const F: bool>(k: usize) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let sizes = [7, 70, k];
        let xs: Vec<Vec<f32>> = (0..30)
            .map(|_| (0..7).map(|_| rng.random_range(-2.0..2.0)).collect())
            .collect();
        let ts: Vec<Vec<f32>> = (0..30)
            .map(|_| (0..k).map(|_| rng.random_range(-1.5..1.5)).collect())
            .collect();
        let cfg = EpConfig {
            learning_rate: 18.0,
            output_learning_rate: Some(5.0),
            lr_scaling: LrScaling::FanIn,
            beta: 0.7,
            ..EpConfig::default()
        };
        let layers = Layers::new(&sizes, 1).unwrap();
        assert_eq!(closed_form_outputs(&layers, &cfg), Some(k));
        let run = |closed: bool| {
            let mut layers = layers.clone();
            let mut st = States::new(&sizes);
            layers.affine::<F>(1, &xs[0], &mut st.drive);
            let mut stats = Vec::new();
            for (i, (x, t)) in xs.iter().zip(&ts).enumerate() {
                let next = xs.get(i + 1).map(|v| v.as_slice());
                let (l, s) = (&mut layers, &mut st);
                stats.push(match (closed, k) {
                    (false, _) => step_general::<F>(l, s, x, t, &cfg, next),
                    (true, 1) => step_one_output::<F>(l, s, x, t[0], &cfg, next),
                    (true, _) => step_two_outputs::<F>(l, s, x, t, &cfg, next),
                });
            }
            (layers, st, stats)
        };
        let (lf, sf, af) = run(true);
        let (lg, sg, ag) = run(false);
        let close = |a: &[f32], b: &[f32], what: &str| {
            assert_eq!(a.len(), b.len(), "{what}");
            for (x, y) in a.iter().zip(b) {
                let ok = (x - y).abs() <= 1e-4 * (1.0 + y.abs());
                assert!(ok, "{what} ({k} outputs): {x} vs {y}");
            }
        };
        for l in 0..2 {
            close(&lf.w[l], &lg.w[l], "weights");
            close(&lf.b[l], &lg.b[l], "biases");
        }
        close(&sf.drive, &sg.drive, "next drive");
        for l in 0..3 {
            close(&sf.s[l], &sg.s[l], "potentials");
        }
        for l in 1..3 {
            close(&sf.e[l], &sg.e[l], "errors");
        }
        close(&sf.phi[1], &sg.phi[1], "clamped activity");
        close(&sf.nudged, &sg.nudged, "nudged output");
        for (a, b) in af.iter().zip(&ag) {
            let tol = |v: f64| 1e-5 * (1.0 + v);
            assert!((a.loss - b.loss).abs() <= tol(b.loss), "{a:?} {b:?}");
            assert!((a.energy - b.energy).abs() <= tol(b.energy), "{a:?} {b:?}");
        }
    }
}
