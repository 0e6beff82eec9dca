//! Training and validation of pose models (report ch. 4.2-4.3).
use crate::error::{LabError, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};
use tactrace_learn::{
    hyperparameter_search, mean_absolute_error, ModelConfig, ModelKind, PoseModel, Preset,
    SearchSpace, TrainingHistory, Trial,
};
use tactrace_store::{stage_model, StoredModel, TapData};

/// Resolve a model configuration: the preset for `kind`, then the keys of an
/// optional TOML override (unknown keys are errors), then `epochs`; the
/// result is validated here, before any work (a NaN or out-of-range value
/// is an error naming its key).
pub fn resolve_config(
    kind: ModelKind,
    preset: Preset,
    toml_text: Option<&str>,
    epochs: Option<usize>,
) -> Result<ModelConfig> {
    let mut cfg = ModelConfig::preset(kind, preset);
    if let Some(text) = toml_text {
        cfg = tactrace_store::overlay(&cfg, text, "model config")?;
    }
    if let Some(e) = epochs {
        cfg.set_epochs(e);
    }
    cfg.validate()?;
    Ok(cfg)
}

/// Error unless `cfg` can be fitted on the `train` samples, before any
/// work; `held_out` samples were set aside for validation (named in the
/// message, since they are what made the training part too small).
pub fn check_trainable(cfg: &ModelConfig, train: &TapData, held_out: usize) -> Result<()> {
    match cfg.check_samples(train.len(), train.dim()) {
        Err(tactrace_learn::LearnError::TooFewSamples {
            got,
            needed,
            reason,
        }) => Err(LabError::TooFewSamples {
            got,
            needed,
            reason,
            held_out,
        }),
        other => Ok(other?),
    }
}

/// Fit a model on a training set.
pub fn train(
    cfg: &ModelConfig,
    data: &TapData,
    progress: &mut dyn FnMut(usize),
) -> Result<(PoseModel, TrainingHistory)> {
    let ds = data.to_learn()?;
    let mut cb = |r: &tactrace_learn::EpochReport| progress(r.epoch + 1);
    Ok(PoseModel::fit(cfg, &ds, &mut cb)?)
}

/// As [`train`], also recording each net's loss on `val` per epoch in the
/// history (`val` is never used for fitting).
pub fn train_with_validation(
    cfg: &ModelConfig,
    data: &TapData,
    val: Option<&TapData>,
    progress: &mut dyn FnMut(usize),
) -> Result<(PoseModel, TrainingHistory)> {
    let ds = data.to_learn()?;
    let vs = val.map(TapData::to_learn).transpose()?;
    if let Some(v) = &vs {
        check_dim(ds.dim_x, v.dim_x)?;
    }
    let mut cb = |r: &tactrace_learn::EpochReport| progress(r.epoch + 1);
    Ok(PoseModel::fit_with_validation(
        cfg,
        &ds,
        vs.as_ref(),
        &mut cb,
    )?)
}

/// Split `data` into a training part and a held-out part of `fraction`
/// of the samples (seeded shuffle); both parts must be non-empty.
pub fn holdout(data: &TapData, fraction: f64, seed: u64) -> Result<(TapData, TapData)> {
    if !(fraction > 0.0 && fraction < 1.0) {
        return Err(LabError::Config(format!(
            "validation fraction {fraction} must be strictly between 0 and 1"
        )));
    }
    let (tr, va) = data.split(1.0 - fraction, seed);
    if tr.is_empty() || va.is_empty() {
        return Err(LabError::Config(format!(
            "{} samples are too few to hold out a fraction {fraction}",
            data.len()
        )));
    }
    Ok((tr, va))
}

/// Hyper-parameter search (report's further work) on `data`, the training
/// set: `fraction` of it (seeded) is held out as the search's validation
/// split; nothing else is seen. Trials come back best first.
pub fn search(
    base: &ModelConfig,
    space: &SearchSpace,
    data: &TapData,
    fraction: f64,
    seed: u64,
    progress: &mut dyn FnMut(&Trial),
) -> Result<Vec<Trial>> {
    let (inner, val) = holdout(data, fraction, seed)?;
    let (inner, val) = (inner.to_learn()?, val.to_learn()?);
    Ok(hyperparameter_search(base, space, &inner, &val, progress)?)
}

/// One line describing a trial's hyper-parameters (the first net's; the
/// search sets every net alike).
pub fn trial_summary(t: &Trial) -> String {
    let c = &t.config;
    let net = c
        .pose
        .as_ref()
        .or(c.angle.as_ref())
        .expect("a validated config has a net");
    let hidden: Vec<String> = net.hidden.iter().map(usize::to_string).collect();
    format!(
        "lr {} output lr {} beta {} hidden [{}] components {}",
        net.learning_rate,
        net.output_learning_rate.unwrap_or(net.learning_rate),
        net.beta,
        hidden.join(", "),
        net.n_components
            .map(|k| k.to_string())
            .unwrap_or_else(|| "-".into())
    )
}

/// The trials as CSV (best first).
pub fn trials_csv(trials: &[Trial]) -> String {
    let mut out = String::from(
        "rank,learning_rate,output_learning_rate,beta,hidden,n_components,position_mae_mm,angle_mae_deg,score\n",
    );
    for (k, t) in trials.iter().enumerate() {
        let c = &t.config;
        if let Some(net) = c.pose.as_ref().or(c.angle.as_ref()) {
            out.push_str(&format!(
                "{},{},{},{},{},{},{},{},{}\n",
                k + 1,
                net.learning_rate,
                net.output_learning_rate.unwrap_or(net.learning_rate),
                net.beta,
                net.hidden
                    .iter()
                    .map(|h| h.to_string())
                    .collect::<Vec<_>>()
                    .join(" "),
                net.n_components.map(|k| k.to_string()).unwrap_or_default(),
                t.val_mae[0],
                t.val_mae[1],
                t.score
            ));
        }
    }
    out
}

fn check_dim(expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(LabError::Config(format!(
            "the model expects {expected} inputs per sample but the dataset has {got} (different pin count?)"
        )))
    }
}

/// Mean absolute errors of a model on a dataset, with the predictions.
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    pub position_mae_mm: f64,
    pub angle_mae_deg: f64,
    pub samples: usize,
    #[serde(skip)]
    pub predictions: Vec<[f64; 2]>,
    #[serde(skip)]
    pub truth: Vec<[f64; 2]>,
}

/// Save a trained model with the reference pins of its training data, its
/// history, `extra` text files and the loss/energy figure (Fig. 4.5) into
/// `dir`, which appears only when complete.
pub fn save_model(
    dir: &Path,
    model: &PoseModel,
    reference_pins: &[[f64; 2]],
    history: &TrainingHistory,
    force: bool,
    extra: &[(&str, String)],
) -> Result<PathBuf> {
    let stage = stage_model(dir, model, reference_pins, history, force, extra)?;
    tactrace_report::figures::training_curves(&stage.path().join("loss_energy"), history)?;
    Ok(stage.commit()?)
}

/// Validate `model` on `data` (named `what`), refused when the data's pins
/// are ordered otherwise than the model's training data.
pub fn validate(model: &StoredModel, data: &TapData, what: &Path) -> Result<Validation> {
    let model = model.for_data(data, what)?;
    validate_net(model, data)
}

/// Validate a network just trained on data ordered like `data`.
pub fn validate_net(model: &PoseModel, data: &TapData) -> Result<Validation> {
    let ds = data.to_learn()?;
    check_dim(model.input_dim(), data.dim())?;
    let predictions = model.predict_batch(&ds)?;
    let [position_mae_mm, angle_mae_deg] = mean_absolute_error(&predictions, &ds);
    for (k, p) in predictions.iter().enumerate() {
        crate::numbers::require_finite(
            &format!("the model's prediction for row {k} of the dataset"),
            &[("r", p[0]), ("theta", p[1])],
            "the row's inputs lie far outside the training data's, or the model is \
             degenerate (trained on too few samples?)",
        )?;
    }
    crate::numbers::require_finite(
        "the validation",
        &[
            ("the position MAE", position_mae_mm),
            ("the angle MAE", angle_mae_deg),
        ],
        "",
    )?;
    let truth = data
        .targets
        .chunks(2)
        .map(|t| [t[0] as f64, t[1] as f64])
        .collect();
    Ok(Validation {
        position_mae_mm,
        angle_mae_deg,
        samples: data.len(),
        predictions,
        truth,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactrace_store::DatasetMeta;

    fn data(n: usize) -> TapData {
        let meta: DatasetMeta = serde_json::from_value(serde_json::json!({
            "source": "test", "origin": "", "seed": null, "samples": n, "pins": 1,
            "targets": ["r", "theta"], "frames_with_missing_pins": 0,
            "reference_pins": [[0.0, 0.0]], "settings": null, "tactrace_version": ""
        }))
        .expect("meta");
        TapData {
            inputs: (0..2 * n).map(|v| v as f32).collect(),
            targets: (0..2 * n).map(|v| v as f32).collect(),
            meta,
        }
    }

    #[test]
    fn holdout_is_seeded_disjoint_and_checked() {
        let d = data(50);
        let (tr, va) = holdout(&d, 0.2, 1).unwrap();
        assert_eq!((tr.len(), va.len()), (40, 10));
        let (tr2, _) = holdout(&d, 0.2, 1).unwrap();
        assert_eq!(tr.inputs, tr2.inputs);
        for row in va.inputs.chunks(2) {
            assert!(!tr.inputs.chunks(2).any(|r| r == row));
        }
        for bad in [0.0, 1.0, -0.5, f64::NAN] {
            assert!(holdout(&d, bad, 1).is_err());
        }
        assert!(holdout(&data(1), 0.5, 1).is_err());
    }
}
