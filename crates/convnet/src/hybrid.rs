//! Pins and pixels (docs/learning.md, "Pins and pixels"): a tap's pin
//! displacement vector, standardised per column on the training rows,
//! appended to the flattened output of the last convolution as more
//! inputs of the first dense layer, `p = W [phi(s_conv); z] + b`.
//!
//! The pins are clamped inputs like the frame: they enter the energy only
//! through that layer's prediction, so the equilibria, the EP estimate
//! `-e z^T` of their weights' gradient and backprop's are those of any
//! other input column (the im2col matrix simply has `P` more rows), and
//! no error is sent down to them.
//!
//! The residual on a pin model (`input = "pin_model_and_pixels"`,
//! docs/learning.md): the side values are a base prediction `b` of the
//! targets, standardised as the targets are (`z = (b - mean) / std`), and
//! the model's output is `y = z + s(L)`. Training fits `s(L)` to the
//! correction `t - z`: with the linear output layer and the cost
//! `C = 1/2 ||s(L) - (t - z)||^2 = 1/2 ||y - t||^2`, the energy, its
//! equilibria and both learning rules are those of the plain network on
//! shifted targets, so the EP estimate still approaches the gradient of
//! the model's loss. The output layer starts at zero, so a fresh model
//! predicts `b` exactly.
use crate::config::{ConvConfig, InputKind};
use crate::data::Frames;
use crate::error::ConvError;
use crate::layout::{LayerShape, Layout};
use crate::network::Network;
use crate::scaling::{InputScaling, TargetScaling};
use crate::workspace::Workspace;

/// The side values' standardisation: `None` for a pixels-only
/// configuration; per column from the training frames' pins for a
/// pins-and-pixels one; `targets`' own for a base prediction (one value
/// an encoded target). Frames that carry no side values, or a base of
/// another width, are refused.
pub(crate) fn fit_pins(
    frames: &Frames,
    config: &ConvConfig,
    targets: &TargetScaling,
) -> Result<Option<TargetScaling>, ConvError> {
    let dim = frames.pin_dim();
    match config.input {
        InputKind::Pixels => return Ok(None),
        InputKind::PinModelAndPixels if dim == targets.dim() => return Ok(Some(targets.clone())),
        InputKind::PinModelAndPixels => {
            return Err(ConvError::PinCount {
                expected: targets.dim(),
                got: dim,
            })
        }
        InputKind::PinsAndPixels if dim == 0 => {
            return Err(ConvError::PinCount {
                expected: 1,
                got: 0,
            })
        }
        InputKind::PinsAndPixels => {}
    }
    let n = frames.count().max(1) as f64;
    let (mut mean, mut var) = (vec![0.0f64; dim], vec![0.0f64; dim]);
    for i in 0..frames.count() {
        let row = frames.pins(i).expect("pins checked above");
        mean.iter_mut().zip(row).for_each(|(m, &v)| *m += v as f64);
    }
    mean.iter_mut().for_each(|m| *m /= n);
    for i in 0..frames.count() {
        let row = frames.pins(i).expect("pins checked above");
        for ((s, m), &v) in var.iter_mut().zip(&mean).zip(row) {
            *s += (v as f64 - m).powi(2);
        }
    }
    let std = var
        .into_iter()
        .map(|v| v / n)
        .map(|v| if v > 1e-24 { v.sqrt() } else { 1.0 })
        .collect();
    Ok(Some(TargetScaling { mean, std }))
}

/// Refuse `frames` whose pins the model cannot read: none, or another
/// count, for a pins-and-pixels model (a pixels-only one ignores them).
pub(crate) fn check_pins(input: &InputScaling, frames: &Frames) -> Result<(), ConvError> {
    let expected = input.pin_count();
    if expected > 0 && frames.pin_dim() != expected {
        return Err(ConvError::PinCount {
            expected,
            got: frames.pin_dim(),
        });
    }
    Ok(())
}

/// The standardised pins of frames `rows` (the chunk's frames in order)
/// into `pins` (`P x nb`, value `j` of frame `b` at `j * nb + b`);
/// nothing for a pixels-only model.
pub(crate) fn load_pins(
    input: &InputScaling,
    frames: &Frames,
    rows: impl Iterator<Item = usize>,
    nb: usize,
    pins: &mut [f32],
) {
    let Some(scaling) = &input.pins else { return };
    for (b, i) in rows.enumerate() {
        let row = frames.pins(i).expect("pins checked before the pass");
        for (j, &v) in row.iter().enumerate() {
            pins[j * nb + b] = scaling.scale(j, v as f64);
        }
    }
}

/// Append the chunk's pins (`P x nb`) to the im2col matrix of the dense
/// layer `shape` that takes them, as its last `P` rows.
pub(crate) fn append_pins(shape: &LayerShape, nb: usize, pins: &[f32], cols: &mut [f32]) {
    let (first, count) = (shape.window() * nb, shape.side_inputs * nb);
    cols[first..first + count].copy_from_slice(&pins[..count]);
}

/// The layers of a model of `config` on `size` px frames with `outputs`
/// targets and `pins` pin values a frame (0 for pixels only), the pins
/// appended to the input of the first dense layer.
pub(crate) fn layout_for(
    config: &ConvConfig,
    size: (usize, usize),
    outputs: usize,
    pins: usize,
) -> Result<Layout, ConvError> {
    let layout = Layout::with_channels(
        config.input_channels(),
        size,
        &config.conv,
        &config.dense,
        outputs,
    )?;
    match (config.input, pins) {
        (InputKind::Pixels, 0) => Ok(layout),
        (InputKind::PinsAndPixels, p) if p > 0 => layout.with_side_inputs(config.conv.len(), p),
        (InputKind::PinModelAndPixels, p) if p == outputs => {
            layout.with_side_inputs(config.conv.len(), p)
        }
        (kind, got) => Err(ConvError::PinCount {
            expected: match kind {
                InputKind::Pixels => 0,
                InputKind::PinsAndPixels => 1,
                InputKind::PinModelAndPixels => outputs,
            },
            got,
        }),
    }
}

/// A base model's side scaling must be its target scaling (what the skip
/// adds is in standardised target units); refused otherwise.
pub(crate) fn check_base(input: &InputScaling, targets: &TargetScaling) -> Result<(), ConvError> {
    if input.base_skip && input.pins.as_ref() != Some(targets) {
        return Err(ConvError::Corrupt {
            reason: "a pin model's prediction is read in other units than the targets".into(),
        });
    }
    Ok(())
}

/// The training targets of a base model's chunk made corrections: `t -=
/// z`, both `outputs x nb` in standardised units (`pins` holds `z`).
pub(crate) fn subtract_base(input: &InputScaling, nb: usize, pins: &[f32], t: &mut [f32]) {
    if input.base_skip {
        let n = input.pin_count() * nb;
        t[..n].iter_mut().zip(&pins[..n]).for_each(|(t, z)| *t -= z);
    }
}

/// The skip of a base model after its feed-forward pass: the output
/// `s(L) += z`, so `s(L)` holds the model's prediction `y` (scaled).
pub(crate) fn add_base(net: &Network, input: &InputScaling, ws: &mut Workspace, nb: usize) {
    if input.base_skip {
        let n = input.pin_count() * nb;
        let last = net.layout.depth() - 1;
        let (s, z) = (&mut ws.s[last], &ws.pins);
        s[..n].iter_mut().zip(&z[..n]).for_each(|(s, z)| *s += z);
    }
}

/// The output layer's weights and bias set to zero: a fresh base model's
/// correction path, so that it predicts the base until it learns.
pub(crate) fn zero_output(net: &mut Network) {
    let last = net.layout.depth() - 1;
    net.params.weights[last].fill(0.0);
    net.params.biases[last].fill(0.0);
}
