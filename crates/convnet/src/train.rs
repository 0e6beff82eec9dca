//! The training loop: each epoch a seeded shuffle, then batches of
//! `batch_size` frames; a batch is split into chunks of `chunk_size`
//! frames that run in parallel (rayon), each summing its frames' gradient
//! (EP estimate or backprop) into its own buffer; the buffers are added in
//! chunk order and Adam takes one step. Nothing is allocated inside the
//! epoch loop, and the result does not depend on the number of threads.
//! With `weight_average`, each network also keeps a moving average of its
//! parameters after every step; the average is what is scored and kept.
use crate::adam::Adam;
use crate::config::{ConvConfig, ModelKind};
use crate::data::{Frames, Targets};
use crate::dropout;
use crate::ep::{backprop_gradient, ep_gradient};
use crate::error::ConvError;
use crate::network::Network;
use crate::params::Parameters;
use crate::predict::{predict_all, prediction_pool};
use crate::scaling::{InputScaling, TargetScaling};
use crate::turns::TurnedSet;
use crate::workspace::Workspace;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A fit has diverged when its epoch loss exceeds this many times the loss
/// of predicting the training mean (0.5 a standardised target).
pub const DIVERGENCE_FACTOR: f64 = 1000.0;

/// Added to the seed for the shuffling stream, so it differs from the
/// initialisation's.
const SHUFFLE_STREAM: u64 = 0x9e37_79b9_7f4a_7c15;

/// Mixed into the seed for the dropout masks' draws, so they differ from
/// the input noise's.
const DROPOUT_STREAM: u64 = 0x5851_f42d_4c95_7f2d;

/// Figures on held-out frames after an epoch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    /// Mean `0.5 ||y - t||^2` in standardised target units.
    pub loss: f64,
    /// Mean absolute error per target, in the targets' units.
    pub mae: Vec<f64>,
}

/// One epoch's figures (`epoch` counts from 0).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpochReport {
    pub epoch: usize,
    /// Adam's step size during the epoch.
    pub learning_rate: f64,
    /// Mean over the epoch's frames of `0.5 ||y - t||^2` at the free
    /// equilibrium before each update, standardised target units.
    pub loss: f64,
    /// On the validation frames given to the fit, after the epoch.
    pub validation: Option<Validation>,
}

/// The per-epoch history of a fit.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TrainingHistory {
    pub epochs: Vec<EpochReport>,
}

/// What a fit reads: frames, targets and their scalings.
pub(crate) struct FitData<'a> {
    /// The network's seed (initialisation, shuffling, shifts, noise).
    pub seed: u64,
    pub frames: Frames<'a>,
    pub targets: Targets<'a>,
    pub input: InputScaling,
    pub scaling: TargetScaling,
}

impl<'a> FitData<'a> {
    /// The same network's fit on the frames and targets of `set` (the
    /// originals and their turned copies).
    fn on<'b>(&self, set: &'b TurnedSet) -> Result<FitData<'b>, ConvError>
    where
        'a: 'b,
    {
        Ok(FitData {
            seed: self.seed,
            frames: set.frames()?,
            targets: set.targets(self.targets.columns())?,
            input: self.input.clone(),
            scaling: self.scaling.clone(),
        })
    }
}

/// One network's training state: its chunk buffers, optimiser, frame
/// order and shuffling stream.
struct Member {
    pool: Vec<Workspace>,
    losses: Vec<f64>,
    adam: Adam,
    order: Vec<usize>,
    rng: ChaCha8Rng,
    /// The moving average of the parameters (`weight_average`), from the
    /// initial weights.
    average: Option<Parameters>,
}

impl Member {
    fn new(net: &Network, config: &ConvConfig, data: &FitData) -> Self {
        let chunks = config.batch_size.div_ceil(config.chunk_size);
        Member {
            pool: (0..chunks)
                .map(|_| {
                    let mut ws = Workspace::for_training(&net.layout, config.chunk_size);
                    dropout::enable(&mut ws, &net.layout, config);
                    ws
                })
                .collect(),
            losses: vec![0.0f64; chunks],
            adam: Adam::new(&net.layout),
            order: (0..data.frames.count()).collect(),
            rng: ChaCha8Rng::seed_from_u64(data.seed.wrapping_add(SHUFFLE_STREAM)),
            average: config.weight_average.map(|_| net.params.clone()),
        }
    }

    /// One epoch of `net` at step size `lr`; returns its mean loss.
    fn epoch(
        &mut self,
        net: &mut Network,
        config: &ConvConfig,
        data: &FitData,
        (lr, epoch): (f64, usize),
    ) -> f64 {
        self.order.shuffle(&mut self.rng);
        let mut total = 0.0;
        for batch in self.order.chunks(config.batch_size) {
            total += batch_step(
                net,
                config,
                data,
                batch,
                (&mut self.pool, &mut self.losses),
                &mut self.adam,
                lr,
                epoch,
            );
            if let (Some(avg), Some(keep)) = (&mut self.average, config.weight_average) {
                avg.blend(&net.params, keep as f32);
            }
        }
        total / self.order.len() as f64
    }

    /// Exchange the network's parameters with the average (if kept).
    fn swap_average(&mut self, net: &mut Network) {
        if let Some(avg) = &mut self.average {
            std::mem::swap(avg, &mut net.params);
        }
    }
}

/// Train the networks `nets` in place for `config.epochs` epochs, side by
/// side, network `k` on `data[k]` (its seed); each epoch's loss is their
/// mean, and the validation frames are scored by their mean prediction.
pub(crate) fn train(
    nets: &mut [Network],
    config: &ConvConfig,
    data: &[FitData],
    validation: Option<(Frames, Targets)>,
    on_epoch: &mut dyn FnMut(&EpochReport),
) -> Result<TrainingHistory, ConvError> {
    let turned = match &config.rotations {
        Some(turns) => Some(TurnedSet::of(&data[0].frames, &data[0].targets, turns)?),
        None => None,
    };
    let with_turns: Vec<FitData>;
    let data = match &turned {
        Some(set) => {
            with_turns = data.iter().map(|d| d.on(set)).collect::<Result<_, _>>()?;
            &with_turns[..]
        }
        None => data,
    };
    let mut members: Vec<Member> = nets
        .iter()
        .zip(data)
        .map(|(net, d)| Member::new(net, config, d))
        .collect();
    let (input, scaling) = (&data[0].input, &data[0].scaling);
    let mut predict_pool = prediction_pool(&nets[0]);
    let len = validation.map_or(0, |v| v.0.count() * scaling.dim());
    let (mut one, mut mean) = (vec![0.0; len], vec![0.0; len]);
    let limit = DIVERGENCE_FACTOR * 0.5 * scaling.dim() as f64;
    let mut history = TrainingHistory::default();
    for epoch in 0..config.epochs {
        let lr = config.learning_rate * config.lr_factor(epoch);
        let mut loss = 0.0;
        let count = nets.len() as f64;
        for ((net, member), d) in nets.iter_mut().zip(&mut members).zip(data) {
            let l = member.epoch(net, config, d, (lr, epoch));
            let finite = net.params.is_finite();
            if l.is_nan() || l > limit || !finite {
                let loss = if finite { l } else { f64::NAN };
                return Err(ConvError::Diverged { epoch, loss, limit });
            }
            loss += l / count;
        }
        let validation = validation.map(|(frames, targets)| {
            mean.fill(0.0);
            for (net, member) in nets.iter_mut().zip(&mut members) {
                member.swap_average(net);
                predict_all(net, input, scaling, &frames, &mut predict_pool, &mut one);
                member.swap_average(net);
                for (m, v) in mean.iter_mut().zip(&one) {
                    *m += v / count;
                }
            }
            score(&mean, &targets, scaling)
        });
        let report = EpochReport {
            epoch,
            learning_rate: lr,
            loss,
            validation,
        };
        on_epoch(&report);
        history.epochs.push(report);
    }
    for (net, member) in nets.iter_mut().zip(&mut members) {
        member.swap_average(net);
    }
    Ok(history)
}

/// One optimiser step on the frames `batch`; returns their summed loss.
#[allow(clippy::too_many_arguments)]
fn batch_step(
    net: &mut Network,
    config: &ConvConfig,
    data: &FitData,
    batch: &[usize],
    (pool, losses): (&mut [Workspace], &mut [f64]),
    adam: &mut Adam,
    lr: f64,
    epoch: usize,
) -> f64 {
    let used = batch.len().div_ceil(config.chunk_size);
    {
        let net: &Network = net;
        pool[..used]
            .par_iter_mut()
            .zip(losses[..used].par_iter_mut())
            .zip(batch.par_chunks(config.chunk_size))
            .for_each(|((ws, loss), idx)| {
                *loss = chunk_gradient(net, config, data, ws, idx, epoch);
            });
    }
    let (first, rest) = pool.split_at_mut(1);
    let Some(grad) = first[0].grad.as_mut() else {
        return 0.0;
    };
    for ws in &rest[..used - 1] {
        if let Some(g) = &ws.grad {
            grad.add(g);
        }
    }
    grad.scale(1.0 / batch.len() as f32);
    let convs = config.conv.len();
    let factor = |l: usize| if l < convs { config.pixel_rate } else { 1.0 };
    adam.step_layers(&mut net.params, grad, (lr, config.weight_decay), factor);
    losses[..used].iter().sum()
}

/// The chunk `idx`'s gradient (the rule of `config.kind`) into a cleared
/// `ws.grad`; returns the chunk's summed loss.
fn chunk_gradient(
    net: &Network,
    config: &ConvConfig,
    data: &FitData,
    ws: &mut Workspace,
    idx: &[usize],
    epoch: usize,
) -> f64 {
    let nb = idx.len();
    let (h, w) = data.frames.size();
    let hw = h * w;
    for (b, &i) in idx.iter().enumerate() {
        let x = &mut ws.x[b * hw..(b + 1) * hw];
        let frame = data.frames.frame(i);
        match shift_of(config.shift_augment, data.seed, epoch, i) {
            (0, 0) => data.input.apply(frame, x),
            (dx, dy) => data.input.apply_shifted(frame, (h, w), (dx, dy), x),
        }
        if config.input_noise > 0.0 {
            add_noise(x, config.input_noise as f32, mix(data.seed, epoch, i));
        }
        if config.drops_out() {
            let key = mix(data.seed ^ DROPOUT_STREAM, epoch, i);
            dropout::draw(ws, &net.layout, config, (nb, b), key);
        }
        for (j, &v) in data.targets.row(i).iter().enumerate() {
            ws.t[j * nb + b] = data.scaling.scale(j, v);
        }
    }
    crate::hybrid::load_pins(
        &data.input,
        &data.frames,
        idx.iter().copied(),
        nb,
        &mut ws.pins,
    );
    crate::hybrid::subtract_base(&data.input, nb, &ws.pins, &mut ws.t);
    if let Some(g) = ws.grad.as_mut() {
        g.clear();
    }
    match config.kind {
        ModelKind::ConvDennn => ep_gradient(net, ws, nb, &config.ep),
        ModelKind::ConvMlp => backprop_gradient(net, ws, nb),
    }
}

/// The shift `(dx, dy)`, each in `-max..=max` px, of frame `i` in
/// `epoch`: a hash of the three numbers and the seed, so it does not
/// depend on which thread loads the frame.
fn shift_of(max: usize, seed: u64, epoch: usize, i: usize) -> (isize, isize) {
    if max == 0 {
        return (0, 0);
    }
    // SplitMix64's finaliser over the seed, the epoch and the frame.
    let mut z = seed
        .wrapping_add((epoch as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15))
        .wrapping_add((i as u64).wrapping_mul(0xd1b5_4a32_d192_ed03));
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    let span = 2 * max as u64 + 1;
    let dx = (z % span) as isize - max as isize;
    let dy = ((z / span) % span) as isize - max as isize;
    (dx, dy)
}

/// A 64-bit hash of frame `i`'s draw in `epoch` of a fit from `seed`
/// (splitmix64's finaliser): the same whatever the thread.
fn mix(seed: u64, epoch: usize, i: usize) -> u64 {
    let mut z = seed
        .wrapping_add((epoch as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15))
        .wrapping_add((i as u64).wrapping_mul(0xd1b5_4a32_d192_ed03));
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Add Gaussian noise of standard deviation `std` to every value of `x`,
/// drawn (Box-Muller, two values a pair of uniforms) from a generator
/// seeded with `key`.
fn add_noise(x: &mut [f32], std: f32, key: u64) {
    use rand::Rng;
    let mut rng = ChaCha8Rng::seed_from_u64(key);
    for pair in x.chunks_mut(2) {
        let u1: f32 = 1.0 - rng.random::<f32>();
        let u2: f32 = rng.random();
        let r = std * (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f32::consts::TAU * u2).sin_cos();
        pair[0] += r * c;
        if let Some(v) = pair.get_mut(1) {
            *v += r * s;
        }
    }
}

/// Mean loss (scaled units) and mean absolute error per target (the
/// targets' units) of `predictions` (`count x dim`, unscaled).
pub(crate) fn score(predictions: &[f64], targets: &Targets, scaling: &TargetScaling) -> Validation {
    let (n, d) = (targets.count(), targets.dim());
    let mut mae = vec![0.0; d];
    let mut loss = 0.0;
    for i in 0..n {
        for (j, &t) in targets.row(i).iter().enumerate() {
            let y = predictions[i * d + j];
            mae[j] += (y - t).abs() / n as f64;
            loss += 0.5 * ((y - t) / scaling.std[j]).powi(2) / n as f64;
        }
    }
    Validation { loss, mae }
}
