//! Fitting a model's members ([`ModelConfig::ensemble`]; a single model is
//! a member of one): the shared standardiser, target scaling and PCA
//! fitted once, every member's nets trained side by side, and a member
//! that diverges restarted alone, from its own seed, with its learning
//! rates halved, while the other members keep what they learnt. Each
//! member is therefore the model its seed gives alone (at the rates it
//! finally trained with), whether or not another member diverged.
use crate::band_weight::epoch_rows;
use crate::config::ModelConfig;
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::pca::{Components, Pca};
use crate::pose_model::{FittedNet, PoseModel};
use crate::standardise::Standardiser;
use crate::targets::{self, ModelTarget};
use crate::trainer::{train_nets, EpochReport, NetData, NetEpoch, Trainer, TrainingHistory};
use crate::Layers;
use std::collections::BTreeMap;
use std::sync::OnceLock;

/// What every member shares: the scaled inputs, the target scaling and
/// each net's target columns and projection.
struct Shared<'a> {
    cfg: &'a ModelConfig,
    outputs: &'a [ModelTarget],
    train: &'a Dataset,
    val: Option<&'a Dataset>,
    targets: Standardiser,
    z: Vec<f64>,
    z_val: Option<Vec<f64>>,
    /// Per net of a member: its encoded target columns and PCA.
    plans: Vec<(Vec<usize>, Option<Pca>)>,
    /// The rows an epoch visits ([`crate::band_weight::epoch_rows`]).
    rows: Vec<usize>,
    /// The model a continued fit starts from: its nets in model order
    /// and the epochs they trained (`None`: fresh weights).
    start: Option<(&'a [FittedNet], usize)>,
}

/// Fit `cfg`'s members on the encoded targets `train` (and report on
/// `val`), restarting a diverged member alone with halved rates up to
/// `cfg.divergence_retries` times; the first member out of retries ends
/// the fit with its divergence.
pub(crate) fn fit_members(
    cfg: &ModelConfig,
    outputs: &[ModelTarget],
    train: &Dataset,
    val: Option<&Dataset>,
    progress: &mut dyn FnMut(&EpochReport),
) -> Result<(PoseModel, TrainingHistory), LearnError> {
    cfg.validate()?;
    cfg.check_samples(train.n, train.dim_x)?;
    let standardiser = Standardiser::fit(&train.x, train.n, train.dim_x)?;
    let shared = Shared::new(cfg, outputs, train, val, &standardiser)?;
    train_members(shared, standardiser, progress)
}

/// Train `start`'s members further on the encoded targets `train` by
/// `cfg` (already checked to describe `start`'s nets): `start`'s
/// standardiser, target scaling and PCA kept, every net starting from its
/// weights, its shuffles continuing from the epochs `start` trained
/// ([`Trainer::skip_epochs`]); a diverged member restarts alone from
/// `start`'s weights with its rates halved, as in [`fit_members`].
pub(crate) fn continue_members(
    start: &PoseModel,
    cfg: &ModelConfig,
    train: &Dataset,
    val: Option<&Dataset>,
    progress: &mut dyn FnMut(&EpochReport),
) -> Result<(PoseModel, TrainingHistory), LearnError> {
    cfg.check_samples(train.n, train.dim_x)?;
    let shared = Shared::continuing(start, cfg, train, val)?;
    let (mut model, history) = train_members(shared, start.standardiser.clone(), progress)?;
    model.epochs_before = start.epochs_before + start.config.epochs;
    Ok((model, history))
}

/// Train every member of `shared`, restarting a diverged member alone with
/// halved rates up to `divergence_retries` times; the first member out of
/// retries ends the fit with its divergence.
fn train_members(
    shared: Shared,
    standardiser: Standardiser,
    progress: &mut dyn FnMut(&EpochReport),
) -> Result<(PoseModel, TrainingHistory), LearnError> {
    let cfg = shared.cfg;
    let (k, per) = (cfg.ensemble, shared.plans.len());
    let mut halvings = vec![0usize; k];
    let mut layers: Vec<Option<Layers>> = vec![None; k * per];
    let mut epochs: Vec<Vec<NetEpoch>> = vec![Vec::new(); k * per];
    let mut todo: Vec<usize> = (0..k).collect();
    while !todo.is_empty() {
        let mut trainers = Vec::with_capacity(todo.len() * per);
        let mut owner = Vec::with_capacity(todo.len() * per);
        for &m in &todo {
            trainers.extend(shared.member_trainers(m, halvings[m])?);
            owner.extend(std::iter::repeat_n(m, per));
        }
        let (history, failed) = train_nets(&mut trainers, &owner, cfg.epochs, progress);
        let mut next = Vec::new();
        for (j, (t, net_epochs)) in trainers.into_iter().zip(history).enumerate() {
            let m = owner[j];
            if failed.contains_key(&m) {
                continue;
            }
            let slot = m * per + j % per;
            layers[slot] = Some(t.into_layers());
            epochs[slot] = net_epochs;
        }
        for (m, err) in failed {
            if halvings[m] >= cfg.divergence_retries {
                return Err(err);
            }
            halvings[m] += 1;
            next.push(m);
        }
        todo = next;
    }
    let model = shared.model(standardiser, layers, &halvings)?;
    Ok((model, history_of(epochs, cfg.epochs, &halvings)))
}

impl<'a> Shared<'a> {
    fn new(
        cfg: &'a ModelConfig,
        outputs: &'a [ModelTarget],
        train: &'a Dataset,
        val: Option<&'a Dataset>,
        standardiser: &Standardiser,
    ) -> Result<Self, LearnError> {
        let encoded = targets::encoded_columns(outputs);
        let rows = epoch_rows(cfg.band_weight.as_ref(), outputs, train)?;
        let targets = fit_target_scaling(cfg, train)?;
        let targets = weight_circular(targets, cfg.circular_weight, outputs, &encoded)?;
        let z = standardiser.transform(&train.x);
        let z_val = val.map(|v| standardiser.transform(&v.x));
        let mut plans = Vec::new();
        for (_, which, net_cfg) in cfg.nets_for(outputs) {
            let cols: Vec<usize> = which.iter().flat_map(|&t| encoded[t].clone()).collect();
            let pca = match net_cfg.n_components {
                Some(c) => Some(Pca::fit(
                    &z,
                    train.n,
                    train.dim_x,
                    Components::Count(c),
                    cfg.pc_scaling,
                )?),
                None => None,
            };
            plans.push((cols, pca));
        }
        Ok(Self {
            cfg,
            outputs,
            train,
            val,
            targets,
            z,
            z_val,
            plans,
            rows,
            start: None,
        })
    }

    /// What a fit continuing `start` shares: `start`'s standardiser,
    /// target scaling and each net's target columns and PCA.
    fn continuing(
        start: &'a PoseModel,
        cfg: &'a ModelConfig,
        train: &'a Dataset,
        val: Option<&'a Dataset>,
    ) -> Result<Self, LearnError> {
        let per = start.nets.len() / start.config.ensemble.max(1);
        let plans = (start.nets.iter().take(per))
            .map(|n| (n.targets.clone(), n.pca.clone()))
            .collect();
        Ok(Self {
            cfg,
            outputs: &start.outputs,
            train,
            val,
            targets: start.targets.clone(),
            z: start.standardiser.transform(&train.x),
            z_val: val.map(|v| start.standardiser.transform(&v.x)),
            plans,
            rows: epoch_rows(cfg.band_weight.as_ref(), &start.outputs, train)?,
            start: Some((&start.nets, start.epochs_before + start.config.epochs)),
        })
    }

    /// The configuration member `m` trains with after `halvings` halvings
    /// of its rates: the model's, with the member's seed.
    fn member_config(&self, m: usize, halvings: usize) -> ModelConfig {
        let mut member = ModelConfig {
            seed: self.cfg.member_seed(m),
            ..self.cfg.clone()
        };
        for _ in 0..halvings {
            member.scale_learning_rates(0.5);
        }
        member
    }

    /// Member `m`'s nets, ready to train, from its seed.
    fn member_trainers(&self, m: usize, halvings: usize) -> Result<Vec<Trainer>, LearnError> {
        let member = self.member_config(m, halvings);
        let k = self.cfg.ensemble;
        let mut out = Vec::with_capacity(self.plans.len());
        for (j, ((name, _, net_cfg), (cols, pca))) in member
            .nets_for(self.outputs)
            .into_iter()
            .zip(&self.plans)
            .enumerate()
        {
            let data = NetData::new(
                net_inputs(pca.as_ref(), &self.z),
                self.train,
                cols,
                &self.targets,
            )?
            .with_rows(self.rows.clone());
            let val_data = match (self.val, &self.z_val) {
                (Some(v), Some(zv)) => Some(NetData::new(
                    net_inputs(pca.as_ref(), zv),
                    v,
                    cols,
                    &self.targets,
                )?),
                _ => None,
            };
            let layers = match self.start {
                Some((nets, _)) => nets[m * self.plans.len() + j].layers.clone(),
                None => Layers::new(
                    &self.sizes(j, data.set.dim_x),
                    member.seed.wrapping_add(j as u64),
                )?,
            };
            let name = member_name(&name, m, k);
            let cost = (member.cost.as_ref())
                .map(|c| c.for_net(self.outputs, cols, self.targets.std()))
                .transpose()?
                .flatten();
            let mut trainer =
                Trainer::new(&name, layers, &member, net_cfg, data, val_data, j as u64)
                    .with_cost(cost);
            if let Some((_, done)) = self.start {
                trainer.skip_epochs(done);
            }
            out.push(trainer);
        }
        Ok(out)
    }

    /// Layer sizes of net `j` of a member on `dim` inputs.
    fn sizes(&self, j: usize, dim: usize) -> Vec<usize> {
        let (_, _, net_cfg) = &self.cfg.nets_for(self.outputs)[j];
        let mut sizes = vec![dim];
        sizes.extend(&net_cfg.hidden);
        sizes.push(self.plans[j].0.len());
        sizes
    }

    /// The fitted model: a single model's configuration holds the rates it
    /// trained with; an ensemble's the members' starting rates, each net
    /// recording its member's halvings.
    fn model(
        self,
        standardiser: Standardiser,
        layers: Vec<Option<Layers>>,
        halvings: &[usize],
    ) -> Result<PoseModel, LearnError> {
        let k = self.cfg.ensemble;
        let config = if k == 1 {
            self.member_config(0, halvings[0])
        } else {
            self.cfg.clone()
        };
        let names = self.cfg.nets_for(self.outputs);
        let per = self.plans.len();
        let mut nets = Vec::with_capacity(layers.len());
        for (slot, l) in layers.into_iter().enumerate() {
            let (m, j) = (slot / per, slot % per);
            nets.push(FittedNet {
                name: member_name(&names[j].0, m, k),
                targets: self.plans[j].0.clone(),
                pca: self.plans[j].1.clone(),
                layers: l.expect("every member trained"),
                lr_halvings: if k == 1 { 0 } else { halvings[m] },
            });
        }
        Ok(PoseModel {
            config,
            standardiser,
            targets: self.targets,
            nets,
            outputs: self.outputs.to_vec(),
            features: None,
            views: None,
            mirror: None,
            epochs_before: 0,
            predictor: OnceLock::new(),
        })
    }
}

/// The history of the nets' last fits, by epoch, nets in model order.
fn history_of(epochs: Vec<Vec<NetEpoch>>, count: usize, halvings: &[usize]) -> TrainingHistory {
    let mut reports: Vec<EpochReport> = (0..count)
        .map(|epoch| EpochReport {
            epoch,
            nets: Vec::with_capacity(epochs.len()),
        })
        .collect();
    for net in epochs {
        for (e, entry) in net.into_iter().enumerate() {
            reports[e].nets.push(entry);
        }
    }
    TrainingHistory {
        epochs: reports,
        lr_halvings: halvings.iter().copied().max().unwrap_or(0),
        member_lr_halvings: if halvings.len() > 1 {
            halvings.to_vec()
        } else {
            Vec::new()
        },
    }
}

/// A net's name in member `m` of an ensemble of `k`: the single model's
/// name for `k = 1`, else `name#m` counting members from 1.
pub(crate) fn member_name(name: &str, m: usize, k: usize) -> String {
    if k == 1 {
        name.to_string()
    } else {
        format!("{name}#{}", m + 1)
    }
}

/// Project standardised rows through `pca`, or pass them through.
pub(crate) fn net_inputs(pca: Option<&Pca>, z: &[f64]) -> Vec<f64> {
    match pca {
        Some(p) => p.transform(z),
        None => z.to_vec(),
    }
}

fn fit_target_scaling(cfg: &ModelConfig, train: &Dataset) -> Result<Standardiser, LearnError> {
    use crate::config::TargetScaling;
    match cfg.target_scaling {
        TargetScaling::Standardise => Standardiser::fit(&train.y, train.n, train.dim_y),
        TargetScaling::None => {
            Standardiser::from_parts(vec![0.0; train.dim_y], vec![1.0; train.dim_y])
        }
    }
}

/// `scaling` with every circular target's encoded columns weighted by
/// `w` ([`ModelConfig::circular_weight`]): their spread divided by it.
fn weight_circular(
    scaling: Standardiser,
    w: f64,
    outputs: &[ModelTarget],
    encoded: &[Vec<usize>],
) -> Result<Standardiser, LearnError> {
    if w == 1.0 {
        return Ok(scaling);
    }
    let mut std = scaling.std().to_vec();
    for (t, cols) in outputs.iter().zip(encoded) {
        if t.circular {
            cols.iter().for_each(|&c| std[c] /= w);
        }
    }
    Standardiser::from_parts(scaling.mean().to_vec(), std)
}

/// Each member's first divergence, by member.
pub(crate) type Failures = BTreeMap<usize, LearnError>;
