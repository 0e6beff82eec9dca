//! Prediction: the free phase's equilibrium, which for this energy is the
//! feed-forward pass (one pass a frame, no relaxation), on reusable
//! buffers. A [`Predictor`] serves one frame at a time without
//! allocating; whole sets run in chunks, one block of frames a thread.
use crate::data::Frames;
use crate::network::Network;
use crate::pass::feed_forward;
use crate::scaling::{InputScaling, TargetScaling};
use crate::workspace::Workspace;
use rayon::prelude::*;

/// Frames per chunk when predicting a whole set.
pub(crate) const PREDICT_CHUNK: usize = 16;

/// Reusable buffers for [`crate::ConvModel::predict_with`].
#[derive(Debug, Clone)]
pub struct Predictor {
    pub(crate) ws: Workspace,
    /// One network's outputs, for an ensemble's mean.
    pub(crate) member: Vec<f64>,
}

/// Standardise frames `first..first + nb` of `frames` into `ws.x` (and
/// their pins into `ws.pins`, for a pins-and-pixels model) and run
/// the feed-forward pass; the outputs are left in the last layer's `s`
/// (`outputs x nb`, scaled units; a base model's base added).
pub(crate) fn forward_frames(
    net: &Network,
    input: &InputScaling,
    ws: &mut Workspace,
    frames: &Frames,
    first: usize,
    nb: usize,
) {
    let (h, w) = frames.size();
    let hw = h * w;
    for b in 0..nb {
        input.apply(frames.frame(first + b), &mut ws.x[b * hw..(b + 1) * hw]);
    }
    crate::hybrid::load_pins(input, frames, first..first + nb, nb, &mut ws.pins);
    feed_forward(net, ws, nb);
    crate::hybrid::add_base(net, input, ws, nb);
}

/// The last layer's output of frame `b` of an `nb`-frame chunk, unscaled.
pub(crate) fn unscaled_output(
    net: &Network,
    ws: &Workspace,
    scaling: &TargetScaling,
    nb: usize,
    b: usize,
    out: &mut [f64],
) {
    let y = &ws.s[net.layout.depth() - 1];
    for (j, o) in out.iter_mut().enumerate() {
        *o = scaling.unscale(j, y[j * nb + b]);
    }
}

/// Every frame's prediction, unscaled, into `out` (`count x outputs`),
/// the frames split into one contiguous block a workspace of `pool`.
pub(crate) fn predict_all(
    net: &Network,
    input: &InputScaling,
    scaling: &TargetScaling,
    frames: &Frames,
    pool: &mut [Workspace],
    out: &mut [f64],
) {
    let k = net.layout.outputs();
    let n = frames.count();
    if n == 0 || pool.is_empty() {
        return;
    }
    let block = n.div_ceil(pool.len());
    pool.par_iter_mut()
        .zip(out.par_chunks_mut(block * k))
        .enumerate()
        .for_each(|(i, (ws, out))| {
            let start = i * block;
            let end = (start + block).min(n);
            let mut first = start;
            while first < end {
                let nb = (end - first).min(ws.cap);
                forward_frames(net, input, ws, frames, first, nb);
                for b in 0..nb {
                    let row = &mut out[(first - start + b) * k..][..k];
                    unscaled_output(net, ws, scaling, nb, b, row);
                }
                first += nb;
            }
        });
}

/// Workspaces for [`predict_all`]: one a thread of the current pool.
pub(crate) fn prediction_pool(net: &Network) -> Vec<Workspace> {
    (0..rayon::current_num_threads().max(1))
        .map(|_| Workspace::for_prediction(&net.layout, PREDICT_CHUNK))
        .collect()
}
