//! Model (de)serialisation to a JSON string (format version, kind, config,
//! architecture, standardiser, PCA, target scaling, the targets predicted:
//! names, units, circular flags; an ensemble's members' nets one after
//! the other, `config.ensemble` of them) plus safetensors bytes
//! (the weights, in the report's `W(l)` orientation `d(l-1) x d(l)`). Pure:
//! the lab crate writes the files.
use crate::config::{ModelConfig, ModelKind};
use crate::error::LearnError;
use crate::net::Layers;
use crate::pca::Pca;
use crate::pin_features::FeatureMap;
use crate::pose_model::{FittedNet, PoseModel};
use crate::standardise::Standardiser;
use crate::targets::{check_targets as check_outputs, edge_targets, ModelTarget};
use crate::turned_views::TurnedViews;
use safetensors::SafeTensors;
use serde::{Deserialize, Serialize};
use tactrace_convnet::model_file::{
    read_f32, read_header, read_tensors, write_tensors, ModelFileError, Tensor,
};

/// Identifies our model files.
const FORMAT: &str = "tactrace-pose-model";
/// Bumped on any incompatible change. Version 3 names the targets
/// (`outputs`); version 2 files, written before, are the edge task's
/// `r` (mm) and `theta` (deg) and still load.
pub const FORMAT_VERSION: u32 = 3;
/// The oldest version read.
const OLDEST_VERSION: u32 = 2;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    format: String,
    version: u32,
    kind: ModelKind,
    config: ModelConfig,
    input_dim: usize,
    standardiser: Standardiser,
    target_scaling: Standardiser,
    nets: Vec<NetFile>,
    /// The targets predicted (absent in version 2: the edge task's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    outputs: Option<Vec<ModelTarget>>,
    /// The features the nets see, when not the displacements: their
    /// kind and the reference pins (absent: the displacements).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    features: Option<FeatureMap>,
    /// The reference pins (px) a model with `rotations` was fitted over,
    /// whose turns averaging over turned views takes (absent: no
    /// rotations, or a file written before they were recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rotation_pins: Option<Vec<[f64; 2]>>,
    /// The reference pins (px) a model with `reflections` was fitted
    /// over, whose mirror averaging with the mirror copy takes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reflection_pins: Option<Vec<[f64; 2]>>,
    /// Epochs the nets trained before this fit's `config.epochs` (a model
    /// continued from another, `train --init`; absent: none).
    #[serde(default, skip_serializing_if = "is_zero")]
    epochs_before: usize,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct NetFile {
    name: String,
    targets: Vec<usize>,
    sizes: Vec<usize>,
    pca: Option<Pca>,
    /// Its member's learning-rate halvings after a divergence, beyond the
    /// configuration's (absent: none).
    #[serde(default, skip_serializing_if = "is_zero")]
    lr_halvings: usize,
}

fn is_zero(v: &usize) -> bool {
    *v == 0
}

fn corrupt(reason: impl ToString) -> LearnError {
    LearnError::Corrupt {
        reason: reason.to_string(),
    }
}

fn tensor_name(net: usize, what: &str, l: usize) -> String {
    format!("net{net}.{what}{l}")
}

impl From<ModelFileError> for LearnError {
    fn from(e: ModelFileError) -> Self {
        corrupt(e.reason())
    }
}

impl PoseModel {
    /// Serialise: `(json, safetensors weights)`.
    pub fn to_bytes(&self) -> Result<(String, Vec<u8>), LearnError> {
        let file = ModelFile {
            format: FORMAT.into(),
            version: FORMAT_VERSION,
            kind: self.config.kind,
            config: self.config.clone(),
            input_dim: self.input_dim(),
            standardiser: self.standardiser.clone(),
            target_scaling: self.targets.clone(),
            nets: self
                .nets
                .iter()
                .map(|n| NetFile {
                    name: n.name.clone(),
                    targets: n.targets.clone(),
                    sizes: n.layers.sizes().to_vec(),
                    pca: n.pca.clone(),
                    lr_halvings: n.lr_halvings,
                })
                .collect(),
            outputs: Some(self.outputs.clone()),
            features: self.features.clone(),
            rotation_pins: self.views.as_ref().map(|v| v.pins().to_vec()),
            reflection_pins: self.mirror.as_ref().map(|v| v.pins().to_vec()),
            epochs_before: self.epochs_before,
        };
        let json = serde_json::to_string_pretty(&file).map_err(corrupt)?;
        let mut tensors = Vec::new();
        for (k, net) in self.nets.iter().enumerate() {
            let sizes = net.layers.sizes();
            for l in 1..sizes.len() {
                let (w, b) = (tensor_name(k, "W", l), tensor_name(k, "b", l));
                tensors.push(Tensor::f32(
                    w,
                    vec![sizes[l - 1], sizes[l]],
                    &net.layers.weight(l),
                ));
                tensors.push(Tensor::f32(b, vec![sizes[l]], net.layers.bias(l)));
            }
        }
        Ok((json, write_tensors(&tensors)?))
    }

    /// Rebuild a model from [`Self::to_bytes`] output. Another format
    /// version, truncated or inconsistent data are errors.
    pub fn from_bytes(json: &str, safetensors: &[u8]) -> Result<Self, LearnError> {
        let (value, version) = read_header(json, FORMAT)?;
        if !(OLDEST_VERSION as u64..=FORMAT_VERSION as u64).contains(&version) {
            return Err(LearnError::Version {
                found: version.min(u32::MAX as u64) as u32,
                supported: FORMAT_VERSION,
            });
        }
        let file: ModelFile =
            serde_json::from_value(value).map_err(|e| corrupt(format!("model json: {e}")))?;
        file.config.validate()?;
        let feature_dim = check_features(&file)?;
        let standardiser = Standardiser::from_parts(
            file.standardiser.mean().to_vec(),
            file.standardiser.std().to_vec(),
        )?;
        let targets = Standardiser::from_parts(
            file.target_scaling.mean().to_vec(),
            file.target_scaling.std().to_vec(),
        )?;
        let outputs = file.outputs.unwrap_or_else(edge_targets);
        check_outputs(&outputs).map_err(|e| corrupt(format!("model json: {e}")))?;
        let width: usize = outputs.iter().map(ModelTarget::width).sum();
        if standardiser.dim() != feature_dim || targets.dim() != width {
            return Err(corrupt("standardiser dimensions disagree with the model"));
        }
        let tensors = read_tensors(safetensors)?;
        let nets = file
            .nets
            .into_iter()
            .enumerate()
            .map(|(k, n)| load_net(k, n, &tensors, feature_dim))
            .collect::<Result<Vec<_>, _>>()?;
        check_targets(&nets, width, file.config.ensemble)?;
        let views = load_views(&file.config, file.rotation_pins.as_deref(), file.input_dim)?;
        let mirror = crate::reflections::load_mirror(
            &file.config,
            &outputs,
            file.reflection_pins.as_deref(),
            file.input_dim,
        )
        .map_err(corrupt)?;
        Ok(PoseModel {
            config: file.config,
            standardiser,
            targets,
            nets,
            outputs,
            features: file.features,
            views,
            mirror,
            epochs_before: file.epochs_before,
            predictor: Default::default(),
        })
    }
}

/// The nets' input length of `file` (its features' or its displacements'),
/// after checking its features against its configuration and input length.
fn check_features(file: &ModelFile) -> Result<usize, LearnError> {
    let kind = file.features.as_ref().map(FeatureMap::kind);
    if kind.unwrap_or_default() != file.config.pin_features {
        return Err(corrupt(
            "the model's features disagree with its configuration's pin_features",
        ));
    }
    match &file.features {
        Some(map) if map.input_dim() != file.input_dim => Err(corrupt(format!(
            "features over {} reference pins, but the model takes {} inputs",
            map.input_dim() / 2,
            file.input_dim
        ))),
        Some(map) => Ok(map.output_dim()),
        None => Ok(file.input_dim),
    }
}

/// The turned views of a model with `rotations` over its recorded
/// `pins`; a model that averages them must record pins that match its
/// input length.
fn load_views(
    config: &ModelConfig,
    pins: Option<&[[f64; 2]]>,
    input_dim: usize,
) -> Result<Option<TurnedViews>, LearnError> {
    let (rot, pins) = match (&config.rotations, pins) {
        (Some(rot), Some(pins)) => (rot, pins),
        (Some(rot), None) if rot.at_prediction => {
            return Err(corrupt(
                "rotations.at_prediction is set but the model records no rotation_pins",
            ))
        }
        (None, Some(_)) => return Err(corrupt("rotation_pins without rotations")),
        _ => return Ok(None),
    };
    if 2 * pins.len() != input_dim {
        return Err(corrupt(format!(
            "{} rotation_pins, but the model takes {input_dim} inputs",
            pins.len()
        )));
    }
    TurnedViews::new(rot, pins)
        .map(Some)
        .map_err(|e| corrupt(format!("rotation_pins: {e}")))
}

fn load_net(
    k: usize,
    n: NetFile,
    tensors: &SafeTensors,
    input_dim: usize,
) -> Result<FittedNet, LearnError> {
    let expected_in = match &n.pca {
        Some(p) => {
            p.validate()?;
            if p.dim() != input_dim {
                return Err(corrupt(format!(
                    "net {}: PCA expects {} inputs, model has {input_dim}",
                    n.name,
                    p.dim()
                )));
            }
            p.n_components()
        }
        None => input_dim,
    };
    if n.sizes.len() < 2
        || n.sizes[0] != expected_in
        || n.sizes[n.sizes.len() - 1] != n.targets.len()
    {
        return Err(corrupt(format!(
            "net {}: layer sizes {} do not fit its inputs/targets",
            n.name,
            crate::net::sizes_text(&n.sizes)
        )));
    }
    let mut w = Vec::new();
    let mut b = Vec::new();
    for l in 1..n.sizes.len() {
        w.push(read_f32(
            tensors,
            &tensor_name(k, "W", l),
            &[n.sizes[l - 1], n.sizes[l]],
        )?);
        b.push(read_f32(tensors, &tensor_name(k, "b", l), &[n.sizes[l]])?);
    }
    if n.lr_halvings > crate::config::MAX_RETRIES {
        return Err(corrupt(format!(
            "net {}: {} learning-rate halvings exceed {}",
            n.name,
            n.lr_halvings,
            crate::config::MAX_RETRIES
        )));
    }
    let layers = Layers::from_parts(n.sizes, w, b)?;
    if !layers.is_finite() {
        return Err(corrupt(format!("net {}: non-finite weights", n.name)));
    }
    Ok(FittedNet {
        name: n.name,
        targets: n.targets,
        pca: n.pca,
        layers,
        lr_halvings: n.lr_halvings,
    })
}

/// The nets are `members` equal parts (an ensemble's members, in order),
/// and in each every encoded target column (`0..width`) is predicted by
/// exactly one net.
fn check_targets(nets: &[FittedNet], width: usize, members: usize) -> Result<(), LearnError> {
    if nets.is_empty() || !nets.len().is_multiple_of(members) {
        return Err(corrupt(format!(
            "{} nets do not make {members} ensemble members",
            nets.len()
        )));
    }
    for member in nets.chunks(nets.len() / members) {
        let mut seen = vec![0usize; width];
        for &t in member.iter().flat_map(|n| &n.targets) {
            *seen
                .get_mut(t)
                .ok_or_else(|| corrupt(format!("target column {t} out of range")))? += 1;
        }
        if !seen.iter().all(|&k| k == 1) {
            return Err(corrupt("each target column must come from exactly one net"));
        }
    }
    Ok(())
}
