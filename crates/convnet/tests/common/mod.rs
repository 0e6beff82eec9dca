//! Set-ups shared by the image-model training tests (`issue22_noise.rs`,
//! `weight_average.rs`, `dropout.rs`): tiny frames whose bright spot
//! moves with the frame's index, and a tiny one-convolution network.
//! Not every file that shares it uses every set-up.
#![allow(dead_code)]

use tactrace_convnet::{ConvConfig, ConvSpec, ModelKind};

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
