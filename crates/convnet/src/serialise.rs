//! A model as a JSON string (format, version, kind and configuration,
//! seed, input size, outputs) plus safetensors bytes: `W1, b1, W2, ...`
//! (each `W(l)` as `cout x cin x kh x kw`, a dense layer's window covering
//! its whole input; f32; an ensemble's other networks as `net2.W1`, ...) and the scalings (`input.mean`, `input.std`,
//! `input.mean_frame` when used, `input.pins.mean` and `input.pins.std`
//! for a pins-and-pixels model, whose first dense layer's `W` is stored
//! `cout x fan_in` with the pins' columns last, `target.mean`, `target.std`; f64, so a
//! reloaded model predicts bit for bit as the saved one). Pure: the
//! caller writes the files, as with the pin models' `model.json` and
//! `model.safetensors`.
use crate::config::ConvConfig;
use crate::error::ConvError;
use crate::layout::{LayerShape, Layout};
use crate::model::ConvModel;
use crate::model_file::{
    read_f32, read_f64, read_header, read_tensors, write_tensors, ModelFileError, Tensor,
};
use crate::network::Network;
use crate::params::Parameters;
use crate::scaling::{InputScaling, TargetScaling};
use safetensors::SafeTensors;
use serde::{Deserialize, Serialize};

/// Identifies these model files.
const FORMAT: &str = "tactrace-conv-model";
/// Bumped on any incompatible change.
pub const CONV_FORMAT_VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    format: String,
    version: u32,
    config: ConvConfig,
    seed: u64,
    input_height: usize,
    input_width: usize,
    outputs: usize,
    /// Pin values a frame (a pins-and-pixels model; 0, left out, else).
    #[serde(default, skip_serializing_if = "is_zero")]
    pins: usize,
}

fn is_zero(v: &usize) -> bool {
    *v == 0
}

/// How a layer's weights are stored: `cout x cin x kh x kw`, or `cout x
/// fan_in` when side inputs (pins) follow the window.
fn weight_shape(s: &LayerShape) -> Vec<usize> {
    match s.side_inputs {
        0 => vec![s.cout, s.cin, s.kh, s.kw],
        _ => vec![s.cout, s.fan_in()],
    }
}

fn corrupt(reason: impl ToString) -> ConvError {
    ConvError::Corrupt {
        reason: reason.to_string(),
    }
}

impl From<ModelFileError> for ConvError {
    fn from(e: ModelFileError) -> Self {
        corrupt(e.reason())
    }
}

impl ConvModel {
    /// Serialise: `(json, safetensors weights)`.
    pub fn to_bytes(&self) -> Result<(String, Vec<u8>), ConvError> {
        let (input_height, input_width) = self.input_size();
        let file = ModelFile {
            format: FORMAT.into(),
            version: CONV_FORMAT_VERSION,
            config: self.config.clone(),
            seed: self.seed,
            input_height,
            input_width,
            outputs: self.outputs(),
            pins: self.pin_inputs(),
        };
        let json = serde_json::to_string_pretty(&file).map_err(corrupt)?;
        let mut tensors = Vec::new();
        for (k, net) in self.nets.iter().enumerate() {
            let (p, prefix) = (&net.params, member_prefix(k));
            for (l, s) in net.layout.layers().iter().enumerate() {
                let (w, b) = (format!("{prefix}W{}", l + 1), format!("{prefix}b{}", l + 1));
                tensors.push(Tensor::f32(w, weight_shape(s), &p.weights[l]));
                tensors.push(Tensor::f32(b, vec![s.cout], &p.biases[l]));
            }
        }
        let (i, t) = (&self.input, &self.targets);
        tensors.push(Tensor::f64("input.mean", vec![1], &[i.mean]));
        tensors.push(Tensor::f64("input.std", vec![1], &[i.std]));
        if !i.mean_frame.is_empty() {
            let frame: Vec<f64> = i.mean_frame.iter().map(|&v| v as f64).collect();
            let shape = vec![input_height, input_width];
            tensors.push(Tensor::f64("input.mean_frame", shape, &frame));
        }
        if let Some(pins) = &i.pins {
            tensors.push(Tensor::f64("input.pins.mean", vec![pins.dim()], &pins.mean));
            tensors.push(Tensor::f64("input.pins.std", vec![pins.dim()], &pins.std));
        }
        tensors.push(Tensor::f64("target.mean", vec![t.dim()], &t.mean));
        tensors.push(Tensor::f64("target.std", vec![t.dim()], &t.std));
        Ok((json, write_tensors(&tensors)?))
    }

    /// Rebuild a model from [`Self::to_bytes`] output. Another format
    /// version, truncated, inconsistent or non-finite data are errors.
    pub fn from_bytes(json: &str, safetensors: &[u8]) -> Result<Self, ConvError> {
        let (value, version) = read_header(json, FORMAT)?;
        if version != CONV_FORMAT_VERSION as u64 {
            return Err(ConvError::Version {
                found: version.min(u32::MAX as u64) as u32,
                supported: CONV_FORMAT_VERSION,
            });
        }
        let file: ModelFile =
            serde_json::from_value(value).map_err(|e| corrupt(format!("model json: {e}")))?;
        file.config.validate()?;
        let c = &file.config;
        let size = (file.input_height, file.input_width);
        let layout = crate::hybrid::layout_for(c, size, file.outputs, file.pins)?;
        let tensors = read_tensors(safetensors)?;
        let (input, targets) = read_scalings(&tensors, &file)?;
        crate::hybrid::check_base(&input, &targets)?;
        let nets = (0..c.members)
            .map(|k| read_network(&tensors, &layout, c, k))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(ConvModel {
            config: file.config,
            seed: file.seed,
            nets,
            input,
            targets,
        })
    }
}

/// The tensor names' prefix of network `k` of a model: none for the
/// first (a one-network file is as before ensembles), `net2.`, `net3.`,
/// ... for the others.
fn member_prefix(k: usize) -> String {
    match k {
        0 => String::new(),
        k => format!("net{}.", k + 1),
    }
}

/// Network `k` of a model of `layout` and `config` from its tensors.
fn read_network(
    tensors: &SafeTensors,
    layout: &Layout,
    config: &ConvConfig,
    k: usize,
) -> Result<Network, ConvError> {
    let prefix = member_prefix(k);
    let mut params = Parameters::zeros(layout);
    for (l, s) in layout.layers().iter().enumerate() {
        let w_shape = weight_shape(s);
        params.weights[l] = read_f32(tensors, &format!("{prefix}W{}", l + 1), &w_shape)?;
        params.biases[l] = read_f32(tensors, &format!("{prefix}b{}", l + 1), &[s.cout])?;
    }
    if !params.is_finite() {
        return Err(corrupt("non-finite weights"));
    }
    Network::from_parts(layout.clone(), config.activation, params)
}

/// The input and target scalings, checked for usable numbers.
fn read_scalings(
    tensors: &SafeTensors,
    file: &ModelFile,
) -> Result<(InputScaling, TargetScaling), ConvError> {
    let (h, w, k) = (file.input_height, file.input_width, file.outputs);
    let mean_frame = if tensors.names().contains(&"input.mean_frame") {
        read_f64(tensors, "input.mean_frame", &[h, w])?
            .into_iter()
            .map(|v| v as f32)
            .collect()
    } else {
        Vec::new()
    };
    let input = InputScaling {
        mean: read_f64(tensors, "input.mean", &[1])?[0],
        std: read_f64(tensors, "input.std", &[1])?[0],
        mean_frame,
        pins: match file.pins {
            0 => None,
            p => Some(TargetScaling {
                mean: read_f64(tensors, "input.pins.mean", &[p])?,
                std: read_f64(tensors, "input.pins.std", &[p])?,
            }),
        },
        base_skip: file.config.input.reads_base(),
    };
    let targets = TargetScaling {
        mean: read_f64(tensors, "target.mean", &[k])?,
        std: read_f64(tensors, "target.std", &[k])?,
    };
    if !input.is_valid(h * w) || !targets.is_valid() {
        return Err(corrupt("scalings are not usable numbers"));
    }
    Ok((input, targets))
}
