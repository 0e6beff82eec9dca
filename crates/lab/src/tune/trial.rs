//! One candidate controller's scoring as an [`Evaluation`], so that a
//! tuning's start and generations run through an executor (this machine
//! or Ray), and one held-out run ([`HeldOutTrial`]) likewise, for the
//! judgement.
use super::{load_set, simulate, Named, Objective, RunScore};
use crate::error::{LabError, Result};
use crate::follow::SimFollowConfig;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use tactrace_control::PbtsConfig;
use tactrace_optim::Evaluation;
use tactrace_store::StoredModel;

/// A candidate controller run once on every training contour (the base
/// follow seed); its score is the objective's mean cost (`None`: a failed
/// candidate, scored +inf: a cost that is not a finite number, or a run
/// that stopped with an error other than bad input).
pub struct TuneTrial {
    context: TuneContext,
    model: StoredModel,
    training: Vec<Named>,
}

/// What a remote worker rebuilds a [`TuneTrial`] from: the base follow
/// configuration, the model's folder and the training contours' specs
/// (files it must see: a shared file system), the objective.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TuneContext {
    pub base: SimFollowConfig,
    pub model: PathBuf,
    pub training: Vec<String>,
    pub objective: Objective,
}

impl TuneTrial {
    /// The evaluation of `context` with its model already loaded.
    pub fn new(context: TuneContext, model: StoredModel) -> Result<Self> {
        let training = load_set(&context.training, "training")?;
        Ok(TuneTrial {
            context,
            model,
            training,
        })
    }

    /// The evaluation a remote worker rebuilds from its context JSON.
    pub fn from_context(context: &str) -> Result<Self> {
        let context: TuneContext = crate::remote::parse_context(Self::NAME, context)?;
        let model = StoredModel::load(&context.model)?;
        Self::new(context, model)
    }

    /// The training contours.
    pub fn training(&self) -> &[Named] {
        &self.training
    }
}

impl Evaluation for TuneTrial {
    const NAME: &'static str = "tactrace.tune.controller";
    type Config = PbtsConfig;
    type Score = Option<f64>;
    type Error = LabError;

    fn evaluate(&self, controller: &PbtsConfig) -> Result<Option<f64>> {
        let scored = super::score_candidate(
            &self.context.base,
            controller,
            &self.model,
            &self.training,
            &self.context.objective,
            &|| {},
        );
        match scored {
            Ok((cost, _)) => Ok(cost.is_finite().then_some(cost)),
            Err(e) if !e.is_bad_input() => Ok(None),
            Err(e) => Err(e),
        }
    }

    fn context(&self) -> Option<String> {
        crate::remote::context_json(Self::NAME, &self.context)
    }
}

/// One held-out run of the judgement: a controller on one held-out
/// contour with one seed offset (the follow seed + 1000 + `seed_offset`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeldOutRun {
    pub controller: PbtsConfig,
    /// Index into the held-out contours.
    pub contour: usize,
    pub seed_offset: u64,
}

/// The judgement's runs as an evaluation: a [`HeldOutRun`] simulated as
/// `follow` would, its [`RunScore`] returned.
pub struct HeldOutTrial {
    context: HeldOutContext,
    model: StoredModel,
    held_out: Vec<Named>,
}

/// What a remote worker rebuilds a [`HeldOutTrial`] from: the base follow
/// configuration, the model's folder, the held-out contours' specs.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeldOutContext {
    pub base: SimFollowConfig,
    pub model: PathBuf,
    pub held_out: Vec<String>,
}

impl HeldOutTrial {
    /// The evaluation of `context` with its model already loaded.
    pub fn new(context: HeldOutContext, model: StoredModel) -> Result<Self> {
        let held_out = load_set(&context.held_out, "held-out")?;
        Ok(HeldOutTrial {
            context,
            model,
            held_out,
        })
    }

    /// The evaluation a remote worker rebuilds from its context JSON.
    pub fn from_context(context: &str) -> Result<Self> {
        let context: HeldOutContext = crate::remote::parse_context(Self::NAME, context)?;
        let model = StoredModel::load(&context.model)?;
        Self::new(context, model)
    }

    /// The held-out contours.
    pub fn held_out(&self) -> &[Named] {
        &self.held_out
    }
}

impl Evaluation for HeldOutTrial {
    const NAME: &'static str = "tactrace.tune.held_out";
    type Config = HeldOutRun;
    type Score = RunScore;
    type Error = LabError;

    fn evaluate(&self, run: &HeldOutRun) -> Result<RunScore> {
        let (name, contour) = self
            .held_out
            .get(run.contour)
            .ok_or_else(|| LabError::Config(format!("no held-out contour {}", run.contour)))?;
        let mut c = SimFollowConfig {
            controller: run.controller.clone(),
            ..self.context.base.clone()
        };
        c.follow.seed = self.context.base.follow.seed + 1000 + run.seed_offset;
        simulate(&c, &self.model, (name, contour))
    }

    fn context(&self) -> Option<String> {
        crate::remote::context_json(Self::NAME, &self.context)
    }
}
