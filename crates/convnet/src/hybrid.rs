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
use crate::config::{ConvConfig, InputKind};
use crate::data::Frames;
use crate::error::ConvError;
use crate::layout::{LayerShape, Layout};
use crate::scaling::{InputScaling, TargetScaling};

/// The pins' per-column standardisation from the training frames' pins,
/// `None` for a pixels-only configuration; a pins-and-pixels one refuses
/// frames that carry no pins.
pub(crate) fn fit_pins(
    frames: &Frames,
    config: &ConvConfig,
) -> Result<Option<TargetScaling>, ConvError> {
    if config.input == InputKind::Pixels {
        return Ok(None);
    }
    let dim = frames.pin_dim();
    if dim == 0 {
        return Err(ConvError::PinCount {
            expected: 1,
            got: 0,
        });
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
        (_, got) => Err(ConvError::PinCount {
            expected: usize::from(config.input == InputKind::PinsAndPixels),
            got,
        }),
    }
}
