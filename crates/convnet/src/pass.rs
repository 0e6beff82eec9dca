//! The local computations every learning rule is made of, on a chunk of
//! `nb` frames:
//! - a layer's dendritic prediction `p(l) = W(l) * phi(s(l-1)) + b(l)`
//!   (im2col, then one matrix product);
//! - a layer's top-down input `phi'(s(l-1)) . W(l)^T e(l)` (one product
//!   with `W(l)^T`, then col2im);
//! - the weight term `dE/dW(l) = -e(l) phi(s(l-1))^T` summed over frames
//!   and positions (one product with the im2col matrix transposed), and
//!   `dE/db(l) = -sum e(l)`.
//!
//! A pins-and-pixels model's first dense layer has the pins as the last
//! rows of its im2col matrix (`crate::hybrid`).
//!
//! With dropout a layer's rates and its top-down input are multiplied by
//! its mask (`crate::dropout`).
//!
//! With the energy `E = 1/2 sum_l ||e(l)||^2` these are the terms of
//! `dE/ds` and `dE/dW` (Scellier and Bengio 2017, eqs. 2 and 13, for this
//! energy; docs/learning.md).
use crate::gemm::{add_product_nt, product, product_tn};
use crate::im2col::{col2im_times_slope, im2col};
use crate::network::Network;
use crate::settle::{settle, Errors, Settle};
use crate::workspace::Workspace;

/// `cols(l) = im2col(phi(s(l-1)))` and `p(l) = W(l) cols(l) + b(l)` for
/// layer index `l` (0-based).
pub(crate) fn predict_layer(net: &Network, ws: &mut Workspace, nb: usize, l: usize) {
    layer_product(net, ws, nb, l);
    let n = nb * net.layout.layers[l].positions();
    let rows = ws.p[l].chunks_exact_mut(n);
    for (row, &b) in rows.zip(&net.params.biases[l]) {
        row.iter_mut().for_each(|v| *v += b);
    }
}

/// `cols(l) = im2col(phi(s(l-1)))` and `p(l) = W(l) cols(l)`, the bias
/// still to add (by [`settle_layer`] or [`predict_layer`]).
fn layer_product(net: &Network, ws: &mut Workspace, nb: usize, l: usize) {
    let shape = &net.layout.layers[l];
    if l == 0 && shape.cin > 1 {
        coordinate_planes(shape, nb, &mut ws.x);
    }
    let input: &[f32] = match l {
        0 => &ws.x,
        _ if ws.mask[l - 1].is_empty() => &ws.a[l - 1],
        _ => {
            // Dropout: the layer above reads the masked rates.
            let (m, a) = (&ws.mask[l - 1], &ws.a[l - 1]);
            let out = &mut ws.masked[l - 1];
            out.iter_mut()
                .zip(m.iter().zip(a))
                .for_each(|(o, (m, a))| *o = m * a);
            &ws.masked[l - 1]
        }
    };
    im2col(shape, nb, input, &mut ws.cols[l]);
    if shape.side_inputs > 0 {
        crate::hybrid::append_pins(shape, nb, &ws.pins, &mut ws.cols[l]);
    }
    let n = nb * shape.positions();
    let (m, k) = (shape.cout, shape.fan_in());
    let p = &mut ws.p[l];
    product(p, &net.params.weights[l], &ws.cols[l], m, k, n);
}

/// The coordinate channels of an `nb`-frame chunk, after its frames
/// (channel 0): channel 1 holds each pixel's column, channel 2 its row,
/// both scaled to [-1, 1]. They are clamped inputs like the frame, so the
/// energy and its equilibria are unchanged (docs/learning.md).
fn coordinate_planes(shape: &crate::layout::LayerShape, nb: usize, x: &mut [f32]) {
    let (h, w) = (shape.hin, shape.win);
    let scale = |i: usize, n: usize| {
        if n > 1 {
            2.0 * i as f32 / (n - 1) as f32 - 1.0
        } else {
            0.0
        }
    };
    let plane = nb * h * w;
    let (cols, rows) = x[plane..3 * plane].split_at_mut(plane);
    for (k, (c, r)) in cols
        .chunks_exact_mut(w)
        .zip(rows.chunks_exact_mut(w))
        .enumerate()
    {
        c.iter_mut().enumerate().for_each(|(i, v)| *v = scale(i, w));
        r.fill(scale(k % h, h));
    }
}

/// Layer `l` settles on the layer below as it now is: for `l >= 1` its
/// prediction `p(l)` anew, then `s(l) = p(l) + e(l)` and, below the
/// output, `phi(s(l))`, in one pass after the product. The first layer's
/// input never moves, so its prediction stands.
pub(crate) fn settle_layer(net: &Network, ws: &mut Workspace, nb: usize, l: usize) {
    if l > 0 {
        layer_product(net, ws, nb, l);
    }
    let bias = (l > 0).then_some(&net.params.biases[l][..]);
    settle_with(net, ws, nb, l, bias, Errors::Held);
}

/// [`settle`] on layer `l`'s buffers (`bias`: add it to `p(l)` first).
fn settle_with(
    net: &Network,
    ws: &mut Workspace,
    nb: usize,
    l: usize,
    bias: Option<&[f32]>,
    errors: Errors,
) {
    let len = net.layout.layers[l].out_len() * nb;
    settle(Settle {
        activation: net.activation,
        bias,
        errors,
        p: &mut ws.p[l][..len],
        e: &mut ws.e[l],
        s: &mut ws.s[l],
        a: (l + 1 < net.layout.depth()).then(|| &mut ws.a[l][..]),
    });
}

/// The free phase's equilibrium, the feed-forward pass: every `e(l) = 0`,
/// `s(l) = p(l)`.
pub(crate) fn feed_forward(net: &Network, ws: &mut Workspace, nb: usize) {
    for l in 0..net.layout.depth() {
        layer_product(net, ws, nb, l);
        let bias = &net.params.biases[l][..];
        settle_with(net, ws, nb, l, Some(bias), Errors::Zero);
    }
}

/// `dst = phi'(s(l-1)) . W(l)^T src` for layer index `l >= 1`, where `src`
/// is layer `l`'s error (`cout x nb x positions`) and `dst` has layer
/// `l - 1`'s output shape.
pub(crate) fn send_down(net: &Network, ws: &mut Workspace, nb: usize, l: usize, into_down: bool) {
    let shape = &net.layout.layers[l];
    let n = nb * shape.positions();
    let (m, k) = (shape.cout, shape.fan_in());
    product_tn(&mut ws.dcols, &net.params.weights[l], &ws.e[l], m, k, n);
    let len = shape.in_len() * nb;
    let dst = if into_down {
        &mut ws.down[l - 1]
    } else {
        &mut ws.e[l - 1]
    };
    let rate = &ws.a[l - 1][..len];
    col2im_times_slope(shape, nb, &ws.dcols, dst, net.activation, rate);
    let mask = &ws.mask[l - 1];
    if !mask.is_empty() {
        dst[..len]
            .iter_mut()
            .zip(&mask[..len])
            .for_each(|(d, m)| *d *= m);
    }
}

/// `grad += coeff (e(l) cols(l)^T, sum e(l))` for every layer: `coeff =
/// -1` adds `dE/dtheta`, `+1` with backprop's deltas in `e` adds the
/// loss gradient.
pub(crate) fn accumulate_gradient(net: &Network, ws: &mut Workspace, nb: usize, coeff: f32) {
    let Some(grad) = ws.grad.as_mut() else { return };
    for (l, shape) in net.layout.layers.iter().enumerate() {
        let n = nb * shape.positions();
        let (m, k) = (shape.cout, shape.fan_in());
        add_product_nt(&mut grad.weights[l], coeff, &ws.e[l], &ws.cols[l], m, k, n);
        for (g, row) in grad.biases[l]
            .iter_mut()
            .zip(ws.e[l][..m * n].chunks_exact(n))
        {
            *g += coeff * row.iter().sum::<f32>();
        }
    }
}

/// `0.5 ||y - t||^2` summed over the chunk, at the output `s(L)`.
pub(crate) fn output_loss(net: &Network, ws: &Workspace, nb: usize) -> f64 {
    let last = net.layout.depth() - 1;
    let len = net.layout.outputs() * nb;
    ws.s[last][..len]
        .iter()
        .zip(&ws.t[..len])
        .map(|(y, t)| 0.5 * ((y - t) as f64).powi(2))
        .sum()
}
