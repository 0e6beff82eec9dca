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
use crate::config::ConvConfig;
use crate::layout::Layout;
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

/// Give `ws` a mask buffer for every layer whose rate is above 0.
pub(crate) fn enable(ws: &mut Workspace, layout: &Layout, config: &ConvConfig) {
    for l in 0..layout.depth() {
        if rate(layout, config, l) > 0.0 {
            let len = layout.layers[l].out_len() * ws.cap;
            ws.mask[l] = vec![1.0; len];
            ws.masked[l] = vec![0.0; len];
        }
    }
}

/// Draw frame `b`'s masks (of an `nb`-frame chunk) into `ws`, from a
/// generator seeded with `key`: one draw a unit of a dense layer, one a
/// feature map of a convolutional layer (the same value at every
/// position).
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
