//! A small random/grid hyper-parameter search over learning rates (hidden
//! and output layer), beta, hidden size and number of components, scored on a validation split that
//! the caller carves out of the training data (never the test data), over
//! every target of the model ([`TargetScale`]).
use crate::config::ModelConfig;
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::pose_model::PoseModel;
use crate::target_score::TargetScale;
use crate::targets::{target_mae, ModelTarget};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The grid to sample from. Each value applies to every net of the model.
/// Missing keys in a TOML file take the [`Default`] grid's values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SearchSpace {
    /// `NetConfig::learning_rate` (the hidden layers' input weights).
    pub learning_rates: Vec<f64>,
    /// `NetConfig::output_learning_rate`.
    pub output_learning_rates: Vec<f64>,
    pub betas: Vec<f64>,
    pub hidden: Vec<usize>,
    /// Ignored by nets without PCA (DisDenNN).
    pub n_components: Vec<usize>,
    /// Configurations to try; the whole grid when it is not larger.
    pub trials: usize,
    pub seed: u64,
    /// Each target's goal (its error to reach, in its unit, one a target
    /// in order): a trial's score divides each target's error by it. Empty
    /// (the default): by the target's spread over the training rows.
    pub goals: Vec<f64>,
}

impl Default for SearchSpace {
    /// Around the default preset (learning rates are per fan-in, see
    /// [`crate::LrScaling::FanIn`]): 8 of the 96 grid points.
    fn default() -> Self {
        SearchSpace {
            learning_rates: vec![18.0, 36.0],
            output_learning_rates: vec![3.0, 5.0],
            betas: vec![0.5, 1.0],
            hidden: vec![500, 1000],
            n_components: vec![20, 35, 50],
            trials: 8,
            seed: 0,
            goals: Vec::new(),
        }
    }
}

/// One evaluated configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    pub config: ModelConfig,
    /// Validation mean absolute error of every target, in the targets'
    /// order and units (circular ones wrapped).
    pub val_mae: Vec<f64>,
    /// `sum_j mae_j / scale_j` over every target ([`TargetScale::score`]:
    /// the goals, or the training targets' spreads, circular ones
    /// wrapped), so every target weighs alike; lower is better. Diverged
    /// runs score +inf.
    pub score: f64,
}

/// Try configurations drawn from `space` on top of `base`, each a model of
/// `outputs` (the columns of the datasets' targets), calling `progress`
/// after each; trials sorted best first. `val` must be carved out of the
/// training data (never the test data).
pub fn hyperparameter_search(
    base: &ModelConfig,
    space: &SearchSpace,
    outputs: &[ModelTarget],
    train: &Dataset,
    val: &Dataset,
    progress: &mut dyn FnMut(&Trial),
) -> Result<Vec<Trial>, LearnError> {
    check_grid_size(space)?;
    check_val(outputs, train, val)?;
    let grid = grid(space);
    if grid.is_empty() {
        return Err(LearnError::Config {
            field: "search space",
            reason: "every list needs at least one value".into(),
        });
    }
    let scale = if space.goals.is_empty() {
        TargetScale::spreads(outputs, train)?
    } else {
        TargetScale::goals(outputs, &space.goals)?
    };
    let mut picks: Vec<usize> = (0..grid.len()).collect();
    picks.shuffle(&mut ChaCha8Rng::seed_from_u64(space.seed));
    picks.truncate(space.trials.max(1));
    let mut trials = Vec::with_capacity(picks.len());
    for k in picks {
        let config = apply(base, grid[k]);
        let trial = match PoseModel::fit_targets(&config, outputs, train, None, &mut |_| {}) {
            Ok((model, _)) => {
                let mae = validation_mae(&model, outputs, val)?;
                let score = scale.score(&mae);
                Trial {
                    config,
                    val_mae: mae,
                    score,
                }
            }
            Err(LearnError::Diverged { .. }) => Trial {
                config,
                val_mae: vec![f64::INFINITY; outputs.len()],
                score: f64::INFINITY,
            },
            Err(e) => return Err(e),
        };
        progress(&trial);
        trials.push(trial);
    }
    trials.sort_by(|a, b| a.score.total_cmp(&b.score));
    Ok(trials)
}

/// Error unless `val` has `train`'s inputs and one target a column of
/// `outputs`.
fn check_val(outputs: &[ModelTarget], train: &Dataset, val: &Dataset) -> Result<(), LearnError> {
    if val.dim_x != train.dim_x {
        return Err(LearnError::DimensionMismatch {
            expected: train.dim_x,
            got: val.dim_x,
        });
    }
    if val.dim_y != outputs.len() {
        return Err(LearnError::Shape {
            what: "validation targets per sample",
            expected: outputs.len(),
            got: val.dim_y,
        });
    }
    Ok(())
}

/// Every target's mean absolute error on `val` (circular ones wrapped).
fn validation_mae(
    model: &PoseModel,
    outputs: &[ModelTarget],
    val: &Dataset,
) -> Result<Vec<f64>, LearnError> {
    let pred = model.predict_targets_batch(val)?;
    let truth: Vec<Vec<f64>> = (0..val.n)
        .map(|i| val.y_row(i).iter().map(|&v| f64::from(v)).collect())
        .collect();
    Ok(target_mae(outputs, &pred, &truth))
}

/// Largest grid a search spans (the grid is listed before it is sampled).
pub const MAX_GRID_POINTS: usize = 1_000_000;

/// Error when the lists span more than [`MAX_GRID_POINTS`] (five lists of
/// 100 values, a 3 kB file, would list 10^10 points).
fn check_grid_size(space: &SearchSpace) -> Result<(), LearnError> {
    let lens = [
        space.learning_rates.len(),
        space.output_learning_rates.len(),
        space.betas.len(),
        space.hidden.len(),
        space.n_components.len(),
    ];
    let points = lens.iter().fold(1usize, |acc, &n| acc.saturating_mul(n));
    if points <= MAX_GRID_POINTS {
        return Ok(());
    }
    Err(LearnError::Config {
        field: "search space",
        reason: format!("the lists span {points} grid points; at most {MAX_GRID_POINTS}"),
    })
}

/// One grid point: (learning rate, output learning rate, beta, hidden, PCs).
type Point = (f64, f64, f64, usize, usize);

fn grid(space: &SearchSpace) -> Vec<Point> {
    let mut out = Vec::new();
    for &lr in &space.learning_rates {
        for &out_lr in &space.output_learning_rates {
            for &beta in &space.betas {
                for &h in &space.hidden {
                    for &c in &space.n_components {
                        out.push((lr, out_lr, beta, h, c));
                    }
                }
            }
        }
    }
    out
}

fn apply(base: &ModelConfig, (lr, out_lr, beta, hidden, comps): Point) -> ModelConfig {
    let mut cfg = base.clone();
    for net in [&mut cfg.pose, &mut cfg.position, &mut cfg.angle]
        .into_iter()
        .flatten()
    {
        net.learning_rate = lr;
        net.output_learning_rate = Some(out_lr);
        net.beta = beta;
        net.hidden = vec![hidden];
        if net.n_components.is_some() {
            net.n_components = Some(comps);
        }
    }
    cfg
}
