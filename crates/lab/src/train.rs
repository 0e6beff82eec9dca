//! Training and validation of pose models (report ch. 4.2-4.3).
use crate::error::{LabError, Result};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tactrace_learn::{
    hyperparameter_search, target_mae, ModelConfig, ModelKind, ModelTarget, PoseModel, Preset,
    SearchSpace, TrainingHistory, Trial, Unit,
};
use tactrace_store::tap_split::SplitUnit;
use tactrace_store::{stage_model, HeldOut, StoredModel, TapData, TrainingRecord};

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
    train_with_validation(cfg, data, None, progress)
}

/// The targets of `data`'s columns ([`tactrace_store::DatasetMeta::model_targets`]).
pub fn data_targets(data: &TapData) -> Result<Vec<ModelTarget>> {
    data.meta
        .model_targets()
        .map_err(|reason| LabError::Learn(tactrace_learn::LearnError::Targets { reason }))
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
    let outputs = data_targets(data)?;
    if let Some(v) = val {
        check_same_targets(&outputs, &data_targets(v)?)?;
    }
    let mut cb = |r: &tactrace_learn::EpochReport| progress(r.epoch + 1);
    Ok(PoseModel::fit_targets_on_pins(
        cfg,
        &outputs,
        &ds,
        vs.as_ref(),
        Some(&data.meta.reference_pins),
        &mut cb,
    )?)
}

/// Split `data` into a training part and a held-out part of `fraction`
/// of the samples (seeded shuffle, whole taps where a tap repeats: see
/// [`holdout_split`]); both parts must be non-empty.
pub fn holdout(data: &TapData, fraction: f64, seed: u64) -> Result<(TapData, TapData)> {
    let (tr, va) = holdout_rows(data, fraction, seed)?;
    Ok((data.subset(&tr), data.subset(&va)))
}

/// The row indices of [`holdout`]'s two parts (training, held out).
pub fn holdout_rows(data: &TapData, fraction: f64, seed: u64) -> Result<(Vec<usize>, Vec<usize>)> {
    let (tr, va, _) = holdout_split(data, fraction, seed, None)?;
    Ok((tr, va))
}

/// The rows of the two parts (training, held out) and how they were
/// dealt. `unit`: `None` deals whole taps where the dataset repeats one
/// (a twin's renders, repeated calibration taps; see
/// [`tactrace_store::tap_split`]) and rows otherwise; `Some(Row)` deals
/// rows always (the split of a model folder written before taps were kept
/// together).
pub fn holdout_split(
    data: &TapData,
    fraction: f64,
    seed: u64,
    unit: Option<SplitUnit>,
) -> Result<(Vec<usize>, Vec<usize>, SplitUnit)> {
    if !(fraction > 0.0 && fraction < 1.0) {
        return Err(LabError::Config(format!(
            "validation fraction {fraction} must be strictly between 0 and 1"
        )));
    }
    let (tr, va, unit) = match unit {
        Some(SplitUnit::Row) => {
            let (tr, va) = data.split_rows(1.0 - fraction, seed);
            (tr, va, SplitUnit::Row)
        }
        _ => tactrace_store::tap_split::split_taps(data, 1.0 - fraction, seed),
    };
    if tr.is_empty() || va.is_empty() {
        return Err(LabError::Config(format!(
            "{} samples are too few to hold out a fraction {fraction}",
            data.len()
        )));
    }
    Ok((tr, va, unit))
}

/// The data a model is fitted on, the part held out, and the record of
/// both the model folder keeps ([`TrainingRecord`]).
pub struct TrainingSplit {
    /// The rows fitted on.
    pub train: TapData,
    /// The rows held out (`Some` with a fraction).
    pub val: Option<TapData>,
    /// Which rows of which dataset `train` and `val` are.
    pub record: TrainingRecord,
}

/// Fit on every row of `data` (read from `path`), or with `held_out =
/// Some((fraction, seed))` on the rows [`holdout`] keeps, holding out the
/// rest. Refused when no pin moves in any row
/// ([`crate::import_checks::still_pins`]): no model learns from that.
pub fn training_split(
    data: &TapData,
    path: Option<&Path>,
    held_out: Option<(f64, u64)>,
) -> Result<TrainingSplit> {
    if let Some(still) = crate::import_checks::still_pins(&data.inputs, data.len()) {
        return Err(LabError::StillPins {
            what: path.map_or("the training rows".into(), |p| p.display().to_string()),
            reason: still.says(data.len()),
        });
    }
    let Some((val_fraction, split_seed)) = held_out else {
        return Ok(TrainingSplit {
            train: data.clone(),
            val: None,
            record: TrainingRecord::all_rows(data, path),
        });
    };
    let (tr, va, unit) = holdout_split(data, val_fraction, split_seed, None)?;
    let (train, val) = (data.subset(&tr), data.subset(&va));
    let split = HeldOut {
        val_fraction,
        split_seed,
        rows: va,
        unit,
    };
    Ok(TrainingSplit {
        train,
        val: Some(val),
        record: TrainingRecord::new(data, path, tr, Some(split)),
    })
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
    let outputs = data_targets(data)?;
    let (inner, val) = holdout(data, fraction, seed)?;
    let (inner, val) = (inner.to_learn()?, val.to_learn()?);
    Ok(hyperparameter_search(
        base, space, &outputs, &inner, &val, progress,
    )?)
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

/// The trials as CSV (best first): the settings, then the validation
/// error of every target of `outputs` (`mae_NAME_UNIT`, circular ones
/// wrapped) and the score.
pub fn trials_csv(trials: &[Trial], outputs: &[ModelTarget]) -> String {
    let mut csv = tactrace_store::CsvText::new();
    let mut header: Vec<String> = [
        "rank",
        "learning_rate",
        "output_learning_rate",
        "beta",
        "hidden",
        "n_components",
    ]
    .map(String::from)
    .to_vec();
    header.extend(
        outputs
            .iter()
            .map(|t| format!("mae_{}_{}", t.name, t.unit.as_str())),
    );
    header.push("score".into());
    csv.row(header);
    for (k, t) in trials.iter().enumerate() {
        let c = &t.config;
        if let Some(net) = c.pose.as_ref().or(c.angle.as_ref()) {
            let hidden: Vec<String> = net.hidden.iter().map(|h| h.to_string()).collect();
            let mut row = vec![
                (k + 1).to_string(),
                net.learning_rate.to_string(),
                net.output_learning_rate
                    .unwrap_or(net.learning_rate)
                    .to_string(),
                net.beta.to_string(),
                hidden.join(" "),
                net.n_components.map(|k| k.to_string()).unwrap_or_default(),
            ];
            row.extend(t.val_mae.iter().map(f64::to_string));
            row.push(t.score.to_string());
            csv.row(row);
        }
    }
    csv.into_string()
}

/// A trial's validation errors as one line: `NAME MAE UNIT` for every
/// target of `outputs`, comma separated.
pub fn trial_errors(t: &Trial, outputs: &[ModelTarget]) -> String {
    outputs
        .iter()
        .zip(&t.val_mae)
        .map(|(o, m)| format!("{} {m:.3} {}", o.name, o.unit.as_str()))
        .collect::<Vec<_>>()
        .join(", ")
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

/// One target's score: its mean absolute error (wrapped when circular)
/// in its unit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TargetScore {
    pub mae: f64,
    pub unit: Unit,
    pub circular: bool,
}

/// Mean absolute errors of a model on a dataset, with the predictions.
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    /// The mean MAE of the targets in mm (the edge task's position); null
    /// in JSON (NaN) when no target is in mm.
    pub position_mae_mm: f64,
    /// The mean MAE of the targets in deg, circular ones wrapped (the edge
    /// task's angle); null in JSON (NaN) when no target is in deg.
    pub angle_mae_deg: f64,
    /// Every target's MAE by its label column.
    pub per_target: BTreeMap<String, TargetScore>,
    pub samples: usize,
    /// How many of the samples the model was trained on (by row hash);
    /// `None` (null) when the model folder does not record it.
    pub rows_seen_in_training: Option<usize>,
    /// Whether each prediction was the mean over the tap's turned views
    /// (`--views`, else what the model's file says); absent for a model
    /// fitted without rotations.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub turned_views: Option<bool>,
    /// The edge pose predicted for each sample (empty unless the model is
    /// an edge model).
    #[serde(skip)]
    pub predictions: Vec<[f64; 2]>,
    /// The edge pose of each sample (as `predictions`).
    #[serde(skip)]
    pub truth: Vec<[f64; 2]>,
    /// The targets, in the model's order (named by the data's columns).
    #[serde(skip)]
    pub targets: Vec<ModelTarget>,
    /// Every target predicted for each sample.
    #[serde(skip)]
    pub target_predictions: Vec<Vec<f64>>,
    /// Every target of each sample.
    #[serde(skip)]
    pub target_truth: Vec<Vec<f64>>,
}

impl Validation {
    /// Whether its outputs may call the targets "position" and "angle":
    /// an edge model whose targets are the edge task's own `r` and
    /// `theta` ([`tactrace_learn::names_the_edge`]). Any other model, a
    /// surface's depth (mm) and angle (deg) included, is shown by its
    /// targets' names.
    pub fn shows_edge_pose(&self) -> bool {
        !self.predictions.is_empty() && tactrace_learn::names_the_edge(&self.targets)
    }

    /// Every target's MAE with its unit, in the model's order: "r 0.120
    /// mm, theta 1.010 deg".
    pub fn per_target_line(&self) -> String {
        let parts: Vec<String> = self
            .targets
            .iter()
            .map(|t| {
                let s = &self.per_target[&t.name];
                format!("{} {:.3} {}", t.name, s.mae, s.unit.as_str())
            })
            .collect();
        parts.join(", ")
    }

    /// The warning when some of the samples were training samples.
    pub fn seen_warning(&self) -> Option<String> {
        let seen = self.rows_seen_in_training.filter(|&k| k > 0)?;
        Some(format!(
            "{seen} of the {} samples are rows the model was trained on: these are \
             not held-out scores (score held-out rows: a dataset the model never saw, or \
             --val-fraction/--split-seed as given to `train`)",
            self.samples
        ))
    }
}

/// Save a trained model (its network, the reference pins of its training
/// data and what it was trained on), its history, `extra` text files and
/// the loss/energy figure (Fig. 4.5) into `dir`, which appears only when
/// complete.
pub fn save_model(
    dir: &Path,
    model: &StoredModel,
    history: &TrainingHistory,
    force: bool,
    extra: &[(&str, String)],
) -> Result<PathBuf> {
    let stage = stage_model(dir, model, history, force, extra)?;
    tactrace_report::figures::training_curves(&stage.path().join("loss_energy"), history)?;
    Ok(stage.commit()?)
}

/// Validate `model` on `data` (named `what`), refused when the data's pins
/// are ordered otherwise than the model's training data; counts the
/// samples the model was trained on when its folder records them.
pub fn validate(model: &StoredModel, data: &TapData, what: &Path) -> Result<Validation> {
    let net = model.for_data(data, what)?;
    let mut v = validate_net(net, data)?;
    v.rows_seen_in_training = model.training().map(|t| t.rows_seen(data));
    Ok(v)
}

/// Validate `model` on exactly the rows of `data` (named `what`) that
/// `train --val-fraction fraction --split-seed seed` held out. Refused
/// when the model's folder records another dataset (content hash), no
/// held-out part or another split; a folder without the record is scored
/// on the split recomputed (the result's `rows_seen_in_training` is then
/// `None`).
pub fn validate_held_out(
    model: &StoredModel,
    data: &TapData,
    what: &Path,
    fraction: f64,
    seed: u64,
) -> Result<Validation> {
    let rows = held_out_rows(model.training(), data, what, (fraction, seed))?;
    validate(model, &data.subset(&rows), what)
}

/// The rows of `data` (named `what`) that `train --val-fraction fraction
/// --split-seed seed` held out, checked against the model's `record`
/// when it has one (see [`validate_held_out`]).
pub(crate) fn held_out_rows(
    record: Option<&TrainingRecord>,
    data: &TapData,
    what: &Path,
    (fraction, seed): (f64, u64),
) -> Result<Vec<usize>> {
    let unit = record.and_then(|r| r.split.as_ref()).map(|s| s.unit);
    let (_, rows, _) = holdout_split(data, fraction, seed, unit)?;
    if let Some(record) = record {
        check_held_out(record, data, what, (fraction, seed), &rows)?;
    }
    Ok(rows)
}

/// That `record` held out `rows` of `data` with `(fraction, seed)`.
fn check_held_out(
    record: &TrainingRecord,
    data: &TapData,
    what: &Path,
    (fraction, seed): (f64, u64),
    rows: &[usize],
) -> Result<()> {
    let trained = &record.dataset;
    let refuse = |reason: String| {
        Err(LabError::Format {
            path: what.to_path_buf(),
            reason,
        })
    };
    let hash = tactrace_store::training_record::dataset_hash(data);
    if hash != trained.sha256 && !record.datasets.is_empty() {
        return refuse(format!(
            "the model was trained on {} datasets together, and --val-fraction held out rows \
             of all of them joined: its held-out rows cannot be scored on one dataset \
             (validate on a dataset it never saw)",
            record.datasets.len()
        ));
    }
    if hash != trained.sha256 {
        let short = |h: &str| format!("{}...", &h[..h.len().min(23)]);
        return refuse(format!(
            "not the dataset the model was trained on ({} rows, {}; the model's: {} rows, \
             {}{}): --val-fraction scores the held-out rows of the model's own training set",
            data.len(),
            short(&hash),
            trained.rows,
            short(&trained.sha256),
            trained
                .path
                .as_ref()
                .map(|p| format!(", read from {p}"))
                .unwrap_or_default()
        ));
    }
    let Some(split) = &record.split else {
        return refuse(
            "the model was trained on every row of this dataset (no --val-fraction): it has \
             no held-out rows here; validate on a dataset it never saw"
                .into(),
        );
    };
    if split.val_fraction != fraction || split.split_seed != seed {
        return refuse(format!(
            "the model held out --val-fraction {} --split-seed {}, not --val-fraction \
             {fraction} --split-seed {seed}: give the model's split",
            split.val_fraction, split.split_seed
        ));
    }
    if split.rows != rows {
        return refuse(
            "the split drawn now differs from the one the model recorded (another version of \
             tactrace's shuffle?); its held-out rows cannot be scored"
                .into(),
        );
    }
    Ok(())
}

/// Error unless `data`'s targets are the model's: as many, in the same
/// units, in order.
pub(crate) fn check_same_targets(model: &[ModelTarget], data: &[ModelTarget]) -> Result<()> {
    let units = |t: &[ModelTarget]| t.iter().map(|t| t.unit).collect::<Vec<_>>();
    if units(model) == units(data) {
        return Ok(());
    }
    let list = |t: &[ModelTarget]| {
        t.iter()
            .map(|t| format!("{} ({})", t.name, t.unit.as_str()))
            .collect::<Vec<_>>()
            .join(", ")
    };
    Err(LabError::Learn(tactrace_learn::LearnError::Targets {
        reason: format!(
            "the model predicts {}, the dataset's targets are {}",
            list(model),
            list(data)
        ),
    }))
}

/// A model's `outputs` named by `data`'s columns, refused when the data's
/// targets are not the model's.
pub(crate) fn named_targets(outputs: &[ModelTarget], data: &TapData) -> Result<Vec<ModelTarget>> {
    let named = data_targets(data)?;
    check_same_targets(outputs, &named)?;
    Ok(outputs
        .iter()
        .zip(&named)
        .map(|(m, d)| ModelTarget {
            name: d.name.clone(),
            ..m.clone()
        })
        .collect())
}

/// The mean of the MAEs of the targets in `unit` (NaN when none is).
fn unit_mean(targets: &[ModelTarget], mae: &[f64], unit: Unit) -> f64 {
    let of: Vec<f64> = targets
        .iter()
        .zip(mae)
        .filter(|(t, _)| t.unit == unit)
        .map(|(_, &m)| m)
        .collect();
    of.iter().sum::<f64>() / of.len() as f64
}

/// Validate a network just trained on data ordered like `data` (what it
/// was trained on is not known here: `rows_seen_in_training` is `None`).
/// Every target is scored (circular ones wrapped) and named by the data's
/// column; the edge pose is kept for an edge model's figures.
pub fn validate_net(model: &PoseModel, data: &TapData) -> Result<Validation> {
    let ds = data.to_learn()?;
    check_dim(model.input_dim(), data.dim())?;
    let targets = named_targets(model.outputs(), data)?;
    let predicted = model.predict_targets_batch(&ds)?;
    let mut v = score_predictions(targets, data, predicted, model.edge_roles().ok())?;
    v.turned_views = model.views_at_prediction();
    Ok(v)
}

/// The validation of `predicted` (one row of every target a sample of
/// `data`, `targets` named by the data's columns): every prediction a
/// number, every target scored (circular ones wrapped); the edge pose
/// kept when `edge` gives its targets' indices.
pub(crate) fn score_predictions(
    targets: Vec<ModelTarget>,
    data: &TapData,
    predicted: Vec<Vec<f64>>,
    edge: Option<[usize; 2]>,
) -> Result<Validation> {
    for (k, p) in predicted.iter().enumerate() {
        let values: Vec<(&str, f64)> = targets
            .iter()
            .map(|t| t.name.as_str())
            .zip(p.iter().copied())
            .collect();
        crate::numbers::require_finite(
            &format!("the model's prediction for row {k} of the dataset"),
            &values,
            "the row's inputs lie far outside the training data's, or the model is \
             degenerate (trained on too few samples?)",
        )?;
    }
    let truth: Vec<Vec<f64>> = (0..data.len())
        .map(|i| data.target_row(i).iter().map(|&v| f64::from(v)).collect())
        .collect();
    let mae = target_mae(&targets, &predicted, &truth);
    let maes: Vec<(String, f64)> = targets
        .iter()
        .zip(&mae)
        .map(|(t, &m)| (format!("the {} MAE", t.name), m))
        .collect();
    let refs: Vec<(&str, f64)> = maes.iter().map(|(n, m)| (n.as_str(), *m)).collect();
    crate::numbers::require_finite("the validation", &refs, "")?;
    let (predictions, edge_truth) = match edge {
        Some([r, theta]) => (
            predicted.iter().map(|p| [p[r], p[theta]]).collect(),
            truth.iter().map(|t| [t[r], t[theta]]).collect(),
        ),
        None => (Vec::new(), Vec::new()),
    };
    let per_target = targets
        .iter()
        .zip(&mae)
        .map(|(t, &m)| {
            let score = TargetScore {
                mae: m,
                unit: t.unit,
                circular: t.circular,
            };
            (t.name.clone(), score)
        })
        .collect();
    Ok(Validation {
        position_mae_mm: unit_mean(&targets, &mae, Unit::Mm),
        angle_mae_deg: unit_mean(&targets, &mae, Unit::Deg),
        per_target,
        samples: data.len(),
        rows_seen_in_training: None,
        turned_views: None,
        predictions,
        truth: edge_truth,
        targets,
        target_predictions: predicted,
        target_truth: truth,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_data::edge_data;

    fn data(n: usize) -> TapData {
        let rows = (0..2 * n).map(|v| v as f32);
        edge_data(rows.clone().collect(), rows.collect(), &[[0.0, 0.0]])
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
