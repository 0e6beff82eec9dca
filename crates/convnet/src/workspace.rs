//! Every buffer one chunk of frames needs, allocated once and reused, so
//! the training and prediction loops allocate nothing. A chunk of `nb`
//! frames stores each layer `channels x nb x h x w`; the dendritic
//! compartments of layer `l` are its somatic potentials `s`, the basal
//! dendrite's prediction `p = W(l) * phi(s(l-1)) + b(l)` and the error
//! `e = s - p` between them.
use crate::layout::Layout;
use crate::params::Parameters;

/// The free-phase state kept while a nudged phase runs, so the other
/// nudged phase can start from it again.
#[derive(Debug, Clone)]
pub(crate) struct Saved {
    pub s: Vec<Vec<f32>>,
    pub p: Vec<Vec<f32>>,
    pub a: Vec<Vec<f32>>,
    pub cols: Vec<Vec<f32>>,
}

/// Buffers for up to `cap` frames.
#[derive(Debug, Clone)]
pub(crate) struct Workspace {
    /// Frames a chunk may hold.
    pub cap: usize,
    /// The standardised input, `channels x nb x h x w` (the frames, then
    /// any coordinate planes).
    pub x: Vec<f32>,
    /// The standardised pins of a pins-and-pixels model, `P x nb` (empty
    /// for pixels only).
    pub pins: Vec<f32>,
    /// The standardised targets, `outputs x nb`.
    pub t: Vec<f32>,
    /// Somatic potentials `s(l)` (index `l - 1`).
    pub s: Vec<Vec<f32>>,
    /// Dendritic predictions `p(l) = W(l) * phi(s(l-1)) + b(l)`.
    pub p: Vec<Vec<f32>>,
    /// Dendritic errors `e(l) = s(l) - p(l)` (backprop: the deltas).
    pub e: Vec<Vec<f32>>,
    /// Rates `phi(s(l))` (the output layer's is unused: it is linear).
    pub a: Vec<Vec<f32>>,
    /// im2col of each layer's input.
    pub cols: Vec<Vec<f32>>,
    /// Top-down input `phi'(s(l)) . W(l+1)^T e(l+1)` of each layer (Euler).
    pub down: Vec<Vec<f32>>,
    /// Scratch for `W(l)^T e(l)` before col2im.
    pub dcols: Vec<f32>,
    /// The free phase, kept for the second nudged phase.
    pub saved: Option<Saved>,
    /// Gradient (or its EP estimate) summed over the chunk's frames.
    pub grad: Option<Parameters>,
    /// Each layer's dropout mask `m(l)` (0 or `1 / (1 - p)` a unit, held
    /// through every phase of a frame), empty where there is no dropout
    /// (always at prediction).
    pub mask: Vec<Vec<f32>>,
    /// Scratch for the masked rates `m(l) . phi(s(l))` the layer above
    /// reads, beside each mask.
    pub masked: Vec<Vec<f32>>,
}

impl Workspace {
    /// Buffers for prediction only (no gradient, no saved phase).
    pub fn for_prediction(layout: &Layout, cap: usize) -> Self {
        let per_layer = |len: &dyn Fn(usize) -> usize| -> Vec<Vec<f32>> {
            (0..layout.depth()).map(|l| vec![0.0; len(l)]).collect()
        };
        let out = |l: usize| layout.layers[l].out_len() * cap;
        let cols = |l: usize| layout.layers[l].fan_in() * layout.layers[l].positions() * cap;
        Workspace {
            cap,
            x: vec![0.0; layout.layers[0].in_len() * cap],
            pins: vec![0.0; layout.side_inputs() * cap],
            t: vec![0.0; layout.outputs() * cap],
            s: per_layer(&out),
            p: per_layer(&out),
            e: per_layer(&out),
            a: per_layer(&out),
            cols: per_layer(&cols),
            down: Vec::new(),
            dcols: Vec::new(),
            saved: None,
            grad: None,
            mask: vec![Vec::new(); layout.depth()],
            masked: vec![Vec::new(); layout.depth()],
        }
    }

    /// Buffers for training: prediction's, plus the top-down scratch, the
    /// saved free phase and a gradient accumulator.
    pub fn for_training(layout: &Layout, cap: usize) -> Self {
        let mut ws = Self::for_prediction(layout, cap);
        let largest = layout
            .layers
            .iter()
            .map(|s| s.fan_in() * s.positions() * cap)
            .max()
            .unwrap_or(0);
        ws.dcols = vec![0.0; largest];
        ws.down = ws.s.clone();
        ws.saved = Some(Saved {
            s: ws.s.clone(),
            p: ws.p.clone(),
            a: ws.a.clone(),
            cols: ws.cols.clone(),
        });
        ws.grad = Some(Parameters::zeros(layout));
        ws
    }

    /// Keep the current (free) state.
    pub fn save(&mut self) {
        if let Some(saved) = &mut self.saved {
            copy_all(&mut saved.s, &self.s);
            copy_all(&mut saved.p, &self.p);
            copy_all(&mut saved.a, &self.a);
            copy_all(&mut saved.cols, &self.cols);
        }
    }

    /// Return to the kept state; its errors are zero (a free equilibrium).
    pub fn restore(&mut self) {
        if let Some(saved) = &self.saved {
            copy_all(&mut self.s, &saved.s);
            copy_all(&mut self.p, &saved.p);
            copy_all(&mut self.a, &saved.a);
            copy_all(&mut self.cols, &saved.cols);
            self.e.iter_mut().for_each(|e| e.fill(0.0));
        }
    }
}

fn copy_all(dst: &mut [Vec<f32>], src: &[Vec<f32>]) {
    for (d, s) in dst.iter_mut().zip(src) {
        d.copy_from_slice(s);
    }
}
