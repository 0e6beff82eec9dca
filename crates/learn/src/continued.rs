//! Continuing a fitted pose model's training (`train --init` with a pin
//! model): the same nets trained further from their weights, by a new
//! schedule, on the standardiser, PCA and target scaling the model was
//! fitted with (its nets' inputs and outputs are in those units), over
//! the same turned or mirrored copies and features.
//!
//! The schedule is the configuration's: `epochs` more epochs at its rates,
//! annealed over its own last `anneal_fraction` of them. The shuffles go on
//! from where the model's left off ([`crate::trainer::Trainer::skip_epochs`]),
//! so with constant rates (`anneal_fraction = 0`) and the same seed and
//! rates, continuing a model of N epochs for M more gives the model of
//! N + M epochs from scratch, bit for bit. An annealed fit cannot be
//! continued so: its rates fell over its last epochs, which a fit of more
//! epochs would have run at the full rate.
use crate::config::ModelConfig;
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::fit_members::continue_members;
use crate::pose_model::{checked_encoded, PinData, PoseModel};
use crate::setting_difference::{first_difference, SettingDifference};
use crate::trainer::{EpochReport, TrainingHistory};
use serde_json::Value;

impl PoseModel {
    /// This model's nets trained further on `train` by `cfg` (`train`,
    /// `val` and `reference_pins` as [`PoseModel::fit_targets_on_pins`]
    /// takes them, the targets this model's): `cfg.epochs` more epochs
    /// at `cfg`'s rates and anneal, shuffles from `cfg.seed` continued past
    /// this model's epochs. The standardiser, PCA, target scaling and
    /// turned views are this model's; the new model records the epochs its
    /// nets trained before (`epochs_before`). Refused unless `cfg`
    /// describes the same nets ([`check_continuable`]) and `train` gives
    /// the rows this model's were made as (inputs, pins, copies).
    /// `cfg.epochs = 0` gives this model's nets untouched (a check).
    pub fn continue_on_pins(
        &self,
        cfg: &ModelConfig,
        train: &Dataset,
        val: Option<&Dataset>,
        reference_pins: Option<&[[f64; 2]]>,
        progress: &mut dyn FnMut(&EpochReport),
    ) -> Result<(PoseModel, TrainingHistory), LearnError> {
        check_continuable(&self.config, cfg)?;
        ModelConfig {
            epochs: cfg.epochs.max(1),
            ..cfg.clone()
        }
        .validate()?;
        let data = PinData::prepare(cfg, &self.outputs, train, val, reference_pins)?;
        if !data.made_as(self) {
            return Err(refused(
                "the training pins, or the copies or features made over them, are not \
                 those the model was fitted over"
                    .into(),
            ));
        }
        let (rows, val_rows) = data.sets(train, val);
        let (rows, val_rows) = checked_encoded(&self.outputs, rows, val_rows)?;
        if rows.dim_x != self.standardiser.dim() {
            return Err(LearnError::DimensionMismatch {
                expected: self.standardiser.dim(),
                got: rows.dim_x,
            });
        }
        let (mut model, history) = continue_members(self, cfg, &rows, val_rows.as_ref(), progress)?;
        data.attach(&mut model);
        Ok((model, history))
    }

    /// Epochs the nets trained before this fit's `config.epochs` (0 for a
    /// model fitted from fresh weights; see [`Self::continue_on_pins`]).
    pub fn epochs_before(&self) -> usize {
        self.epochs_before
    }
}

/// Error unless `next` describes the nets of a model fitted by `start`:
/// the same kind, nets (layers, components), scalings, phases, members,
/// circular weight, features, rotations and reflections. The schedule may
/// differ: epochs, seed, rates, `beta`, anneal, divergence retries, input
/// noise, band weight, and whether turned views average at prediction.
pub fn check_continuable(start: &ModelConfig, next: &ModelConfig) -> Result<(), LearnError> {
    let (a, b) = (nets_of(start)?, nets_of(next)?);
    match first_difference(&a, &b) {
        None => Ok(()),
        Some(SettingDifference { key, was, now }) => Err(refused(format!(
            "`{key}` is {was} in the model and {now} in the configuration: a continued fit \
             trains the same nets"
        ))),
    }
}

/// `cfg` as JSON with what a continued fit may change set to fixed values.
fn nets_of(cfg: &ModelConfig) -> Result<Value, LearnError> {
    let mut c = cfg.clone();
    c.epochs = 1;
    c.seed = 0;
    c.divergence_retries = 0;
    c.anneal_fraction = 0.0;
    c.input_noise = 0.0;
    c.band_weight = None;
    c.cost = None;
    if let Some(r) = c.rotations.as_mut() {
        r.at_prediction = false;
    }
    if let Some(r) = c.reflections.as_mut() {
        r.at_prediction = false;
    }
    for net in [&mut c.pose, &mut c.position, &mut c.angle]
        .into_iter()
        .flatten()
    {
        net.learning_rate = 1.0;
        net.output_learning_rate = None;
        net.beta = 1.0;
    }
    serde_json::to_value(&c).map_err(|e| refused(e.to_string()))
}

fn refused(reason: String) -> LearnError {
    LearnError::Config {
        field: "init",
        reason,
    }
}
