//! Training and validation of pose models (report ch. 4.2-4.3).
use crate::dataset::TapData;
use crate::error::{LabError, Result};
use serde::Serialize;
use tactrace_learn::{
    mean_absolute_error, ModelConfig, ModelKind, PoseModel, Preset, TrainingHistory,
};

/// Resolve a model configuration: the preset for `kind`, then the keys of an
/// optional TOML override (unknown keys are errors), then `epochs`.
pub fn resolve_config(
    kind: ModelKind,
    preset: Preset,
    toml_text: Option<&str>,
    epochs: Option<usize>,
) -> Result<ModelConfig> {
    let mut cfg = ModelConfig::preset(kind, preset);
    if let Some(text) = toml_text {
        let base = toml::Value::try_from(&cfg).map_err(|e| LabError::Config(e.to_string()))?;
        let over: toml::Value =
            toml::from_str(text).map_err(|e| LabError::Config(format!("model config: {e}")))?;
        let merged = merge(base, over);
        cfg = merged
            .try_into()
            .map_err(|e: toml::de::Error| LabError::Config(format!("model config: {e}")))?;
    }
    if let Some(e) = epochs {
        cfg.set_epochs(e);
    }
    Ok(cfg)
}

/// Overlay `over` on `base`, table by table.
fn merge(base: toml::Value, over: toml::Value) -> toml::Value {
    match (base, over) {
        (toml::Value::Table(mut b), toml::Value::Table(o)) => {
            for (k, v) in o {
                let merged = match b.remove(&k) {
                    Some(old) => merge(old, v),
                    None => v,
                };
                b.insert(k, merged);
            }
            toml::Value::Table(b)
        }
        (_, o) => o,
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

/// Validate `model` on `data`.
pub fn validate(model: &PoseModel, data: &TapData) -> Result<Validation> {
    let ds = data.to_learn()?;
    if model.input_dim() != data.dim() {
        return Err(LabError::Config(format!(
            "the model expects {} inputs per sample but the dataset has {} (different pin count?)",
            model.input_dim(),
            data.dim()
        )));
    }
    let predictions = model.predict_batch(&ds)?;
    let [position_mae_mm, angle_mae_deg] = mean_absolute_error(&predictions, &ds);
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
