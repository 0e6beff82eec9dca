//! `tactrace search`: Bayesian optimisation (TPE, `tactrace_optim::Tpe`)
//! of a pin or image model's settings. Each trial trains on the fit part
//! of the training data and is scored on every target of an inner
//! validation part of the same data (a seeded split, recorded; nothing
//! given for scoring is read).
//! Trials run in batches through an [`Executor`]; trial `k` depends only
//! on the seed, `k` and the trials finished before its batch, so a search
//! resumed from its trials file gives the trials an uninterrupted one
//! gives.
//!
//! The output folder is built in `<out>.partial` (the trials appended one
//! whole line at a time) and renamed into place at the end: `config.toml`
//! (the settings, seed and version), `trials.jsonl`, `trials.csv`,
//! `best.toml` (a `train --config` file) and `convergence.{png,svg}`.
mod files;
mod space;

pub use files::{describe_mae, TrialRecord};
pub use space::{ParamSpec, SpaceFile, TrialConfig};

use crate::error::{LabError, Result};
use crate::train::holdout_rows;
use crate::train_image::train_image;
use files::SearchFolder;
use serde::{Deserialize, Serialize};
use std::path::Path;
use tactrace_convnet::{ConvConfig, Frames};
use tactrace_learn::{
    target_mae, Dataset, LearnError, ModelConfig, ModelTarget, PoseModel, TargetScale,
};
use tactrace_optim::{Evaluation, Executor, Observation, Tpe, TpeConfig};
use tactrace_store::{ImageFrames, TapData, TrainingRecord};

/// Everything a search was asked (`config.toml`); a resumed search must
/// be asked the same.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchSettings {
    /// Trials in all (a resumed search may raise it).
    pub trials: usize,
    /// Seed of the TPE's draws and of the inner split.
    pub seed: u64,
    /// Fraction of the training data held out as the inner validation part
    /// (`train --val-fraction F --split-seed SEED` holds out the same rows).
    pub val_fraction: f64,
    /// Trials evaluated together (each batch's suggestions see the trials
    /// before it).
    pub batch: usize,
    /// Random trials before the TPE's model is used.
    pub startup: usize,
    /// The training data's content hash and rows.
    pub data_sha256: String,
    pub data_rows: usize,
    /// The configuration each trial's settings are laid over (a pin or
    /// an image model's).
    pub base: TrialConfig,
    /// The settings searched.
    pub space: SpaceFile,
}

impl SearchSettings {
    /// The TPE over `space`, checked against `base`.
    fn tpe(&self) -> Result<Tpe> {
        let domains = self.space.domains(&self.base)?;
        let config = TpeConfig {
            seed: self.seed,
            startup: self.startup,
            ..TpeConfig::default()
        };
        Tpe::new(domains, config).map_err(|e| LabError::Config(e.to_string()))
    }
}

/// The content hash and size of `data` (as `training.json` records them).
pub fn data_id(data: &TapData) -> (String, usize) {
    let id = TrainingRecord::all_rows(data, None).dataset;
    (id.sha256, id.rows)
}

/// What one trial gave: the inner validation mean absolute error of
/// every target of the data (in its unit, circular angles wrapped) and
/// the score (`sum MAE_k / spread_k`, the fit part's target spreads,
/// circular ones wrapped; lower is better: [`tactrace_learn::TargetScale`]). A trial that failed scores
/// +inf (written `null` in JSON, read back as +inf): a training that
/// diverged (`failure` empty) or another failure (`failure` says why).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialScore {
    #[serde(deserialize_with = "null_is_infinite::many")]
    pub val_mae: Vec<f64>,
    #[serde(deserialize_with = "null_is_infinite::one")]
    pub score: f64,
    /// Why the training failed, other than by diverging.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

impl TrialScore {
    /// A failed trial: diverged when `failure` is `None`.
    fn failed(targets: usize, failure: Option<String>) -> Self {
        TrialScore {
            val_mae: vec![f64::INFINITY; targets],
            score: f64::INFINITY,
            failure,
        }
    }

    /// `ok`, `diverged` or `failed: REASON` (the table's status column).
    pub fn status(&self) -> String {
        match (&self.failure, self.score.is_finite()) {
            (Some(reason), _) => format!("failed: {reason}"),
            (None, true) => "ok".into(),
            (None, false) => "diverged".into(),
        }
    }
}

/// JSON has no infinity: serde_json writes it `null`; read `null` back as
/// +inf (a failed trial's score).
mod null_is_infinite {
    use serde::{Deserialize, Deserializer};

    pub fn one<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }

    pub fn many<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let v = Vec::<Option<f64>>::deserialize(d)?;
        Ok(v.into_iter().map(|x| x.unwrap_or(f64::INFINITY)).collect())
    }
}

/// One trial as an evaluation: train a pose model of the data's targets
/// on the fit part, score it on the inner validation part. Pure: the
/// model's seed is in its configuration.
pub struct PoseTrial {
    fit: Dataset,
    val: Dataset,
    /// The data's targets (names, units, circular flags), in order.
    targets: Vec<ModelTarget>,
    /// Each target's spread over the fit part (circular ones wrapped).
    scale: TargetScale,
    /// The validation part's targets, a row a sample.
    truth: Vec<Vec<f64>>,
    /// The parts' frames, for a search of an image model.
    images: Option<ImageParts>,
    /// Where a remote worker finds the same parts, if known.
    context: Option<SearchContext>,
}

/// An image model's trial data: the fit part's rows and frames, the
/// validation part's frames.
struct ImageParts {
    fit: TapData,
    fit_frames: ImageFrames,
    val_frames: ImageFrames,
}

/// The seed of every image model a search trains (`train --model
/// conv-dennn` without `--seed` uses it too, so `best.toml` trains the
/// best trial's model again).
const IMAGE_SEED: u64 = 0;

/// What a remote worker rebuilds a [`PoseTrial`] from: the training
/// dataset's folder (which it must see: a shared file system), its
/// content hash, and the inner split.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchContext {
    pub train: std::path::PathBuf,
    pub data_sha256: String,
    pub val_fraction: f64,
    pub seed: u64,
    /// A search of an image model: the dataset's frames are read too.
    #[serde(default)]
    pub images: bool,
}

impl PoseTrial {
    /// The evaluation of a model of `targets` over the fit and validation
    /// parts.
    pub fn new(fit: Dataset, val: Dataset, targets: Vec<ModelTarget>) -> Result<Self> {
        let scale = TargetScale::spreads(&targets, &fit)?;
        let truth = (0..val.n)
            .map(|i| val.y_row(i).iter().map(|&v| f64::from(v)).collect())
            .collect();
        Ok(PoseTrial {
            scale,
            fit,
            val,
            targets,
            truth,
            images: None,
            context: None,
        })
    }

    /// The evaluation over the inner split of `data` (fit part, validation
    /// part), which a remote worker rebuilds from `context`.
    fn split(data: &TapData, context: SearchContext) -> Result<(Self, TapData, usize)> {
        let (fit_rows, val_rows) = holdout_rows(data, context.val_fraction, context.seed)?;
        let val = data.subset(&val_rows).to_learn()?;
        let fit_data = data.subset(&fit_rows);
        let targets = crate::train::data_targets(data)?;
        let mut trial = PoseTrial::new(fit_data.to_learn()?, val, targets)?;
        if context.images {
            let frames = crate::train_image::data_frames(data, &context.train)?;
            trial.images = Some(ImageParts {
                fit: fit_data.clone(),
                fit_frames: frames.subset(&fit_rows),
                val_frames: frames.subset(&val_rows),
            });
        }
        trial.context = Some(context);
        Ok((trial, fit_data, val_rows.len()))
    }

    /// The evaluation a remote worker rebuilds from [`SearchContext`] JSON
    /// (the dataset read again, and refused if its content differs).
    pub fn from_context(context: &str) -> Result<Self> {
        let context: SearchContext = crate::remote::parse_context(Self::NAME, context)?;
        let data = tactrace_store::read_dataset(&context.train)?;
        if data_id(&data).0 != context.data_sha256 {
            return Err(LabError::Format {
                path: context.train.clone(),
                reason: "this worker's copy of the training data differs from the search's".into(),
            });
        }
        Ok(Self::split(&data, context)?.0)
    }
}

impl Evaluation for PoseTrial {
    const NAME: &'static str = "tactrace.search.pose_model";
    type Config = TrialConfig;
    type Score = TrialScore;
    type Error = LabError;

    fn context(&self) -> Option<String> {
        let c = self.context.as_ref()?;
        crate::remote::context_json(Self::NAME, c)
    }

    fn evaluate(&self, config: &TrialConfig) -> Result<TrialScore> {
        match (config, &self.images) {
            (TrialConfig::Pins(c), None) => Ok(self.score(c)),
            (TrialConfig::Image(c), Some(parts)) => Ok(self.score_image(c, parts)),
            _ => Err(LabError::Config(
                "a search trial of a pin model on frames, or of an image model on pins".into(),
            )),
        }
    }
}

impl PoseTrial {
    /// Train on the fit part, score every target on the validation part.
    fn score(&self, config: &ModelConfig) -> TrialScore {
        let n = self.targets.len();
        let fitted = PoseModel::fit_targets(config, &self.targets, &self.fit, None, &mut |_| {});
        let model = match fitted {
            Ok((model, _)) => model,
            Err(LearnError::Diverged { .. }) => return TrialScore::failed(n, None),
            Err(e) => return TrialScore::failed(n, Some(e.to_string())),
        };
        let predicted = match model.predict_targets_batch(&self.val) {
            Ok(p) => p,
            Err(e) => return TrialScore::failed(n, Some(e.to_string())),
        };
        self.scored(&predicted)
    }

    /// The score of `predicted`, the validation part's every target.
    fn scored(&self, predicted: &[Vec<f64>]) -> TrialScore {
        let val_mae = target_mae(&self.targets, predicted, &self.truth);
        let score = self.scale.score(&val_mae);
        let failure = (!score.is_finite()).then(|| "its predictions are not numbers".to_string());
        TrialScore {
            val_mae,
            score,
            failure,
        }
    }

    /// Train an image model on the fit part's frames, score every target
    /// on the validation part's.
    fn score_image(&self, config: &ConvConfig, parts: &ImageParts) -> TrialScore {
        let n = self.targets.len();
        let fit = (&parts.fit, &parts.fit_frames);
        let model = match train_image(config, IMAGE_SEED, fit, None, &mut |_| {}) {
            Ok((model, _)) => model,
            Err(LabError::Learn(e)) if e.is_diverged() => return TrialScore::failed(n, None),
            Err(e) => return TrialScore::failed(n, Some(e.to_string())),
        };
        let f = &parts.val_frames;
        let predicted = Frames::new(&f.pixels, f.count(), f.info.height, f.info.width)
            .map_err(LearnError::from)
            .and_then(|frames| model.predict_batch(&frames));
        match predicted {
            Ok(p) => self.scored(&p),
            Err(e) => TrialScore::failed(n, Some(e.to_string())),
        }
    }
}

/// How a search ended.
#[derive(Debug, Clone)]
pub struct SearchOutcome {
    /// Every trial, in order.
    pub trials: Vec<TrialRecord>,
    /// The best trial's index.
    pub best: usize,
    /// The finished folder.
    pub dir: std::path::PathBuf,
    /// The data's targets, in the order of each trial's `val_mae`.
    pub targets: Vec<ModelTarget>,
}

/// Run (or with `resume`, continue) the search of `settings` on `data`
/// (read from the folder `train`, where a remote executor's workers read
/// it too) into `out`, calling `progress` after each trial.
pub fn search(
    settings: &SearchSettings,
    (data, train): (&TapData, &Path),
    out: &Path,
    (force, resume): (bool, bool),
    executor: &impl Executor,
    progress: &mut dyn FnMut(&TrialRecord),
) -> Result<SearchOutcome> {
    let tpe = settings.tpe()?;
    if settings.trials == 0 || settings.batch == 0 {
        return Err(LabError::Config(
            "--trials and --batch must be at least 1".into(),
        ));
    }
    let context = SearchContext {
        train: std::path::absolute(train).map_err(|e| LabError::Config(e.to_string()))?,
        data_sha256: settings.data_sha256.clone(),
        val_fraction: settings.val_fraction,
        seed: settings.seed,
        images: matches!(settings.base, TrialConfig::Image(_)),
    };
    let (trial, fit_data, val_rows) = PoseTrial::split(data, context)?;
    for cfg in settings.space.corners(&settings.base, tpe.domains())? {
        if let TrialConfig::Pins(cfg) = cfg {
            crate::train::check_trainable(&cfg, &fit_data, val_rows)?;
        }
    }
    let mut folder = SearchFolder::open(out, settings, force, resume)?;
    let mut history: Vec<Observation> = folder
        .trials()
        .iter()
        .map(|t| Observation {
            values: t.values.clone(),
            score: t.score.score,
        })
        .collect();
    while history.len() < settings.trials {
        let start = history.len() - history.len() % settings.batch;
        let end = (start + settings.batch).min(settings.trials);
        let ks: Vec<usize> = (history.len()..end).collect();
        let values: Vec<Vec<f64>> = ks
            .iter()
            .map(|&k| tpe.suggest(k, &history[..start]))
            .collect();
        let configs = values
            .iter()
            .map(|v| settings.space.apply(&settings.base, v))
            .collect::<Result<Vec<_>>>()?;
        let t0 = std::time::Instant::now();
        let scores = executor.run(&trial, &configs)?;
        let seconds = t0.elapsed().as_secs_f64() / ks.len() as f64;
        for ((k, v), score) in ks.into_iter().zip(values).zip(scores) {
            let record = TrialRecord {
                trial: k,
                settings: settings.space.named(&v),
                values: v.clone(),
                score: score.clone(),
                seconds,
            };
            folder.append(&record)?;
            progress(&record);
            history.push(Observation {
                values: v,
                score: score.score,
            });
        }
    }
    let Some(best) = folder.best() else {
        return Err(all_failed(folder.trials(), out));
    };
    let trials = folder.trials().to_vec();
    let dir = folder.finish(settings, best, &trial.targets)?;
    Ok(SearchOutcome {
        trials,
        best,
        dir,
        targets: trial.targets,
    })
}

/// The error of a search none of whose `trials` gave a score (exit 1):
/// how many diverged, how many failed otherwise and the last reason; the
/// trials stay in `<out>.partial`.
fn all_failed(trials: &[TrialRecord], out: &Path) -> LabError {
    let failed: Vec<&String> = trials
        .iter()
        .filter_map(|t| t.score.failure.as_ref())
        .collect();
    let diverged = trials.len() - failed.len();
    let mut reason = format!("{diverged} diverged, {} failed otherwise", failed.len());
    if let Some(last) = failed.last() {
        reason += &format!(", the last because {last}");
    }
    if diverged > 0 {
        reason += "; lower the learning rates' ranges";
    }
    LabError::AllFailed {
        what: "search trials".into(),
        tried: trials.len(),
        reason,
        kept: Some(tactrace_store::fsutil::partial_path(out)),
    }
}
