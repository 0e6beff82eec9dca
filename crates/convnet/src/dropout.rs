//! Dropout that equilibrium propagation keeps (docs/learning.md,
//! "Dropout"): each training frame draws one mask `m(l)` for a layer's
//! units (`dense_dropout`: every unit of a dense hidden layer;
//! `channel_dropout`: whole feature maps of a convolutional layer), held
//! fixed through the free and both nudged phases. The layer above sees the
//! rates `m(l) . phi(s(l))`, with `m = 0` for a dropped unit and
//! `1 / (1 - p)` for a kept one (so prediction, with no mask, needs no
//! rescaling). The energy is that of the masked network, so its top-down
//! term is `m(l) . phi'(s(l)) . W(l+1)^T e(l+1)`: a dropped unit's error
//! is 0 in every phase, its output is held at 0, and the EP estimate is
//! the backprop gradient of the masked network.
//!
//! `pixel_dropout` (pins and pixels) is one more draw a frame, on the
//! last convolution: with its probability the whole layer's mask is 0 for
//! that frame (kept, its mask is unchanged: 1, or the channel draws), so
//! the dense layer sees the pins alone; the same masked energy, the same
//! estimate.
use crate::config::ConvConfig;
use crate::layout::Layout;
use crate::params::Parameters;
use crate::workspace::Workspace;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The dropout probability of layer `l`'s output under `config` (the
/// output layer's is always 0).
fn rate(layout: &Layout, config: &ConvConfig, l: usize) -> f64 {
    match (l + 1 == layout.depth(), layout.layers[l].is_dense()) {
        (true, _) => 0.0,
        (false, true) => config.dense_dropout,
        (false, false) => config.channel_dropout,
    }
}

/// Mixed into a frame's key for its pixel-feature draw, so that the
/// channel draws are those of a fit without `pixel_dropout`.
const PIXEL_STREAM: u64 = 0x2545_f491_4f6c_dd1d;

/// The layer whose whole output `pixel_dropout` drops (the last
/// convolution), if it is on.
fn pixel_layer(config: &ConvConfig) -> Option<usize> {
    (config.pixel_dropout > 0.0).then(|| config.conv.len() - 1)
}

/// Give `ws` a mask buffer for every layer whose rate is above 0.
pub(crate) fn enable(ws: &mut Workspace, layout: &Layout, config: &ConvConfig) {
    for l in 0..layout.depth() {
        if rate(layout, config, l) > 0.0 || pixel_layer(config) == Some(l) {
            let len = layout.layers[l].out_len() * ws.cap;
            ws.mask[l] = vec![1.0; len];
            ws.masked[l] = vec![0.0; len];
        }
    }
}

/// Draw frame `b`'s masks (of an `nb`-frame chunk) into `ws`, from a
/// generator seeded with `key`: one draw a unit of a dense layer, one a
/// feature map of a convolutional layer (the same value at every
/// position); then the pixel-feature draw.
pub(crate) fn draw(
    ws: &mut Workspace,
    layout: &Layout,
    config: &ConvConfig,
    (nb, b): (usize, usize),
    key: u64,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(key);
    for l in 0..layout.depth() {
        let p = rate(layout, config, l);
        if p <= 0.0 {
            continue;
        }
        let shape = &layout.layers[l];
        let positions = shape.positions();
        let kept = (1.0 / (1.0 - p)) as f32;
        for c in 0..shape.cout {
            let v = if rng.random::<f64>() < p { 0.0 } else { kept };
            let at = (c * nb + b) * positions;
            ws.mask[l][at..at + positions].fill(v);
        }
    }
    if let Some(l) = pixel_layer(config) {
        let mut rng = ChaCha8Rng::seed_from_u64(key ^ PIXEL_STREAM);
        let dropped = rng.random::<f64>() < config.pixel_dropout;
        let shape = &layout.layers[l];
        let positions = shape.positions();
        for c in 0..shape.cout {
            let at = (c * nb + b) * positions;
            let frame = &mut ws.mask[l][at..at + positions];
            if dropped {
                frame.fill(0.0);
            } else if config.channel_dropout == 0.0 {
                frame.fill(1.0);
            }
        }
    }
}

/// Zero the dense layer's weights on the pixel features (every column
/// but the pins') in each network of `config.pixel_dropout == 1`: they
/// are never trained, so the model reads the pins alone, at prediction
/// too, and a fine-tune with the pixels on starts at its figure.
pub(crate) fn zero_masked_pixels(params: &mut Parameters, layout: &Layout, config: &ConvConfig) {
    if config.pixel_dropout < 1.0 {
        return;
    }
    let l = config.conv.len();
    let shape = &layout.layers[l];
    for row in params.weights[l].chunks_exact_mut(shape.fan_in()) {
        row[..shape.window()].fill(0.0);
    }
}

/// Load masks given frame by frame (`masks[l]`: `nb x out_len` of layer
/// `l`, or empty for none) into `ws` in the chunk layout.
pub(crate) fn load(ws: &mut Workspace, layout: &Layout, masks: &[Vec<f32>], nb: usize) {
    for (l, m) in masks.iter().enumerate() {
        if m.is_empty() {
            continue;
        }
        let shape = &layout.layers[l];
        let (c_out, positions) = (shape.cout, shape.positions());
        let len = shape.out_len() * ws.cap;
        ws.mask[l] = vec![1.0; len];
        ws.masked[l] = vec![0.0; len];
        for b in 0..nb {
            for c in 0..c_out {
                let src = &m[(b * c_out + c) * positions..][..positions];
                let at = (c * nb + b) * positions;
                ws.mask[l][at..at + positions].copy_from_slice(src);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{ConvSpec, InputKind, ModelKind};

    /// A one-convolution pins-and-pixels configuration dropping the pixel
    /// features at `p`, and its layout on 8 x 8 frames with 3 pins.
    fn set_up(p: f64) -> (ConvConfig, Layout) {
        let mut c = ConvConfig::new(ModelKind::ConvMlp);
        c.conv = vec![ConvSpec {
            channels: 2,
            kernel: 3,
            stride: 2,
        }];
        c.dense = vec![4];
        (c.input, c.pixel_dropout) = (InputKind::PinsAndPixels, p);
        let layout = Layout::new(8, 8, &c.conv, &c.dense, 1).unwrap();
        (c, layout.with_side_inputs(1, 3).unwrap())
    }

    #[test]
    fn pixel_features_drop_whole_at_their_rate_and_come_back() {
        let (config, layout) = set_up(0.3);
        let mut ws = Workspace::for_training(&layout, 2);
        enable(&mut ws, &layout, &config);
        let draws = 4000;
        let mut dropped = 0;
        for key in 0..draws {
            draw(&mut ws, &layout, &config, (2, 1), key);
            // Frame 1's half of every map: all 0 or all 1; frame 0's kept.
            let n = layout.layers[0].positions();
            let frame: Vec<f32> = (0..2)
                .flat_map(|c| ws.mask[0][(c * 2 + 1) * n..][..n].to_vec())
                .collect();
            assert!(frame.iter().all(|&m| m == frame[0]) && (frame[0] == 0.0 || frame[0] == 1.0));
            assert!((0..2).all(|c| ws.mask[0][c * 2 * n..][..n].iter().all(|&m| m == 1.0)));
            dropped += usize::from(frame[0] == 0.0);
        }
        let rate = dropped as f64 / draws as f64;
        // Four standard deviations of a binomial share at 0.3.
        assert!(
            (rate - 0.3).abs() < 4.0 * (0.21f64 / draws as f64).sqrt(),
            "{rate}"
        );
        assert!(ws.mask[1].is_empty(), "the dense layer has no mask");
    }
}
