//! Theory tests of the convolutional dendritic network (issue 22, item 3):
//! the EP update approaches the backprop gradient as beta -> 0; the free
//! phase relaxes to the feed-forward output; the clamped sweeps reach the
//! same equilibrium as the Euler relaxation; a convolution equals its
//! dense matrix; backprop agrees with finite differences.
use crate::common;

use common::{random, small_net};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_convnet::{
    Activation, ClampedPhase, ConvSpec, EpSettings, FreePhase, LayerShape, Layout, Network,
    Nudging, Parameters, Rule,
};

const ACTIVATIONS: [Activation; 3] = [Activation::Tanh, Activation::Sigmoid, Activation::Relu];

fn ep(beta: f64, nudging: Nudging, clamped_phase: ClampedPhase) -> Rule {
    Rule::Ep(EpSettings {
        beta,
        nudging,
        free_phase: FreePhase::FeedForward,
        clamped_phase,
    })
}

/// Relative distance `||a - b|| / ||b||` of two gradients.
fn rel_error(a: &Parameters, b: &Parameters) -> f64 {
    let (a, b) = (a.flatten(), b.flatten());
    let d: f64 = a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum();
    let n: f64 = b.iter().map(|y| y * y).sum();
    (d / n).sqrt()
}

#[test]
fn ep_update_approaches_the_backprop_gradient_as_beta_shrinks() {
    let n = 3;
    for (k, &act) in ACTIVATIONS.iter().enumerate() {
        let net = small_net(act, 2, 10 + k as u64);
        let x = random(n * 144, 1);
        let t = random(n * 2, 2);
        let bp = net.gradient(&x, &t, n, Rule::Backprop).unwrap();
        let mut last = f64::INFINITY;
        for beta in [0.2, 0.05, 0.01] {
            let sweeps = ClampedPhase::Sweeps { iterations: 1 };
            let est = net
                .gradient(&x, &t, n, ep(beta, Nudging::Symmetric, sweeps))
                .unwrap();
            let cos = est.cosine(&bp);
            let err = rel_error(&est, &bp);
            assert!(cos > 0.99, "{act:?} beta {beta}: cosine {cos}");
            assert!(
                err < last * 1.01 + 1e-4,
                "{act:?} beta {beta}: error {err} after {last}"
            );
            last = err;
        }
        // The Euler relaxation (the report's dynamics), run to equilibrium,
        // gives the same estimate.
        let euler = ClampedPhase::Euler {
            steps: 1000,
            dt: 0.2,
        };
        let est = net
            .gradient(&x, &t, n, ep(0.01, Nudging::Symmetric, euler))
            .unwrap();
        assert!(est.cosine(&bp) > 0.99, "{act:?} Euler: {}", est.cosine(&bp));
    }
}

#[test]
fn symmetric_nudging_removes_the_first_order_bias() {
    let n = 3;
    let net = small_net(Activation::Tanh, 2, 3);
    let x = random(n * 144, 4);
    let t = random(n * 2, 5);
    let bp = net.gradient(&x, &t, n, Rule::Backprop).unwrap();
    let converged = ClampedPhase::Sweeps { iterations: 30 };
    let mut errors = Vec::new();
    for beta in [0.04, 0.02] {
        let sym = net
            .gradient(&x, &t, n, ep(beta, Nudging::Symmetric, converged))
            .unwrap();
        let pos = net
            .gradient(&x, &t, n, ep(beta, Nudging::Positive, converged))
            .unwrap();
        let (es, ep_) = (rel_error(&sym, &bp), rel_error(&pos, &bp));
        assert!(
            es < ep_ / 5.0,
            "beta {beta}: symmetric {es}, one-sided {ep_}"
        );
        errors.push((es, ep_));
    }
    // One-sided bias is first order in beta (halves with beta), symmetric
    // second order (quarters).
    let (s_ratio, p_ratio) = (errors[0].0 / errors[1].0, errors[0].1 / errors[1].1);
    assert!((1.6..2.5).contains(&p_ratio), "one-sided ratio {p_ratio}");
    assert!((3.2..5.0).contains(&s_ratio), "symmetric ratio {s_ratio}");
}

#[test]
fn free_phase_relaxes_to_the_feed_forward_output() {
    // With the dendritic energy every error vanishes at the minimum, so
    // the Euler dynamics from zero potentials end at the feed-forward pass.
    for (k, &act) in ACTIVATIONS.iter().enumerate() {
        let net = small_net(act, 3, 20 + k as u64);
        let n = 2;
        let x = random(n * 144, 6);
        let ff = net.feed_forward(&x, n).unwrap();
        let mut energies = Vec::new();
        // dt 0.2: the rectifier's He initialisation makes the dynamics
        // stiffer than the saturating units' (0.5 diverges there).
        for steps in [10, 40, 160, 2000] {
            let eq = net
                .relax(&x, None, FreePhase::Euler { steps, dt: 0.2 }, n)
                .unwrap();
            energies.push(eq.energy);
            if steps == 2000 {
                let worst = eq
                    .output
                    .iter()
                    .zip(&ff)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0f32, f32::max);
                assert!(worst < 1e-4, "{act:?}: output differs by {worst}");
                assert!(
                    eq.stationarity < 1e-4,
                    "{act:?}: |dE/ds| {}",
                    eq.stationarity
                );
            }
        }
        assert!(
            energies.windows(2).all(|w| w[1] <= w[0]),
            "{act:?}: energy not decreasing {energies:?}"
        );
        assert!(energies[3] < 1e-8, "{act:?}: energy {energies:?}");
    }
}

#[test]
fn clamped_sweeps_reach_the_euler_equilibrium() {
    let net = small_net(Activation::Sigmoid, 2, 8);
    let n = 2;
    let x = random(n * 144, 9);
    let t = random(n * 2, 10);
    let ff = FreePhase::FeedForward;
    let beta = 0.3;
    let mut residuals = Vec::new();
    for iterations in [1, 2, 4, 8] {
        let phase = ClampedPhase::Sweeps { iterations };
        let eq = net.relax(&x, Some((&t, beta, phase)), ff, n).unwrap();
        residuals.push(eq.stationarity);
    }
    // Each round shrinks the distance from equilibrium by a large factor,
    // down to f32 rounding.
    assert!(
        residuals[1] < residuals[0] * 0.1 && residuals[2] < residuals[1] * 0.1,
        "sweeps do not converge: {residuals:?}"
    );
    assert!(residuals[3] < 1e-5, "sweeps do not converge: {residuals:?}");
    let sweeps = ClampedPhase::Sweeps { iterations: 30 };
    let a = net.relax(&x, Some((&t, beta, sweeps)), ff, n).unwrap();
    let euler = ClampedPhase::Euler {
        steps: 2000,
        dt: 0.2,
    };
    let b = net.relax(&x, Some((&t, beta, euler)), ff, n).unwrap();
    assert!(
        a.stationarity < 1e-5 && b.stationarity < 1e-5,
        "{a:?} {b:?}"
    );
    for (u, v) in a.output.iter().zip(&b.output) {
        assert!(
            (u - v).abs() < 1e-4,
            "outputs {:?} vs {:?}",
            a.output,
            b.output
        );
    }
    assert!((a.energy - b.energy).abs() < 1e-6 * a.energy.max(1.0));
}

/// The dense matrix of layer `s` with weights `w`, built from the
/// definition of a zero-padded strided convolution (not from im2col):
/// `M[(co, oy, ox), (ci, iy, ix)] = W[co, ci, ky, kx]` where
/// `iy = oy stride + ky - pad`, `ix = ox stride + kx - pad`.
fn dense_matrix(s: &LayerShape, w: &[f32]) -> Vec<f32> {
    let (rows, cols) = (s.out_len(), s.in_len());
    let mut m = vec![0.0; rows * cols];
    for co in 0..s.cout {
        for oy in 0..s.hout {
            for ox in 0..s.wout {
                let r = (co * s.hout + oy) * s.wout + ox;
                for ci in 0..s.cin {
                    for ky in 0..s.kh {
                        for kx in 0..s.kw {
                            let iy = (oy * s.stride + ky) as isize - s.pad as isize;
                            let ix = (ox * s.stride + kx) as isize - s.pad as isize;
                            if iy < 0 || ix < 0 || iy >= s.hin as isize || ix >= s.win as isize {
                                continue;
                            }
                            let c = (ci * s.hin + iy as usize) * s.win + ix as usize;
                            m[r * cols + c] += w[((co * s.cin + ci) * s.kh + ky) * s.kw + kx];
                        }
                    }
                }
            }
        }
    }
    m
}

#[test]
fn convolution_equals_its_dense_matrix() {
    // Odd and even sizes, strides 1-3, kernels 1-5, several channels, and
    // the dense layers (a window covering the whole input).
    let conv = [
        ConvSpec {
            channels: 3,
            kernel: 5,
            stride: 2,
        },
        ConvSpec {
            channels: 4,
            kernel: 3,
            stride: 1,
        },
        ConvSpec {
            channels: 2,
            kernel: 4,
            stride: 3,
        },
        ConvSpec {
            channels: 3,
            kernel: 1,
            stride: 1,
        },
    ];
    let layout = Layout::new(13, 10, &conv, &[5], 2).unwrap();
    let net = Network::new(layout.clone(), Activation::Tanh, 4);
    for (l, s) in layout.layers().iter().enumerate() {
        let m = dense_matrix(s, &net.parameters().weights[l]);
        let x = random(s.in_len(), 30 + l as u64);
        let y = net.layer_map(l, &x).unwrap();
        let e = random(s.out_len(), 40 + l as u64);
        let g = net.layer_map_transposed(l, &e).unwrap();
        let (rows, cols) = (s.out_len(), s.in_len());
        for r in 0..rows {
            let want: f32 = (0..cols).map(|c| m[r * cols + c] * x[c]).sum();
            assert!(
                (y[r] - want).abs() < 1e-4,
                "layer {l} row {r}: {} vs {want}",
                y[r]
            );
        }
        for c in 0..cols {
            let want: f32 = (0..rows).map(|r| m[r * cols + c] * e[r]).sum();
            assert!(
                (g[c] - want).abs() < 1e-4,
                "layer {l} column {c}: {} vs {want}",
                g[c]
            );
        }
    }
}

#[test]
fn backprop_gradient_matches_finite_differences() {
    let n = 2;
    for (k, &act) in ACTIVATIONS.iter().enumerate() {
        let mut net = small_net(act, 2, 50 + k as u64);
        let x = random(n * 144, 11);
        let t = random(n * 2, 12);
        let bp = net.gradient(&x, &t, n, Rule::Backprop).unwrap();
        let loss = |net: &Network| -> f64 {
            let y = net.feed_forward(&x, n).unwrap();
            y.iter()
                .zip(&t)
                .map(|(y, t)| 0.5 * ((y - t) as f64).powi(2))
                .sum()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let (mut fd, mut an) = (Vec::new(), Vec::new());
        let tensors = bp.weights.len() * 2;
        for _ in 0..60 {
            let which = rng.random_range(0..tensors);
            let (l, is_w) = (which / 2, which % 2 == 0);
            let len = if is_w {
                bp.weights[l].len()
            } else {
                bp.biases[l].len()
            };
            let i = rng.random_range(0..len);
            let h = 1e-2f32;
            let set = |net: &mut Network, v: f32| {
                let p = net.parameters_mut();
                let tensor = if is_w {
                    &mut p.weights[l]
                } else {
                    &mut p.biases[l]
                };
                tensor[i] = v;
            };
            let v0 = if is_w {
                bp.weights[l][i]
            } else {
                bp.biases[l][i]
            };
            let v0 = {
                let _ = v0;
                let p = net.parameters();
                if is_w {
                    p.weights[l][i]
                } else {
                    p.biases[l][i]
                }
            };
            set(&mut net, v0 + h);
            let up = loss(&net);
            set(&mut net, v0 - h);
            let down = loss(&net);
            set(&mut net, v0);
            fd.push((up - down) / (2.0 * h as f64));
            an.push(if is_w {
                bp.weights[l][i]
            } else {
                bp.biases[l][i]
            } as f64);
        }
        let dot: f64 = fd.iter().zip(&an).map(|(a, b)| a * b).sum();
        let na: f64 = fd.iter().map(|a| a * a).sum::<f64>().sqrt();
        let nb: f64 = an.iter().map(|a| a * a).sum::<f64>().sqrt();
        assert!(
            dot / (na * nb) > 0.999,
            "{act:?}: cosine {}",
            dot / (na * nb)
        );
    }
}
