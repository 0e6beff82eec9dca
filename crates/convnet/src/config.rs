//! What a convolutional model is and how it learns, every value explicit
//! and checked before any work (docs/learning.md, "Images in: the
//! convolutional DenNN"): the layers, the activation, the two learning
//! rules (equilibrium propagation, or backprop for the twin) and the
//! optimiser's schedule.
use crate::error::{config_error, ConvError};
use crate::turns::FrameTurns;
use serde::{Deserialize, Serialize};

/// Largest kernel side, stride, channel count and dense width accepted.
const MAX_KERNEL: usize = 15;
const MAX_STRIDE: usize = 8;
const MAX_WIDTH: usize = 8192;

/// One convolutional layer: `channels` feature maps, each unit seeing a
/// `kernel x kernel` window of the layer below moved by `stride` pixels,
/// the input zero-padded by `kernel / 2` on every side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConvSpec {
    /// Output feature maps.
    pub channels: usize,
    /// Side of the square kernel, px of the layer's input.
    pub kernel: usize,
    /// Step between neighbouring windows, px of the layer's input.
    pub stride: usize,
}

/// The neurons' rate function `phi` (hidden layers; the input is used as
/// is and the output is linear).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Activation {
    /// `1 / (1 + e^-s)`, the report's.
    Sigmoid,
    /// `tanh s`.
    Tanh,
    /// `max(0, s)`; `phi'` is taken as 0 at 0.
    Relu,
}

/// What is taken from every pixel before the network sees it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InputCentring {
    /// The training frames' mean over all pixels.
    Global,
    /// The training frames' mean at each pixel (the mean frame), so the
    /// network sees each frame's difference from it: a convolution shares
    /// its bias across positions and cannot learn this offset itself.
    MeanFrame,
}

/// What the network reads.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InputKind {
    /// The frame alone. Default.
    #[default]
    Pixels,
    /// The frame, and the tap's pin displacement vector (standardised per
    /// column on the training rows) appended to the flattened output of
    /// the last convolution, as the first dense layer's input
    /// (docs/learning.md, "Pins and pixels").
    PinsAndPixels,
    /// The frame, and a pin model's prediction of the targets (the base,
    /// computed by the caller from the tap's pins and given as the frame's
    /// side values, one an encoded target), standardised as the targets
    /// are and read beside the pixels as the pins are; the network learns
    /// the correction `t - base` in standardised units, its output layer
    /// starting at zero, so that a fresh model predicts the base
    /// (docs/learning.md, "The residual on a pin model").
    PinModelAndPixels,
}

impl InputKind {
    fn is_pixels(&self) -> bool {
        *self == InputKind::Pixels
    }

    /// Whether the side values are a base prediction the network corrects.
    pub fn reads_base(&self) -> bool {
        *self == InputKind::PinModelAndPixels
    }
}

/// The learning rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// Equilibrium propagation in the convolutional dendritic network.
    ConvDennn,
    /// The backprop twin: the same layers, initialisation, batches and
    /// optimiser, with the exact gradient of `0.5 ||y - t||^2`.
    ConvMlp,
}

impl ModelKind {
    /// The name the command line will use ("conv-dennn", "conv-mlp").
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::ConvDennn => "conv-dennn",
            ModelKind::ConvMlp => "conv-mlp",
        }
    }
}

/// How the free phase (no target) finds its equilibrium.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum FreePhase {
    /// The feed-forward pass: with no target every dendritic error vanishes
    /// at the minimum of the energy, so this *is* the equilibrium (exact,
    /// one pass). Default.
    FeedForward,
    /// `steps` Euler steps of `ds/dt = -dE/ds` of size `dt` from zero
    /// potentials (the report's relaxation; for tests and comparison).
    Euler { steps: usize, dt: f64 },
}

/// How the weakly clamped phases relax to their equilibrium.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ClampedPhase {
    /// `iterations` rounds of the two local sweeps: top-down, each layer
    /// sets its dendritic error to the stationary value its upper layer
    /// implies; bottom-up, each soma takes its dendrite's prediction plus
    /// that error. Its fixed points are the energy's stationary points.
    /// Default: 1 (second-order accurate with symmetric nudging).
    Sweeps { iterations: usize },
    /// `steps` simultaneous Euler steps of `ds/dt = -dF/ds` of size `dt`
    /// from the free state (for tests and comparison).
    Euler { steps: usize, dt: f64 },
}

/// Which nudged phases the update compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Nudging {
    /// `+beta` against `-beta` (Laborieux et al. 2021): the estimate's
    /// first-order bias in beta cancels. Default.
    Symmetric,
    /// `+beta` against the free phase (Scellier and Bengio 2017).
    Positive,
}

/// The equilibrium-propagation settings of `conv-dennn`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EpSettings {
    /// Nudging strength `beta` of `F = E + beta C`, in (0, 1).
    pub beta: f64,
    pub nudging: Nudging,
    pub free_phase: FreePhase,
    pub clamped_phase: ClampedPhase,
}

impl Default for EpSettings {
    fn default() -> Self {
        EpSettings {
            beta: 0.1,
            nudging: Nudging::Symmetric,
            free_phase: FreePhase::FeedForward,
            clamped_phase: ClampedPhase::Sweeps { iterations: 1 },
        }
    }
}

/// A whole model configuration: architecture, learning rule, schedule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConvConfig {
    pub kind: ModelKind,
    /// The convolutional layers, input side first.
    pub conv: Vec<ConvSpec>,
    /// Widths of the dense hidden layers after the convolutions (the
    /// output layer, one unit a target, follows them).
    pub dense: Vec<usize>,
    pub activation: Activation,
    /// What is taken from every pixel first.
    pub input_centring: InputCentring,
    /// Used by `conv-dennn` only.
    pub ep: EpSettings,
    /// Passes over the training frames.
    pub epochs: usize,
    /// Frames per optimiser step.
    pub batch_size: usize,
    /// Frames per matrix product; a batch is split into chunks of this
    /// size that run in parallel (the result does not depend on the
    /// number of threads).
    pub chunk_size: usize,
    /// Adam's step size at the start.
    pub learning_rate: f64,
    /// The step size falls along a half cosine to this fraction of
    /// `learning_rate` at the last epoch.
    pub final_lr_fraction: f64,
    /// L2 penalty on the weights (not the biases), added to the gradient.
    pub weight_decay: f64,
    /// Training frames are moved by up to this many pixels in x and y
    /// (a fresh seeded draw for each frame and epoch, edge pixels
    /// repeated), so the network cannot rely on where the whole pin
    /// pattern sits; 0 turns it off.
    pub shift_augment: usize,
    /// Standard deviation of the Gaussian noise added to every
    /// standardised training pixel (a fresh seeded draw for each frame
    /// and epoch; never at prediction): a regulariser against
    /// over-fitting the few training frames; 0 turns it off.
    #[serde(default)]
    pub input_noise: f64,
    /// Networks in the model, trained side by side from seeds `seed`,
    /// `seed + 1`, ... on the same frames and batches' schedule; the model
    /// predicts the mean of their outputs (a circular target's sine and
    /// cosine are averaged, so its angle is the circular mean). 1, the
    /// default, is one network (left out of the JSON then).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub members: usize,
    /// Two more input channels beside the frame, fixed for every frame:
    /// each pixel's column and row scaled to [-1, 1] (CoordConv, Liu et
    /// al. 2018), so the first layer can weigh where in the frame a
    /// pattern lies. Off (false), the default, is left out of the JSON.
    #[serde(default, skip_serializing_if = "is_false")]
    pub coord_channels: bool,
    /// The weights kept for prediction: with `Some(d)`, an exponential
    /// moving average of each network's parameters over the optimiser's
    /// steps, `avg <- d avg + (1 - d) theta` from the initial weights, is
    /// what the model saves and predicts with (and what the validation
    /// frames are scored with after each epoch); the learning rule and its
    /// updates are unchanged. `Some(0)` is the plain model; `None`, the
    /// default, is left out of the JSON.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight_average: Option<f64>,
    /// Dropout on the dense hidden layers: each training frame drops every
    /// unit with this probability, one mask held through the free and both
    /// nudged phases (docs/learning.md, "Dropout"); none at prediction.
    /// 0, the default, is off and left out of the JSON.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub dense_dropout: f64,
    /// Channel dropout on the convolutional layers: each training frame
    /// drops whole feature maps with this probability, held like
    /// `dense_dropout`'s mask. 0, the default, is off and left out.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub channel_dropout: f64,
    /// What the network reads: `pixels` (the default, left out of the
    /// JSON), `pins_and_pixels` or `pin_model_and_pixels`.
    #[serde(default, skip_serializing_if = "InputKind::is_pixels")]
    pub input: InputKind,
    /// Pins and pixels only: the probability that a training frame's
    /// pixel features (the last convolution's whole output, as the first
    /// dense layer reads it) are all set to 0, so that the network must
    /// also predict from the pins alone (docs/learning.md, "Leaning on
    /// the pins"); kept features are not rescaled. 1 masks them in every
    /// frame and starts their weights in the dense layer at zero: a pin
    /// model, which `train --init` can then fine-tune with the pixels on,
    /// starting at its figure. 0, the default, is off and left out.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub pixel_dropout: f64,
    /// The convolutions' step size (the pixel path, below the dense
    /// layers) as a fraction of `learning_rate`, e.g. 0.1 for a residual
    /// model whose head learns faster than its pixel features; 1, the
    /// default, is one step size for all and left out of the JSON.
    #[serde(default = "one_f64", skip_serializing_if = "is_one_f64")]
    pub pixel_rate: f64,
    /// Training on every frame and its copies turned by the sensor's
    /// symmetry (docs/learning.md, "Turned frames"); `None`, the default,
    /// is off and left out of the JSON.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotations: Option<FrameTurns>,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn is_false(v: &bool) -> bool {
    !*v
}

fn one() -> usize {
    1
}

fn one_f64() -> f64 {
    1.0
}

fn is_one_f64(v: &f64) -> bool {
    *v == 1.0
}

fn is_one(v: &usize) -> bool {
    *v == 1
}

/// Most networks an ensemble may have.
pub const MAX_MEMBERS: usize = 32;

impl ConvConfig {
    /// The defaults for `kind` (docs/learning.md says how they were chosen).
    pub fn new(kind: ModelKind) -> Self {
        ConvConfig {
            kind,
            conv: vec![
                ConvSpec {
                    channels: 16,
                    kernel: 5,
                    stride: 2,
                },
                ConvSpec {
                    channels: 32,
                    kernel: 3,
                    stride: 2,
                },
                ConvSpec {
                    channels: 64,
                    kernel: 3,
                    stride: 2,
                },
            ],
            dense: vec![256],
            activation: Activation::Tanh,
            input_centring: InputCentring::Global,
            ep: EpSettings::default(),
            epochs: 40,
            batch_size: 16,
            chunk_size: 8,
            learning_rate: 1e-3,
            final_lr_fraction: 0.02,
            weight_decay: 0.0,
            shift_augment: 0,
            input_noise: 0.0,
            members: 1,
            coord_channels: false,
            weight_average: None,
            dense_dropout: 0.0,
            channel_dropout: 0.0,
            input: InputKind::Pixels,
            pixel_dropout: 0.0,
            pixel_rate: 1.0,
            rotations: None,
        }
    }

    /// Input channels the first layer sees: the frame, and with
    /// `coord_channels` its two coordinate planes.
    pub fn input_channels(&self) -> usize {
        if self.coord_channels {
            3
        } else {
            1
        }
    }

    /// Check every value; the first one out of range is the error.
    pub fn validate(&self) -> Result<(), ConvError> {
        for c in &self.conv {
            check_range("conv.channels", c.channels, 1, MAX_WIDTH)?;
            check_range("conv.kernel", c.kernel, 1, MAX_KERNEL)?;
            check_range("conv.stride", c.stride, 1, MAX_STRIDE)?;
        }
        for &d in &self.dense {
            check_range("dense", d, 1, MAX_WIDTH)?;
        }
        check_range("epochs", self.epochs, 1, 1_000_000)?;
        check_range("batch_size", self.batch_size, 1, 65_536)?;
        check_range("chunk_size", self.chunk_size, 1, 1024)?;
        check_range("shift_augment", self.shift_augment, 0, 16)?;
        check_range("members", self.members, 1, MAX_MEMBERS)?;
        check_positive("learning_rate", self.learning_rate)?;
        if !(self.final_lr_fraction > 0.0 && self.final_lr_fraction <= 1.0) {
            return Err(config_error(
                "final_lr_fraction",
                format!("{} is not in (0, 1]", self.final_lr_fraction),
            ));
        }
        if !(self.input_noise >= 0.0 && self.input_noise <= 10.0) {
            return Err(config_error(
                "input_noise",
                format!("{} is not in [0, 10]", self.input_noise),
            ));
        }
        if let Some(d) = self.weight_average {
            if !(0.0..1.0).contains(&d) {
                return Err(config_error(
                    "weight_average",
                    format!("{d} is not in [0, 1)"),
                ));
            }
        }
        for (field, p) in [
            ("dense_dropout", self.dense_dropout),
            ("channel_dropout", self.channel_dropout),
        ] {
            if !(0.0..0.95).contains(&p) {
                return Err(config_error(field, format!("{p} is not in [0, 0.95)")));
            }
        }
        self.check_pixel_dropout()?;
        if !(self.pixel_rate > 0.0 && self.pixel_rate <= 1.0) {
            return Err(config_error(
                "pixel_rate",
                format!("{} is not in (0, 1]", self.pixel_rate),
            ));
        }
        if !(self.weight_decay >= 0.0 && self.weight_decay.is_finite()) {
            return Err(config_error(
                "weight_decay",
                format!("{} is not a number >= 0", self.weight_decay),
            ));
        }
        if let Some(turns) = &self.rotations {
            turns.validate()?;
            if !self.input.is_pixels() {
                return Err(config_error(
                    "rotations",
                    "turned frames are for a model of pixels only (the pins would have to turn too)",
                ));
            }
        }
        self.ep.validate()
    }

    /// `pixel_dropout` in [0, 1], and above 0 only for a pins-and-pixels
    /// network with convolutions (whose output is what it drops).
    fn check_pixel_dropout(&self) -> Result<(), ConvError> {
        let p = self.pixel_dropout;
        if !(0.0..=1.0).contains(&p) {
            return Err(config_error(
                "pixel_dropout",
                format!("{p} is not in [0, 1]"),
            ));
        }
        if p > 0.0 && (self.input.is_pixels() || self.conv.is_empty()) {
            return Err(config_error(
                "pixel_dropout",
                "needs input = \"pins_and_pixels\" and at least one convolution",
            ));
        }
        Ok(())
    }

    /// Whether any training frame draws a dropout mask.
    pub(crate) fn drops_out(&self) -> bool {
        self.dense_dropout > 0.0 || self.channel_dropout > 0.0 || self.pixel_dropout > 0.0
    }

    /// The step-size factor of epoch `epoch` (0-based): a half cosine from
    /// 1 at the first epoch to `final_lr_fraction` at the last.
    pub fn lr_factor(&self, epoch: usize) -> f64 {
        let last = self.epochs.saturating_sub(1).max(1) as f64;
        let progress = (epoch as f64 / last).min(1.0);
        let f = self.final_lr_fraction;
        f + (1.0 - f) * 0.5 * (1.0 + (std::f64::consts::PI * progress).cos())
    }
}

impl EpSettings {
    /// `beta` in (0, 1) (the `-beta` phase's output equilibrium divides by
    /// `1 - beta`), relaxation counts at least 1 and steps in (0, 1].
    pub fn validate(&self) -> Result<(), ConvError> {
        if !(self.beta > 0.0 && self.beta < 1.0) {
            return Err(config_error(
                "ep.beta",
                format!("{} is not in (0, 1)", self.beta),
            ));
        }
        if let FreePhase::Euler { steps, dt } = self.free_phase {
            check_range("ep.free_phase.steps", steps, 1, 1_000_000)?;
            check_step("ep.free_phase.dt", dt)?;
        }
        match self.clamped_phase {
            ClampedPhase::Sweeps { iterations } => {
                check_range("ep.clamped_phase.iterations", iterations, 1, 10_000)
            }
            ClampedPhase::Euler { steps, dt } => {
                check_range("ep.clamped_phase.steps", steps, 1, 1_000_000)?;
                check_step("ep.clamped_phase.dt", dt)
            }
        }
    }
}

fn check_range(field: &'static str, v: usize, lo: usize, hi: usize) -> Result<(), ConvError> {
    if v < lo || v > hi {
        return Err(config_error(field, format!("{v} is not in {lo}..={hi}")));
    }
    Ok(())
}

fn check_positive(field: &'static str, v: f64) -> Result<(), ConvError> {
    if !(v > 0.0 && v.is_finite()) {
        return Err(config_error(field, format!("{v} is not a positive number")));
    }
    Ok(())
}

fn check_step(field: &'static str, v: f64) -> Result<(), ConvError> {
    if !(v > 0.0 && v <= 1.0) {
        return Err(config_error(field, format!("{v} is not in (0, 1]")));
    }
    Ok(())
}
