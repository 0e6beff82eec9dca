//! The training loop of a pose model: per-epoch shuffling with a seeded RNG,
//! one EP (or backprop) pass per net, the nets (the PDenNN's two, an
//! ensemble's members) in parallel with rayon, and the per-epoch history of report Fig. 4.5.
use crate::config::{anneal_factor, ModelConfig, ModelKind, NetConfig};
use crate::cost::NetCost;
use crate::dataset::Dataset;
use crate::dennn::{DenNN, EpConfig};
use crate::error::LearnError;
use crate::fit_members::Failures;
use crate::mlp::Mlp;
use crate::net::{Layers, States};
use crate::standardise::Standardiser;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// One net's figures for one epoch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NetEpoch {
    pub name: String,
    /// Mean over the epoch's samples of eq. 3.16 with `beta = 1`,
    /// `0.5 ||y - t||^2`, at the free-phase output before each update, in
    /// scaled target units (standardised when `TargetScaling::Standardise`).
    pub loss: f64,
    /// Mean total energy, eq. 3.17, at the weakly clamped equilibrium. For
    /// the backprop twin (no clamped phase) it equals `loss`.
    pub energy: f64,
    /// `0.5 ||y - t||^2` on the validation set after the epoch, same units.
    pub val_loss: Option<f64>,
}

/// All nets' figures for one epoch (`epoch` counts from 0).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpochReport {
    pub epoch: usize,
    pub nets: Vec<NetEpoch>,
}

/// The per-epoch history of a fit.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TrainingHistory {
    pub epochs: Vec<EpochReport>,
    /// How often the learning rates were halved after a divergence
    /// (`ModelConfig::divergence_retries`; the most of any member); the
    /// epochs are each net's last fit's.
    #[serde(default)]
    pub lr_halvings: usize,
    /// An ensemble's halvings member by member (each diverged member
    /// restarts alone); empty for a single model.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub member_lr_halvings: Vec<usize>,
}

/// One net's training inputs and scaled targets, and the rows one epoch
/// visits (each once, or some more often: [`crate::BandWeight`]).
pub(crate) struct NetData {
    pub set: Dataset,
    pub rows: Vec<usize>,
}

impl NetData {
    /// `inputs` is `n x dim` row-major (f64); targets are `src`'s columns
    /// `cols`, scaled by `scaler`.
    pub fn new(
        inputs: Vec<f64>,
        src: &Dataset,
        cols: &[usize],
        scaler: &Standardiser,
    ) -> Result<Self, LearnError> {
        let dim = inputs.len() / src.n.max(1);
        let x = inputs.into_iter().map(|v| v as f32).collect();
        let mut y = Vec::with_capacity(src.n * cols.len());
        for i in 0..src.n {
            let row = src.y_row(i);
            y.extend(
                cols.iter()
                    .map(|&c| ((row[c] as f64 - scaler.mean()[c]) / scaler.std()[c]) as f32),
            );
        }
        Ok(NetData {
            set: Dataset::new(x, y, src.n, dim, cols.len())?,
            rows: (0..src.n).collect(),
        })
    }

    /// The same data, an epoch visiting `rows` (indices into it, in any
    /// order and with repeats; shuffled every epoch).
    pub fn with_rows(self, rows: Vec<usize>) -> Self {
        Self { rows, ..self }
    }
}

enum Engine {
    Ep(DenNN, EpConfig),
    /// The net, its rate and its output layer's rate (before annealing).
    Backprop(Mlp, f64, Option<f64>),
}

/// How far above the loss of predicting the training mean an epoch's mean
/// loss may go before the training counts as diverged: 1000 times is an
/// RMS error about 45 times the targets' spread. Trained nets stay below
/// the mean's loss (on the shared real set the default models peak at
/// 0.26-0.41, against 0.5 for one target and 1 for two); a net whose loss
/// grew without bound (7e56 once) is caught long before its weights
/// overflow.
pub const DIVERGENCE_FACTOR: f64 = 1000.0;

/// The divergence limit of a net trained on the scaled targets `y`
/// (`n x dim`, row-major): [`DIVERGENCE_FACTOR`] times the loss of
/// predicting their mean, `0.5 sum_j var_j`, taken as at least 0.5 a
/// target (the mean's loss on standardised targets) so that a constant
/// target does not make every loss a divergence.
pub(crate) fn divergence_limit(y: &[f32], n: usize, dim: usize) -> f64 {
    let mut mean_loss = 0.0;
    for j in 0..dim {
        let col = || {
            y.iter()
                .skip(j)
                .step_by(dim.max(1))
                .take(n)
                .map(|&v| v as f64)
        };
        let mean = col().sum::<f64>() / n.max(1) as f64;
        let var = col().map(|v| (v - mean).powi(2)).sum::<f64>() / n.max(1) as f64;
        mean_loss += 0.5 * var;
    }
    DIVERGENCE_FACTOR * mean_loss.max(0.5 * dim as f64)
}

/// One net being trained.
pub(crate) struct Trainer {
    name: String,
    engine: Engine,
    data: NetData,
    val: Option<NetData>,
    rng: ChaCha8Rng,
    order: Vec<usize>,
    /// Epochs and the annealed fraction of them (`ModelConfig`).
    schedule: (usize, f64),
    /// An epoch's mean loss above this is a divergence ([`divergence_limit`]).
    limit: f64,
    /// Noise added to the inputs each epoch (`ModelConfig::input_noise`).
    noise: Option<InputNoise>,
}

impl Trainer {
    pub fn new(
        name: &str,
        layers: Layers,
        cfg: &ModelConfig,
        net: &NetConfig,
        data: NetData,
        val: Option<NetData>,
        k: u64,
    ) -> Self {
        let engine = if cfg.kind == ModelKind::Mlp {
            Engine::Backprop(
                Mlp::from_layers(layers)
                    .with_lr_scaling(cfg.lr_scaling)
                    .with_output_learning_rate(net.output_learning_rate),
                net.learning_rate,
                net.output_learning_rate,
            )
        } else {
            let ep = EpConfig {
                learning_rate: net.learning_rate,
                output_learning_rate: net.output_learning_rate,
                lr_scaling: cfg.lr_scaling,
                beta: net.beta,
                free_phase: cfg.free_phase,
                clamped_phase: cfg.clamped_phase,
                epochs: cfg.epochs,
                seed: cfg.seed,
                cost: None,
            };
            Engine::Ep(DenNN::from_layers(layers), ep)
        };
        let rng =
            ChaCha8Rng::seed_from_u64(cfg.seed ^ (0x9E37_79B9_7F4A_7C15u64.wrapping_mul(k + 1)));
        let order = data.rows.clone();
        let limit = divergence_limit(&data.set.y, data.set.n, data.set.dim_y);
        Trainer {
            name: name.to_string(),
            engine,
            data,
            val,
            rng,
            order,
            schedule: (cfg.epochs, cfg.anneal_fraction),
            limit,
            noise: (cfg.input_noise > 0.0).then(|| InputNoise::new(cfg.input_noise, cfg.seed, k)),
        }
    }

    /// Train on `cost` in place of the squared cost ([`crate::Cost`]).
    pub fn with_cost(mut self, cost: Option<NetCost>) -> Self {
        self.engine = match self.engine {
            Engine::Ep(net, cfg) => Engine::Ep(net, EpConfig { cost, ..cfg }),
            Engine::Backprop(net, lr, out) => Engine::Backprop(net.with_cost(cost), lr, out),
        };
        self
    }

    /// Draw the shuffles (and input noise) of `epochs` epochs without
    /// training, so that a fit continued from a model of `epochs` epochs
    /// visits the rows as a fit of more epochs from the same seed would.
    pub fn skip_epochs(&mut self, epochs: usize) {
        for _ in 0..epochs {
            self.order.shuffle(&mut self.rng);
            if let Some(noise) = self.noise.as_mut() {
                noise.apply(&self.data.set);
            }
        }
    }

    /// One shuffled pass over the training data.
    pub fn epoch(&mut self, epoch: usize) -> Result<NetEpoch, LearnError> {
        self.order.shuffle(&mut self.rng);
        let f = anneal_factor(epoch, self.schedule.0, self.schedule.1);
        let noisy = self.noise.as_mut().map(|n| n.apply(&self.data.set));
        let set = noisy.as_ref().unwrap_or(&self.data.set);
        let (loss, energy) = match &mut self.engine {
            Engine::Ep(net, cfg) => {
                let cfg = EpConfig {
                    learning_rate: cfg.learning_rate * f,
                    output_learning_rate: cfg.output_learning_rate.map(|o| o * f),
                    ..*cfg
                };
                let s = net.train_sequence(set, &self.order, &cfg)?;
                (s.loss, s.energy)
            }
            Engine::Backprop(net, lr, out_lr) => {
                net.set_output_learning_rate(out_lr.map(|o| o * f));
                let lr = *lr * f;
                let mut total = 0.0;
                for &i in &self.order {
                    total += net.train_sample(set.x_row(i), set.y_row(i), lr)?;
                }
                let mean = total / self.order.len() as f64;
                (mean, mean)
            }
        };
        // Written so that a NaN loss diverges too.
        let within = loss <= self.limit;
        if !within || !self.layers().is_finite() {
            return Err(LearnError::Diverged {
                net: self.name.clone(),
                epoch,
                loss,
                limit: if loss.is_finite() && !within {
                    self.limit
                } else {
                    f64::INFINITY
                },
            });
        }
        let val_loss = self.val.as_ref().map(|v| mean_loss(self.layers(), &v.set));
        Ok(NetEpoch {
            name: self.name.clone(),
            loss,
            energy,
            val_loss,
        })
    }

    fn layers(&self) -> &Layers {
        match &self.engine {
            Engine::Ep(net, _) => net.layers(),
            Engine::Backprop(net, ..) => net.layers(),
        }
    }

    pub fn into_layers(self) -> Layers {
        match self.engine {
            Engine::Ep(net, _) => net.layers().clone(),
            Engine::Backprop(net, ..) => net.layers().clone(),
        }
    }
}

/// Gaussian noise on a net's training inputs, drawn afresh every epoch
/// from its own seeded generator (so the shuffles are those of a fit
/// without noise); the targets and the validation inputs are left alone.
struct InputNoise {
    std: f32,
    rng: ChaCha8Rng,
}

impl InputNoise {
    /// Noise of standard deviation `std` for net `k` of a fit seeded `seed`.
    fn new(std: f64, seed: u64, k: u64) -> Self {
        let stream = seed.rotate_left(17) ^ 0xD1B5_4A32_D192_ED03u64.wrapping_mul(k + 1);
        Self {
            std: std as f32,
            rng: ChaCha8Rng::seed_from_u64(stream),
        }
    }

    /// `set` with noise added to every input.
    fn apply(&mut self, set: &Dataset) -> Dataset {
        let normal = StandardNormal;
        let x = set
            .x
            .iter()
            .map(|&v| {
                let e: f32 = normal.sample(&mut self.rng);
                v + self.std * e
            })
            .collect();
        Dataset {
            x,
            y: set.y.clone(),
            ..*set
        }
    }
}

/// Mean `0.5 ||y - t||^2` of `layers` over `data`.
pub(crate) fn mean_loss(layers: &Layers, data: &Dataset) -> f64 {
    let mut st = States::new(layers.sizes());
    let mut out = vec![0.0f32; data.dim_y];
    let mut total = 0.0;
    for i in 0..data.n {
        if layers
            .predict_with(data.x_row(i), &mut out, &mut st)
            .is_err()
        {
            return f64::NAN;
        }
        total += out
            .iter()
            .zip(data.y_row(i))
            .map(|(y, t)| 0.5 * ((y - t) as f64).powi(2))
            .sum::<f64>();
    }
    total / data.n as f64
}

/// Train every net for `epochs`, the nets of an epoch in parallel (rayon;
/// each net has its own data and random order, so the result does not
/// depend on the threads nor on the other nets). Net `t` belongs to member
/// `owner[t]`: a net that diverges stops its member's nets, the others go
/// on. Returns each net's epochs (a failed member's cut short) and each
/// failed member's first error (in net order within the epoch it failed).
pub(crate) fn train_nets(
    trainers: &mut [Trainer],
    owner: &[usize],
    epochs: usize,
    progress: &mut dyn FnMut(&EpochReport),
) -> (Vec<Vec<NetEpoch>>, Failures) {
    let mut history = vec![Vec::with_capacity(epochs); trainers.len()];
    let mut failed = Failures::new();
    for epoch in 0..epochs {
        let results = trainers
            .par_iter_mut()
            .enumerate()
            .map(|(t, tr)| (!failed.contains_key(&owner[t])).then(|| tr.epoch(epoch)))
            .collect::<Vec<_>>();
        let mut done = Vec::new();
        for (t, r) in results.into_iter().enumerate() {
            match r {
                Some(Ok(e)) => {
                    history[t].push(e.clone());
                    done.push((t, e));
                }
                Some(Err(e)) => {
                    failed.entry(owner[t]).or_insert(e);
                }
                None => {}
            }
        }
        if owner.iter().all(|m| failed.contains_key(m)) {
            break;
        }
        let nets = done
            .into_iter()
            .filter(|(t, _)| !failed.contains_key(&owner[*t]))
            .map(|(_, e)| e)
            .collect();
        progress(&EpochReport { epoch, nets });
    }
    (history, failed)
}
