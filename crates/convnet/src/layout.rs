//! The geometry of every layer, worked out once from the input size and
//! the configuration. A dense layer is the convolution whose window covers
//! its whole input (no padding, one output position), so one code path
//! (im2col, then a matrix product) serves both kinds.
use crate::config::ConvSpec;
use crate::error::{config_error, ConvError};

/// Most values a layer's input or output may hold per frame.
const MAX_VALUES: usize = 1 << 24;

/// One layer's linear map `W(l)`: input `cin x hin x win`, output
/// `cout x hout x wout`, window `kh x kw` moved by `stride`, the input
/// zero-padded by `pad` on every side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LayerShape {
    pub cin: usize,
    pub hin: usize,
    pub win: usize,
    pub cout: usize,
    pub hout: usize,
    pub wout: usize,
    pub kh: usize,
    pub kw: usize,
    pub stride: usize,
    pub pad: usize,
    /// Values appended to the window after the `cin x kh x kw` ones: the
    /// pin displacement vector on the first dense layer of a
    /// pins-and-pixels model (clamped inputs, like the frame), 0
    /// elsewhere.
    pub side_inputs: usize,
}

impl LayerShape {
    /// A convolution of `spec` on a `cin x hin x win` input.
    fn conv(cin: usize, hin: usize, win: usize, spec: &ConvSpec) -> Result<Self, ConvError> {
        let (k, s, pad) = (spec.kernel, spec.stride, spec.kernel / 2);
        if hin + 2 * pad < k || win + 2 * pad < k {
            return Err(config_error(
                "conv",
                format!("a {k} x {k} kernel does not fit a {hin} x {win} input"),
            ));
        }
        Ok(LayerShape {
            cin,
            hin,
            win,
            cout: spec.channels,
            hout: (hin + 2 * pad - k) / s + 1,
            wout: (win + 2 * pad - k) / s + 1,
            kh: k,
            kw: k,
            stride: s,
            pad,
            side_inputs: 0,
        })
    }

    /// A dense layer of `cout` units on a `cin x hin x win` input.
    fn dense(cin: usize, hin: usize, win: usize, cout: usize) -> Self {
        LayerShape {
            cin,
            hin,
            win,
            cout,
            hout: 1,
            wout: 1,
            kh: hin,
            kw: win,
            stride: 1,
            pad: 0,
            side_inputs: 0,
        }
    }

    /// The fan-in: rows of the im2col matrix, columns of `W(l)` (the
    /// window, then any side inputs).
    pub fn fan_in(&self) -> usize {
        self.window() + self.side_inputs
    }

    /// Values of one window of the layer below (`cin x kh x kw`): the
    /// im2col rows that come from it.
    pub fn window(&self) -> usize {
        self.cin * self.kh * self.kw
    }

    /// Output positions per frame (`hout * wout`).
    pub fn positions(&self) -> usize {
        self.hout * self.wout
    }

    /// Values of the input per frame.
    pub fn in_len(&self) -> usize {
        self.cin * self.hin * self.win
    }

    /// Values of the output per frame.
    pub fn out_len(&self) -> usize {
        self.cout * self.positions()
    }

    /// Weights of `W(l)` (`cout x fan_in`).
    pub fn weights(&self) -> usize {
        self.cout * self.fan_in()
    }

    /// Whether the window covers the whole input (a dense layer).
    pub fn is_dense(&self) -> bool {
        self.kh == self.hin && self.kw == self.win && self.pad == 0 && self.positions() == 1
    }
}

/// Every layer of a network, input side first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    pub(crate) layers: Vec<LayerShape>,
}

impl Layout {
    /// Layers for a one-channel `height x width` input: the convolutions of
    /// `conv`, the dense hidden layers `dense`, and `outputs` linear units.
    pub fn new(
        height: usize,
        width: usize,
        conv: &[ConvSpec],
        dense: &[usize],
        outputs: usize,
    ) -> Result<Self, ConvError> {
        Self::with_channels(1, (height, width), conv, dense, outputs)
    }

    /// [`Self::new`] for an input of `channels` planes of `(height,
    /// width)` px (the frame first; more planes are the coordinate
    /// channels, which the network fills itself).
    pub fn with_channels(
        channels: usize,
        (height, width): (usize, usize),
        conv: &[ConvSpec],
        dense: &[usize],
        outputs: usize,
    ) -> Result<Self, ConvError> {
        if channels == 0 || height == 0 || width == 0 || outputs == 0 {
            return Err(config_error(
                "input",
                format!(
                    "{channels} x {height} x {width} px inputs and {outputs} outputs: none may be 0"
                ),
            ));
        }
        let mut layers = Vec::new();
        let (mut c, mut h, mut w) = (channels, height, width);
        for spec in conv {
            let shape = LayerShape::conv(c, h, w, spec)?;
            (c, h, w) = (shape.cout, shape.hout, shape.wout);
            layers.push(shape);
        }
        for &units in dense.iter().chain([&outputs]) {
            let shape = LayerShape::dense(c, h, w, units);
            (c, h, w) = (units, 1, 1);
            layers.push(shape);
        }
        for s in &layers {
            if s.in_len() > MAX_VALUES || s.out_len() > MAX_VALUES || s.weights() > MAX_VALUES {
                return Err(config_error(
                    "conv",
                    format!(
                        "a layer of {} x {} x {} -> {} x {} x {} values is larger than {MAX_VALUES}",
                        s.cin, s.hin, s.win, s.cout, s.hout, s.wout
                    ),
                ));
            }
        }
        Ok(Layout { layers })
    }

    /// The same layers with `count` side inputs (the pin displacement
    /// vector) appended to the input of layer `layer`, which must be a
    /// dense one (the first after the convolutions: concatenated after
    /// the flatten).
    pub fn with_side_inputs(mut self, layer: usize, count: usize) -> Result<Self, ConvError> {
        let Some(shape) = self.layers.get_mut(layer).filter(|s| s.is_dense()) else {
            return Err(config_error(
                "input",
                format!("layer {layer} is not a dense layer to take side inputs"),
            ));
        };
        if count > MAX_VALUES / shape.cout.max(1) {
            return Err(config_error("input", format!("{count} side inputs")));
        }
        shape.side_inputs = count;
        Ok(self)
    }

    /// Side inputs (pins) the network takes, 0 for a pixels-only one.
    pub fn side_inputs(&self) -> usize {
        self.layers.iter().map(|s| s.side_inputs).sum()
    }

    /// The layers, input side first.
    pub fn layers(&self) -> &[LayerShape] {
        &self.layers
    }

    /// Number of layers `L` (the output layer is the last).
    pub fn depth(&self) -> usize {
        self.layers.len()
    }

    /// Input `(height, width)`, px.
    pub fn input_size(&self) -> (usize, usize) {
        (self.layers[0].hin, self.layers[0].win)
    }

    /// Input planes: 1, the frame, or 3 with the coordinate channels.
    pub fn input_channels(&self) -> usize {
        self.layers[0].cin
    }

    /// Output units (targets).
    pub fn outputs(&self) -> usize {
        self.layers[self.layers.len() - 1].cout
    }

    /// Parameters (weights and biases) in all.
    pub fn parameters(&self) -> usize {
        self.layers.iter().map(|s| s.weights() + s.cout).sum()
    }

    /// Multiply-adds of one feed-forward pass of one frame.
    pub fn forward_macs(&self) -> usize {
        self.layers
            .iter()
            .map(|s| s.weights() * s.positions())
            .sum()
    }
}
