//! A convolutional dendritic network on its own (layers, activation,
//! parameters), with frame-level entry points for the theory tests and the
//! bench: the feed-forward pass, a layer's linear map and its transpose,
//! the backprop gradient, the EP estimate of it, and the relaxations with
//! their energy and distance from equilibrium. Inputs here are already
//! standardised f32 frames; [`crate::ConvModel`] does the scaling.
use crate::config::{Activation, ClampedPhase, EpSettings, FreePhase};
use crate::ep::{
    backprop_gradient, clamped_phase, consistent_errors, ep_gradient, free_phase, stationarity,
    total_energy,
};
use crate::error::ConvError;
use crate::gemm::product_tn;
use crate::im2col::{col2im, im2col};
use crate::layout::Layout;
use crate::params::Parameters;
use crate::workspace::Workspace;

/// Layers, activation and parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Network {
    pub(crate) layout: Layout,
    pub(crate) activation: Activation,
    pub(crate) params: Parameters,
}

/// Which gradient [`Network::gradient`] computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rule {
    /// The exact gradient of `0.5 ||y - t||^2` (the `conv-mlp` twin).
    Backprop,
    /// Its equilibrium-propagation estimate (`conv-dennn`).
    Ep(EpSettings),
}

/// What a relaxation reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium {
    /// The output potentials `s(L)`, frame by frame (`n x outputs`).
    pub output: Vec<f32>,
    /// `F = E + beta C` at the end, summed over frames.
    pub energy: f64,
    /// `||dF/ds||` at the end (0 at an exact equilibrium).
    pub stationarity: f64,
}

impl Network {
    /// Weights from `seed` ([`Parameters::init`]).
    pub fn new(layout: Layout, activation: Activation, seed: u64) -> Self {
        let params = Parameters::init(&layout, activation, seed);
        Network {
            layout,
            activation,
            params,
        }
    }

    /// Given parameters, checked against the layout's shapes.
    pub fn from_parts(
        layout: Layout,
        activation: Activation,
        params: Parameters,
    ) -> Result<Self, ConvError> {
        let expected = Parameters::zeros(&layout);
        let n = layout.depth();
        if params.weights.len() != n || params.biases.len() != n {
            return Err(ConvError::Shape {
                what: "parameter tensors",
                expected: 2 * n,
                got: params.weights.len() + params.biases.len(),
            });
        }
        for (got, want) in params.values().zip(expected.values()) {
            if got.len() != want.len() {
                return Err(ConvError::Shape {
                    what: "parameter tensor",
                    expected: want.len(),
                    got: got.len(),
                });
            }
        }
        Ok(Network {
            layout,
            activation,
            params,
        })
    }

    /// The layers.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The hidden units' rate function.
    pub fn activation(&self) -> Activation {
        self.activation
    }

    /// The weights and biases.
    pub fn parameters(&self) -> &Parameters {
        &self.params
    }

    /// The weights and biases, to change (shapes must stay).
    pub fn parameters_mut(&mut self) -> &mut Parameters {
        &mut self.params
    }

    /// A workspace holding `n` frames `x` (`n x h x w`) and targets `t`
    /// (`n x outputs`, frame by frame) in the chunk layout.
    fn load(&self, x: &[f32], t: Option<&[f32]>, n: usize) -> Result<Workspace, ConvError> {
        self.load_pins(x, &[], t, n)
    }

    /// [`Self::load`] with each frame's standardised pins `z` (`n x P`,
    /// frame by frame; empty for a network of pixels only).
    fn load_pins(
        &self,
        x: &[f32],
        z: &[f32],
        t: Option<&[f32]>,
        n: usize,
    ) -> Result<Workspace, ConvError> {
        let (h, w) = self.layout.input_size();
        let k = self.layout.outputs();
        let p = self.layout.side_inputs();
        check_len("frames", x.len(), n * h * w)?;
        check_len("pins", z.len(), n * p)?;
        let mut ws = Workspace::for_training(&self.layout, n.max(1));
        ws.x[..n * h * w].copy_from_slice(x);
        for (b, row) in z.chunks_exact(p.max(1)).enumerate() {
            row.iter()
                .enumerate()
                .for_each(|(j, &v)| ws.pins[j * n + b] = v);
        }
        if let Some(t) = t {
            check_len("targets", t.len(), n * k)?;
            for b in 0..n {
                for o in 0..k {
                    ws.t[o * n + b] = t[b * k + o];
                }
            }
        }
        Ok(ws)
    }

    /// The output of `n` frames (`n x h x w`), frame by frame: the
    /// feed-forward pass, which is the free phase's equilibrium.
    pub fn feed_forward(&self, x: &[f32], n: usize) -> Result<Vec<f32>, ConvError> {
        self.feed_forward_masked(x, n, &[])
    }

    /// [`Self::feed_forward`] with dropout masks: `masks[l]` multiplies
    /// layer `l`'s rates (0-based, frame by frame, `n x out_len`; an empty
    /// vector, or a missing entry, is no mask).
    pub fn feed_forward_masked(
        &self,
        x: &[f32],
        n: usize,
        masks: &[Vec<f32>],
    ) -> Result<Vec<f32>, ConvError> {
        let mut ws = self.load(x, None, n)?;
        self.load_masks(&mut ws, masks, n)?;
        free_phase(self, &mut ws, n, FreePhase::FeedForward);
        Ok(self.output_of(&ws, n))
    }

    /// Check the masks' shapes and put them in `ws`.
    fn load_masks(
        &self,
        ws: &mut Workspace,
        masks: &[Vec<f32>],
        n: usize,
    ) -> Result<(), ConvError> {
        if masks.len() > self.layout.depth() {
            return Err(ConvError::Shape {
                what: "dropout masks (one a layer)",
                expected: self.layout.depth(),
                got: masks.len(),
            });
        }
        for (m, shape) in masks.iter().zip(&self.layout.layers) {
            if !m.is_empty() {
                check_len("dropout mask", m.len(), n * shape.out_len())?;
            }
        }
        crate::dropout::load(ws, &self.layout, masks, n);
        Ok(())
    }

    /// [`Self::feed_forward`] of a pins-and-pixels network: `n` frames `x`
    /// and their standardised pins `z` (`n x P`, frame by frame).
    pub fn feed_forward_pins(&self, x: &[f32], z: &[f32], n: usize) -> Result<Vec<f32>, ConvError> {
        let mut ws = self.load_pins(x, z, None, n)?;
        free_phase(self, &mut ws, n, FreePhase::FeedForward);
        Ok(self.output_of(&ws, n))
    }

    /// [`Self::gradient`] of a pins-and-pixels network: `n` frames `x`,
    /// their standardised pins `z` (`n x P`) and targets `t`.
    pub fn gradient_pins(
        &self,
        (x, z): (&[f32], &[f32]),
        t: &[f32],
        n: usize,
        rule: Rule,
    ) -> Result<Parameters, ConvError> {
        let mut ws = self.load_pins(x, z, Some(t), n)?;
        self.gradient_of(&mut ws, n, rule)
    }

    /// The gradient of `sum 0.5 ||y - t||^2` over `n` frames, or its EP
    /// estimate.
    pub fn gradient(
        &self,
        x: &[f32],
        t: &[f32],
        n: usize,
        rule: Rule,
    ) -> Result<Parameters, ConvError> {
        self.gradient_masked(x, t, n, rule, &[])
    }

    /// [`Self::gradient`] of the network with dropout masks `masks` (as
    /// [`Self::feed_forward_masked`]), held through every phase.
    pub fn gradient_masked(
        &self,
        x: &[f32],
        t: &[f32],
        n: usize,
        rule: Rule,
        masks: &[Vec<f32>],
    ) -> Result<Parameters, ConvError> {
        let mut ws = self.load(x, Some(t), n)?;
        self.load_masks(&mut ws, masks, n)?;
        self.gradient_of(&mut ws, n, rule)
    }

    /// The gradient (or its estimate) of the `n` frames loaded in `ws`.
    fn gradient_of(
        &self,
        ws: &mut Workspace,
        n: usize,
        rule: Rule,
    ) -> Result<Parameters, ConvError> {
        match rule {
            Rule::Backprop => backprop_gradient(self, ws, n),
            Rule::Ep(ep) => {
                ep.validate()?;
                ep_gradient(self, ws, n, &ep)
            }
        };
        Ok(ws
            .grad
            .take()
            .unwrap_or_else(|| Parameters::zeros(&self.layout)))
    }

    /// Relax `n` frames: the free phase `free`, then (with a target) a
    /// clamped phase at signed `beta` from there.
    pub fn relax(
        &self,
        x: &[f32],
        clamp: Option<(&[f32], f64, ClampedPhase)>,
        free: FreePhase,
        n: usize,
    ) -> Result<Equilibrium, ConvError> {
        let mut ws = self.load(x, clamp.map(|c| c.0), n)?;
        free_phase(self, &mut ws, n, free);
        let beta = clamp.map_or(0.0, |c| c.1 as f32);
        if let Some((_, _, phase)) = clamp {
            clamped_phase(self, &mut ws, n, beta, phase);
        }
        consistent_errors(self, &mut ws, n);
        Ok(Equilibrium {
            output: self.output_of(&ws, n),
            energy: total_energy(self, &ws, n, beta),
            stationarity: stationarity(self, &mut ws, n, beta),
        })
    }

    /// Layer `l`'s linear map (0-based) on one frame's input to it
    /// (`cin x hin x win`): `W(l) * input`, no bias, `cout x hout x wout`.
    pub fn layer_map(&self, l: usize, input: &[f32]) -> Result<Vec<f32>, ConvError> {
        let s = self.layer(l)?;
        check_len("layer input", input.len(), s.in_len())?;
        let mut cols = vec![0.0; s.fan_in() * s.positions()];
        im2col(s, 1, input, &mut cols);
        let mut out = vec![0.0; s.out_len()];
        crate::gemm::product(
            &mut out,
            &self.params.weights[l],
            &cols,
            s.cout,
            s.fan_in(),
            s.positions(),
        );
        Ok(out)
    }

    /// The transpose of [`Self::layer_map`]: `W(l)^T output` (col2im of
    /// the product), `cin x hin x win`.
    pub fn layer_map_transposed(&self, l: usize, output: &[f32]) -> Result<Vec<f32>, ConvError> {
        let s = self.layer(l)?;
        check_len("layer output", output.len(), s.out_len())?;
        let mut cols = vec![0.0; s.fan_in() * s.positions()];
        product_tn(
            &mut cols,
            &self.params.weights[l],
            output,
            s.cout,
            s.fan_in(),
            s.positions(),
        );
        let mut out = vec![0.0; s.in_len()];
        col2im(s, 1, &cols, &mut out);
        Ok(out)
    }

    fn layer(&self, l: usize) -> Result<&crate::layout::LayerShape, ConvError> {
        self.layout.layers.get(l).ok_or(ConvError::Shape {
            what: "layer index",
            expected: self.layout.depth(),
            got: l,
        })
    }

    /// The output layer's potentials, frame by frame.
    fn output_of(&self, ws: &Workspace, n: usize) -> Vec<f32> {
        let k = self.layout.outputs();
        let s = &ws.s[self.layout.depth() - 1];
        (0..n * k).map(|i| s[(i % k) * n + i / k]).collect()
    }
}

fn check_len(what: &'static str, got: usize, expected: usize) -> Result<(), ConvError> {
    if got != expected {
        return Err(ConvError::Shape {
            what,
            expected,
            got,
        });
    }
    Ok(())
}
