//! Set-ups shared by the image-model tests (`input_noise.rs`,
//! `weight_average.rs`, `dropout.rs`, `theory.rs`,
//! `pins_and_pixels.rs`): tiny frames
//! whose bright spot moves with the frame's index, a tiny one-convolution
//! training configuration, and the small net of the gradient checks.
//! Not every file that shares it uses every set-up.
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use tactrace_convnet::{
    Activation, ClampedPhase, ConvConfig, ConvSpec, EpSettings, FreePhase, Layout, ModelKind,
    Network, Nudging, Rule,
};

/// The side of the tiny frames, px.
pub const SIDE: usize = 12;

/// `count` frames with a bright pixel pair at a place that moves with the
/// frame's index; targets its column and row.
pub fn moving_pair_frames(count: usize) -> (Vec<u8>, Vec<f64>) {
    let (mut pixels, mut targets) = (Vec::new(), Vec::new());
    for k in 0..count {
        let (cx, cy) = (1 + (k * 7) % (SIDE - 3), 1 + (k * 5) % (SIDE - 2));
        let mut f = vec![10u8; SIDE * SIDE];
        f[cy * SIDE + cx] = 240;
        f[cy * SIDE + cx + 1] = 200;
        pixels.extend(f);
        targets.extend([cx as f64, cy as f64]);
    }
    (pixels, targets)
}

/// A convolution of 4 maps (3 x 3, stride 2) and a dense layer of 8;
/// 3 epochs of batches of 12 in chunks of 4 (each test sets the rest).
pub fn tiny_config(kind: ModelKind) -> ConvConfig {
    let mut c = ConvConfig::new(kind);
    c.conv = vec![ConvSpec {
        channels: 4,
        kernel: 3,
        stride: 2,
    }];
    c.dense = vec![8];
    c.epochs = 3;
    c.batch_size = 12;
    c.chunk_size = 4;
    c
}

/// The two convolutions of the small net: 3 maps 3 x 3 stride 1, then 4
/// maps 3 x 3 stride 2 (12 x 12 -> 6 x 6).
pub fn small_conv() -> [ConvSpec; 2] {
    [
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
    ]
}

/// A small net: 12 x 12 input, [`small_conv`], one dense hidden layer of
/// 10, `outputs` linear units.
pub fn small_net(activation: Activation, outputs: usize, seed: u64) -> Network {
    let layout = Layout::new(12, 12, &small_conv(), &[10], outputs).expect("valid layout");
    Network::new(layout, activation, seed)
}

/// The EP rule at `beta`: symmetric nudging, the feed-forward free
/// phase, one sweep a clamped phase (the defaults but beta).
pub fn ep_rule(beta: f64) -> Rule {
    Rule::Ep(EpSettings {
        beta,
        nudging: Nudging::Symmetric,
        free_phase: FreePhase::FeedForward,
        clamped_phase: ClampedPhase::Sweeps { iterations: 1 },
    })
}

/// `n` values uniform in -1..1, seeded by `seed`.
pub fn random(n: usize, seed: u64) -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| rng.random_range(-1.0..1.0)).collect()
}
