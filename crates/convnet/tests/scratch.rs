use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_convnet::*;
fn random(n: usize, seed: u64) -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| rng.random_range(-1.0..1.0)).collect()
}
fn small_net(activation: Activation, outputs: usize, seed: u64) -> Network {
    let conv = [
        ConvSpec {
            channels: 3,
            kernel: 3,
            stride: 1,
        },
        ConvSpec {
            channels: 4,
            kernel: 3,
            stride: 2,
        },
    ];
    let layout = Layout::new(12, 12, &conv, &[10], outputs).expect("valid layout");
    Network::new(layout, activation, seed)
}
fn rel(a: &Parameters, b: &Parameters) -> f64 {
    let (a, b) = (a.flatten(), b.flatten());
    let d: f64 = a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum();
    let n: f64 = b.iter().map(|y| y * y).sum();
    (d / n).sqrt()
}
#[test]
fn scratch() {
    let n = 3;
    let net = small_net(Activation::Tanh, 2, 3);
    let x = random(n * 144, 4);
    let t = random(n * 2, 5);
    let bp = net.gradient(&x, &t, n, Rule::Backprop).unwrap();
    for beta in [0.04, 0.02] {
        for it in [1, 30] {
            for nud in [Nudging::Symmetric, Nudging::Positive] {
                let r = Rule::Ep(EpSettings {
                    beta,
                    nudging: nud,
                    free_phase: FreePhase::FeedForward,
                    clamped_phase: ClampedPhase::Sweeps { iterations: it },
                });
                let g = net.gradient(&x, &t, n, r).unwrap();
                let eq = net
                    .relax(
                        &x,
                        Some((&t, beta, ClampedPhase::Sweeps { iterations: it })),
                        FreePhase::FeedForward,
                        n,
                    )
                    .unwrap();
                println!(
                    "beta {beta} it {it} {nud:?}: rel {:.3e} cos {:.6} stat {:.2e}",
                    rel(&g, &bp),
                    g.cosine(&bp),
                    eq.stationarity
                );
            }
        }
    }
    let net = small_net(Activation::Relu, 3, 22);
    let x = random(2 * 144, 6);
    let ff = net.feed_forward(&x, 2).unwrap();
    for (steps, dt) in [(400, 0.2), (2000, 0.2), (400, 0.1), (2000, 0.1)] {
        let eq = net
            .relax(&x, None, FreePhase::Euler { steps, dt }, 2)
            .unwrap();
        println!(
            "relu steps {steps} dt {dt}: E {:.3e} stat {:.3e} out {:?} ff {:?}",
            eq.energy, eq.stationarity, &eq.output, ff
        );
    }
}
