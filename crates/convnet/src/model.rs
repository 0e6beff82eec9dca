//! The image pose model: a [`Network`] with its input and target scalings,
//! its configuration and seed; fitted from frames and targets, predicting
//! N outputs from one grey frame.
use crate::config::ConvConfig;
use crate::data::{Frames, Targets};
use crate::error::ConvError;
use crate::hybrid;
use crate::network::Network;
use crate::predict::{forward_frames, predict_all, prediction_pool, unscaled_output, Predictor};
use crate::scaling::{InputScaling, TargetScaling};
use crate::train::{train, EpochReport, FitData, TrainingHistory};
use crate::workspace::Workspace;

/// A fitted `conv-dennn` or `conv-mlp` model.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvModel {
    pub(crate) config: ConvConfig,
    pub(crate) seed: u64,
    /// The networks (`config.members` of them, the first from `seed`).
    pub(crate) nets: Vec<Network>,
    pub(crate) input: InputScaling,
    pub(crate) targets: TargetScaling,
}

impl ConvModel {
    /// Fit a model of `config` (its `kind` picks the learning rule) on
    /// `frames` and their `targets` from `seed` (initialisation and
    /// shuffling).
    pub fn fit(
        frames: &Frames,
        targets: &Targets,
        config: &ConvConfig,
        seed: u64,
    ) -> Result<(Self, TrainingHistory), ConvError> {
        Self::fit_with(frames, targets, config, seed, None, &mut |_| ())
    }

    /// [`Self::fit`], scoring `validation` after every epoch and handing
    /// each epoch's report to `on_epoch` as it ends.
    pub fn fit_with(
        frames: &Frames,
        targets: &Targets,
        config: &ConvConfig,
        seed: u64,
        validation: Option<(Frames, Targets)>,
        on_epoch: &mut dyn FnMut(&EpochReport),
    ) -> Result<(Self, TrainingHistory), ConvError> {
        config.validate()?;
        check_pair(frames, targets)?;
        if frames.count() == 0 {
            return Err(ConvError::Empty);
        }
        if let Some((vf, vt)) = &validation {
            check_pair(vf, vt)?;
            check_size(frames.size(), vf.size())?;
            if vt.dim() != targets.dim() {
                return Err(ConvError::Shape {
                    what: "validation targets a row",
                    expected: targets.dim(),
                    got: vt.dim(),
                });
            }
        }
        let scaling = TargetScaling::fit(targets);
        let mut input = InputScaling::fit(frames, config.input_centring);
        input.pins = hybrid::fit_pins(frames, config, &scaling)?;
        input.base_skip = config.input.reads_base();
        if let Some((vf, _)) = &validation {
            hybrid::check_pins(&input, vf)?;
        }
        let layout = hybrid::layout_for(config, frames.size(), targets.dim(), input.pin_count())?;
        let mut nets: Vec<Network> = (0..config.members as u64)
            .map(|k| Network::new(layout.clone(), config.activation, seed.wrapping_add(k)))
            .collect();
        if input.base_skip {
            nets.iter_mut().for_each(hybrid::zero_output);
        }
        let start = ConvModel {
            config: config.clone(),
            seed,
            nets,
            input,
            targets: scaling,
        };
        start.trained((frames, targets), validation, on_epoch)
    }

    /// This model's networks trained by its configuration's rule and
    /// schedule on `frames` and `targets` (network `k` shuffled from
    /// `seed + k`), its input and target scalings kept: the one training
    /// step of [`Self::fit_with`] and [`Self::fine_tune_with`]. With
    /// `pixel_dropout = 1` the pixel features' weights are zeroed first.
    pub(crate) fn trained(
        mut self,
        (frames, targets): (&Frames, &Targets),
        validation: Option<(Frames, Targets)>,
        on_epoch: &mut dyn FnMut(&EpochReport),
    ) -> Result<(ConvModel, TrainingHistory), ConvError> {
        for net in &mut self.nets {
            crate::dropout::zero_masked_pixels(&mut net.params, &net.layout, &self.config);
        }
        let data: Vec<FitData> = (0..self.nets.len() as u64)
            .map(|k| FitData {
                seed: self.seed.wrapping_add(k),
                frames: *frames,
                targets: *targets,
                input: self.input.clone(),
                scaling: self.targets.clone(),
            })
            .collect();
        let history = train(&mut self.nets, &self.config, &data, validation, on_epoch)?;
        Ok((self, history))
    }

    /// The N outputs for one frame (`height x width` grey pixels), in the
    /// targets' units.
    pub fn predict(&self, frame: &[u8]) -> Result<Vec<f64>, ConvError> {
        let mut out = vec![0.0; self.outputs()];
        self.predict_with(&mut self.predictor(), frame, &mut out)?;
        Ok(out)
    }

    /// [`Self::predict`] on reusable buffers, into `out` (N values): no
    /// allocation, for a loop that predicts frame after frame.
    pub fn predict_with(
        &self,
        predictor: &mut Predictor,
        frame: &[u8],
        out: &mut [f64],
    ) -> Result<(), ConvError> {
        self.predict_pins_with(predictor, frame, None, out)
    }

    /// The N outputs for one frame and its pin displacement vector
    /// `pins` (as the training frames carried them; ignored by a model
    /// of pixels only, required by a pins-and-pixels one).
    pub fn predict_with_pins(&self, frame: &[u8], pins: &[f32]) -> Result<Vec<f64>, ConvError> {
        let mut out = vec![0.0; self.outputs()];
        self.predict_pins_with(&mut self.predictor(), frame, Some(pins), &mut out)?;
        Ok(out)
    }

    /// [`Self::predict_with_pins`] on reusable buffers, into `out`;
    /// `pins` may be `None` for a model of pixels only.
    pub fn predict_pins_with(
        &self,
        predictor: &mut Predictor,
        frame: &[u8],
        pins: Option<&[f32]>,
        out: &mut [f64],
    ) -> Result<(), ConvError> {
        let (h, w) = self.input_size();
        let mut frames = Frames::new(frame, 1, h, w).map_err(|_| ConvError::Shape {
            what: "frame pixels",
            expected: h * w,
            got: frame.len(),
        })?;
        if let (Some(p), true) = (pins, self.pin_inputs() > 0) {
            frames = frames.with_pins(p, p.len())?;
        }
        hybrid::check_pins(&self.input, &frames)?;
        if out.len() != self.outputs() {
            return Err(ConvError::Shape {
                what: "outputs",
                expected: self.outputs(),
                got: out.len(),
            });
        }
        let Predictor { ws, member } = predictor;
        let (first, others) = self.nets.split_first().expect("a model has a network");
        forward_frames(first, &self.input, ws, &frames, 0, 1);
        unscaled_output(first, ws, &self.targets, 1, 0, out);
        for net in others {
            forward_frames(net, &self.input, ws, &frames, 0, 1);
            unscaled_output(net, ws, &self.targets, 1, 0, member);
            for (o, m) in out.iter_mut().zip(member.iter()) {
                *o += m;
            }
        }
        if !others.is_empty() {
            let n = self.nets.len() as f64;
            out.iter_mut().for_each(|o| *o /= n);
        }
        Ok(())
    }

    /// Buffers for [`Self::predict_with`].
    pub fn predictor(&self) -> Predictor {
        Predictor {
            ws: Workspace::for_prediction(&self.nets[0].layout, 1),
            member: vec![0.0; self.outputs()],
        }
    }

    /// Every frame's outputs (`count x N`, frame by frame), the frames
    /// shared among the threads of the current rayon pool.
    pub fn predict_batch(&self, frames: &Frames) -> Result<Vec<f64>, ConvError> {
        check_size(self.input_size(), frames.size())?;
        hybrid::check_pins(&self.input, frames)?;
        let mut out = vec![0.0; frames.count() * self.outputs()];
        let mut pool = prediction_pool(&self.nets[0]);
        let (first, others) = self.nets.split_first().expect("a model has a network");
        let (input, scaling) = (&self.input, &self.targets);
        predict_all(first, input, scaling, frames, &mut pool, &mut out);
        if !others.is_empty() {
            let mut member = vec![0.0; out.len()];
            for net in others {
                predict_all(net, input, scaling, frames, &mut pool, &mut member);
                out.iter_mut().zip(&member).for_each(|(o, m)| *o += m);
            }
            let n = self.nets.len() as f64;
            out.iter_mut().for_each(|o| *o /= n);
        }
        Ok(out)
    }

    /// Mean loss and mean absolute error per target on `frames`.
    pub fn score(
        &self,
        frames: &Frames,
        targets: &Targets,
    ) -> Result<crate::train::Validation, ConvError> {
        check_pair(frames, targets)?;
        if targets.dim() != self.outputs() {
            return Err(ConvError::Shape {
                what: "targets a row",
                expected: self.outputs(),
                got: targets.dim(),
            });
        }
        let predictions = self.predict_batch(frames)?;
        Ok(crate::train::score(&predictions, targets, &self.targets))
    }

    /// The configuration it was fitted with.
    pub fn config(&self) -> &ConvConfig {
        &self.config
    }

    /// The seed it was fitted from.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The network (layers and parameters); of an ensemble, the first
    /// (from `seed`).
    pub fn network(&self) -> &Network {
        &self.nets[0]
    }

    /// Every network, the first from `seed`, the next from `seed + 1`, ...
    /// (one unless `config.members` > 1); the model predicts their mean.
    pub fn networks(&self) -> &[Network] {
        &self.nets
    }

    /// Frame `(height, width)` it takes, px.
    pub fn input_size(&self) -> (usize, usize) {
        self.nets[0].layout.input_size()
    }

    /// Pin values a frame it reads beside the pixels (0: pixels only).
    pub fn pin_inputs(&self) -> usize {
        self.input.pin_count()
    }

    /// Number of outputs N.
    pub fn outputs(&self) -> usize {
        self.nets[0].layout.outputs()
    }

    /// The pixel standardisation fitted on the training frames.
    pub fn input_scaling(&self) -> &InputScaling {
        &self.input
    }

    /// The target standardisation fitted on the training targets.
    pub fn target_scaling(&self) -> &TargetScaling {
        &self.targets
    }
}

fn check_pair(frames: &Frames, targets: &Targets) -> Result<(), ConvError> {
    if frames.count() != targets.count() {
        return Err(ConvError::Shape {
            what: "target rows (one a frame)",
            expected: frames.count(),
            got: targets.count(),
        });
    }
    Ok(())
}

fn check_size(model: (usize, usize), got: (usize, usize)) -> Result<(), ConvError> {
    if model != got {
        return Err(ConvError::FrameSize {
            height: model.0,
            width: model.1,
            got_height: got.0,
            got_width: got.1,
        });
    }
    Ok(())
}
