//! One candidate controller's scoring as an [`Evaluation`], so that a
//! tuning's generations run through an executor (this machine or Ray).
use super::{load_set, Named, Objective};
use crate::error::{LabError, Result};
use crate::follow::SimFollowConfig;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use tactrace_control::PbtsConfig;
use tactrace_optim::Evaluation;
use tactrace_store::StoredModel;

/// A candidate controller run once on every training contour (the base
/// follow seed); its score is the objective's mean cost (`None`: not a
/// finite number, scored +inf).
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
        let (cost, _) = super::score_candidate(
            &self.context.base,
            controller,
            &self.model,
            &self.training,
            &self.context.objective,
            &|| {},
        )?;
        Ok(cost.is_finite().then_some(cost))
    }

    fn context(&self) -> Option<String> {
        crate::remote::context_json(Self::NAME, &self.context)
    }
}
