//! A search space file (`configs/search/*.toml`): the model settings a
//! search varies, each with its range (linear or log, real or integer)
//! or its list of choices, and how a point of the space becomes a
//! [`TrialConfig`]: a pin model's [`ModelConfig`] or an image model's
//! [`ConvConfig`].
//!
//! For a pin model, a setting is a model key (`epochs`,
//! `anneal_fraction`) or a net key (`learning_rate`,
//! `output_learning_rate`, `beta`, `hidden`, `n_components`) that applies
//! to every net of the model, or to one net when prefixed by its name
//! (`position.beta`, `angle.n_components`, `pose.hidden`). For an image
//! model, a setting is any number of its configuration named by its path
//! (`learning_rate`, `ep.beta`, `epochs`, `batch_size`, `dense.0`,
//! `conv.1.channels`, `weight_decay`): the space file names the fields,
//! nothing here lists them.
use crate::error::{LabError, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use tactrace_convnet::ConvConfig;
use tactrace_learn::{LearnError, ModelConfig, NetConfig};
use tactrace_optim::Domain;

/// What a search lays its settings over and what each trial trains: a
/// pin model's configuration or an image model's (written as either,
/// untagged: a pin search's files are those of before image searches).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum TrialConfig {
    /// A pin model (`pdennn`, `pcadennn`, `disdennn`, `mlp`).
    Pins(ModelConfig),
    /// An image model (`conv-dennn`, `conv-mlp`).
    Image(ConvConfig),
}

impl TrialConfig {
    /// The model kind's name (`pdennn`, `conv-dennn`, ...).
    pub fn kind_name(&self) -> &'static str {
        match self {
            TrialConfig::Pins(c) => c.kind.name(),
            TrialConfig::Image(c) => c.kind.name(),
        }
    }
}

/// The file: a list of `[[param]]` tables.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceFile {
    /// The settings searched, in the order they are listed.
    pub param: Vec<ParamSpec>,
}

/// One setting: either `low`/`high` (with `log`, `integer`) or `choices`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamSpec {
    /// The setting's key (module docs).
    pub name: String,
    /// Lower end of the range (inclusive).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub low: Option<f64>,
    /// Upper end of the range (inclusive).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub high: Option<f64>,
    /// Spaced logarithmically (learning rates, sizes).
    #[serde(default)]
    pub log: bool,
    /// Whole numbers only (sizes, epochs).
    #[serde(default)]
    pub integer: bool,
    /// The values to choose from (unordered), instead of a range.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub choices: Option<Vec<f64>>,
}

/// The keys of one net.
const NET_KEYS: [&str; 5] = [
    "learning_rate",
    "output_learning_rate",
    "beta",
    "hidden",
    "n_components",
];
/// The keys of the whole model.
const MODEL_KEYS: [&str; 2] = ["epochs", "anneal_fraction"];
/// Keys whose values must be whole numbers.
const WHOLE_KEYS: [&str; 3] = ["hidden", "n_components", "epochs"];

fn bad(name: &str, reason: impl std::fmt::Display) -> LabError {
    LabError::Config(format!("search space: `{name}`: {reason}"))
}

impl ParamSpec {
    /// The optimiser's domain of this setting.
    pub fn domain(&self) -> Result<Domain> {
        let name = &self.name;
        let whole = WHOLE_KEYS.contains(&self.key());
        match (&self.choices, self.low, self.high) {
            (Some(c), None, None) => {
                if c.is_empty() || c.iter().any(|v| !v.is_finite()) {
                    return Err(bad(name, "choices must be a non-empty list of numbers"));
                }
                if whole && c.iter().any(|v| v.fract() != 0.0 || *v < 1.0) {
                    return Err(bad(name, "choices must be whole numbers of at least 1"));
                }
                Ok(Domain::Choice { n: c.len() })
            }
            (None, Some(low), Some(high)) => {
                if !(low.is_finite() && high.is_finite() && low <= high) {
                    return Err(bad(name, format!("[{low}, {high}] is not a range")));
                }
                if self.log && low <= 0.0 {
                    return Err(bad(name, "a log range needs low > 0"));
                }
                if whole && !self.integer {
                    return Err(bad(name, "is a whole number: set `integer = true`"));
                }
                if self.integer {
                    if low.fract() != 0.0 || high.fract() != 0.0 || low < 1.0 {
                        return Err(bad(name, "an integer range needs whole ends of at least 1"));
                    }
                    let (low, high, log) = (low as i64, high as i64, self.log);
                    return Ok(Domain::Int { low, high, log });
                }
                let log = self.log;
                Ok(Domain::Float { low, high, log })
            }
            _ => Err(bad(name, "give either `low` and `high`, or `choices`")),
        }
    }

    /// The key without its net prefix.
    fn key(&self) -> &str {
        self.name.rsplit('.').next().unwrap_or(&self.name)
    }

    /// The net named by the prefix, if any.
    fn net(&self) -> Option<&str> {
        self.name.rsplit_once('.').map(|(net, _)| net)
    }

    /// The setting's value for the optimiser's `value` (a choice's index
    /// becomes the choice).
    pub fn value(&self, value: f64) -> f64 {
        match &self.choices {
            Some(c) => c[(value.max(0.0) as usize).min(c.len() - 1)],
            None => value,
        }
    }
}

impl SpaceFile {
    /// The domains, after checking every setting's name and range, and
    /// that the ranges' ends give valid configurations over `base`.
    pub fn domains(&self, base: &TrialConfig) -> Result<Vec<Domain>> {
        if self.param.is_empty() {
            return Err(LabError::Config(
                "search space: no [[param]] to search".into(),
            ));
        }
        let mut seen = std::collections::HashSet::new();
        for p in &self.param {
            if !seen.insert(p.name.as_str()) {
                return Err(bad(&p.name, "listed twice"));
            }
        }
        let domains = self
            .param
            .iter()
            .map(ParamSpec::domain)
            .collect::<Result<Vec<_>>>()?;
        self.corners(base, &domains)?;
        Ok(domains)
    }

    /// The configurations at the ranges' low ends and at their high ends
    /// (the first and the last choice), validated.
    pub fn corners(&self, base: &TrialConfig, domains: &[Domain]) -> Result<Vec<TrialConfig>> {
        [Corner::Low, Corner::High]
            .into_iter()
            .map(|end| {
                let values: Vec<f64> = domains.iter().map(|d| corner(d, end)).collect();
                self.apply(base, &values)
            })
            .collect()
    }

    /// `base` with the optimiser's `values` (one per setting) set,
    /// validated.
    pub fn apply(&self, base: &TrialConfig, values: &[f64]) -> Result<TrialConfig> {
        match base {
            TrialConfig::Pins(base) => {
                let mut cfg = base.clone();
                for (p, &v) in self.param.iter().zip(values) {
                    set(&mut cfg, p, p.value(v))?;
                }
                cfg.validate()?;
                Ok(TrialConfig::Pins(cfg))
            }
            TrialConfig::Image(base) => {
                let mut doc = serde_json::to_value(base).map_err(|e| bad("image model", e))?;
                for (p, &v) in self.param.iter().zip(values) {
                    set_field(&mut doc, p, p.value(v))?;
                }
                let cfg: ConvConfig =
                    serde_json::from_value(doc).map_err(|e| bad("image model", e))?;
                cfg.validate().map_err(LearnError::from)?;
                Ok(TrialConfig::Image(cfg))
            }
        }
    }

    /// `(name, value)` of each setting for the optimiser's `values`.
    pub fn named(&self, values: &[f64]) -> Vec<(String, f64)> {
        self.param
            .iter()
            .zip(values)
            .map(|(p, &v)| (p.name.clone(), p.value(v)))
            .collect()
    }
}

#[derive(Clone, Copy)]
enum Corner {
    Low,
    High,
}

fn corner(d: &Domain, end: Corner) -> f64 {
    match (*d, end) {
        (Domain::Float { low, .. }, Corner::Low) => low,
        (Domain::Float { high, .. }, Corner::High) => high,
        (Domain::Int { low, .. }, Corner::Low) => low as f64,
        (Domain::Int { high, .. }, Corner::High) => high as f64,
        (Domain::Choice { .. }, Corner::Low) => 0.0,
        (Domain::Choice { n }, Corner::High) => n as f64 - 1.0,
    }
}

/// Set the number at the path `p.name` (`ep.beta`, `dense.0`) of an
/// image model's configuration `doc` to `v`: a whole number where the
/// configuration holds one (the space must say `integer = true`, or list
/// whole choices).
fn set_field(doc: &mut Value, p: &ParamSpec, v: f64) -> Result<()> {
    let mut at = doc;
    for part in p.name.split('.') {
        let next = match at {
            Value::Object(m) => m.get_mut(part),
            Value::Array(a) => part.parse::<usize>().ok().and_then(|i| a.get_mut(i)),
            _ => None,
        };
        at = next.ok_or_else(|| {
            bad(
                &p.name,
                "an image model has no such setting (e.g. learning_rate, ep.beta, epochs, \
                 batch_size, dense.0, conv.0.channels, weight_decay, final_lr_fraction)",
            )
        })?;
    }
    let whole = p.integer
        || p.choices
            .as_ref()
            .is_some_and(|c| c.iter().all(|x| x.fract() == 0.0 && *x >= 0.0));
    *at = match at {
        Value::Number(n) if n.is_u64() && !whole => {
            return Err(bad(&p.name, "is a whole number: set `integer = true`"))
        }
        Value::Number(n) if n.is_u64() => Value::from(v as u64),
        Value::Number(_) => Value::from(v),
        _ => {
            return Err(bad(
                &p.name,
                "is not a number of the image model's settings",
            ))
        }
    };
    Ok(())
}

/// Set one setting on `cfg`.
fn set(cfg: &mut ModelConfig, p: &ParamSpec, v: f64) -> Result<()> {
    let key = p.key();
    if MODEL_KEYS.contains(&key) {
        if p.net().is_some() {
            return Err(bad(
                &p.name,
                "is a setting of the whole model: no net prefix",
            ));
        }
        match key {
            "epochs" => cfg.epochs = v as usize,
            _ => cfg.anneal_fraction = v,
        }
        return Ok(());
    }
    if !NET_KEYS.contains(&key) {
        let known = [&MODEL_KEYS[..], &NET_KEYS[..]].concat().join(", ");
        return Err(bad(&p.name, format!("unknown setting (known: {known})")));
    }
    let nets: Vec<&mut NetConfig> = match p.net() {
        None => [&mut cfg.pose, &mut cfg.position, &mut cfg.angle]
            .into_iter()
            .flatten()
            .collect(),
        Some("pose") => cfg.pose.as_mut().into_iter().collect(),
        Some("position") => cfg.position.as_mut().into_iter().collect(),
        Some("angle") => cfg.angle.as_mut().into_iter().collect(),
        Some(other) => {
            return Err(bad(
                &p.name,
                format!("no net `{other}` (pose, position, angle)"),
            ))
        }
    };
    if nets.is_empty() {
        return Err(bad(
            &p.name,
            format!("a {} has no such net", cfg.kind.name()),
        ));
    }
    for net in nets {
        match key {
            "learning_rate" => net.learning_rate = v,
            "output_learning_rate" => net.output_learning_rate = Some(v),
            "beta" => net.beta = v,
            "hidden" => net.hidden = vec![v as usize],
            _ if net.n_components.is_none() => {
                return Err(bad(&p.name, "this net takes no principal components"))
            }
            _ => net.n_components = Some(v as usize),
        }
    }
    Ok(())
}
