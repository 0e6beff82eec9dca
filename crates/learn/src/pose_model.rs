//! Pose models (report ch. 4.2): standardiser, PCA per net, one or two nets
//! and target scaling, fitted together and predicting `[r mm, theta deg]`
//! from one pin-displacement vector.
use crate::config::{ModelConfig, ModelKind, TargetScaling};
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::pca::{Components, Pca};
use crate::predict::Predictor;
use crate::standardise::Standardiser;
use crate::trainer::{train_nets, NetData, Trainer};
pub use crate::trainer::{EpochReport, NetEpoch, TrainingHistory};
use crate::Layers;
use std::sync::OnceLock;

/// One fitted network with its input projection and target columns.
#[derive(Debug, Clone)]
pub(crate) struct FittedNet {
    pub name: String,
    /// Target columns this net predicts (0 = r, 1 = theta).
    pub targets: Vec<usize>,
    /// `None` feeds the standardised displacements directly.
    pub pca: Option<Pca>,
    pub layers: Layers,
}

/// A trained pose model.
#[derive(Debug, Clone)]
pub struct PoseModel {
    pub(crate) config: ModelConfig,
    pub(crate) standardiser: Standardiser,
    /// Target scaling (mean 0 / std 1 identity when `TargetScaling::None`).
    pub(crate) targets: Standardiser,
    pub(crate) nets: Vec<FittedNet>,
    /// The prediction path, laid out at the first prediction.
    pub(crate) predictor: OnceLock<Predictor>,
}

impl PoseModel {
    /// Fit on `train` (inputs: displacements; targets: `[r, theta]`),
    /// calling `progress` after every epoch.
    pub fn fit(
        cfg: &ModelConfig,
        train: &Dataset,
        progress: &mut dyn FnMut(&EpochReport),
    ) -> Result<(PoseModel, TrainingHistory), LearnError> {
        Self::fit_with_validation(cfg, train, None, progress)
    }

    /// As [`Self::fit`], also reporting each net's loss on `val` per epoch
    /// (never used for fitting). A divergence restarts the fit with halved
    /// learning rates up to `cfg.divergence_retries` times (the history
    /// counts the halvings; the model's config holds the rates used).
    pub fn fit_with_validation(
        cfg: &ModelConfig,
        train: &Dataset,
        val: Option<&Dataset>,
        progress: &mut dyn FnMut(&EpochReport),
    ) -> Result<(PoseModel, TrainingHistory), LearnError> {
        let mut cfg = cfg.clone();
        let mut halvings = 0;
        loop {
            match Self::fit_once(&cfg, train, val, progress) {
                Err(LearnError::Diverged { .. }) if halvings < cfg.divergence_retries => {
                    cfg.scale_learning_rates(0.5);
                    halvings += 1;
                }
                Ok((model, mut history)) => {
                    history.lr_halvings = halvings;
                    return Ok((model, history));
                }
                Err(e) => return Err(e),
            }
        }
    }

    fn fit_once(
        cfg: &ModelConfig,
        train: &Dataset,
        val: Option<&Dataset>,
        progress: &mut dyn FnMut(&EpochReport),
    ) -> Result<(PoseModel, TrainingHistory), LearnError> {
        cfg.validate()?;
        cfg.check_samples(train.n, train.dim_x)?;
        if train.dim_y != 2 {
            return Err(LearnError::Shape {
                what: "targets per sample",
                expected: 2,
                got: train.dim_y,
            });
        }
        if let Some(v) = val {
            if v.dim_x != train.dim_x || v.dim_y != 2 {
                return Err(LearnError::DimensionMismatch {
                    expected: train.dim_x,
                    got: v.dim_x,
                });
            }
        }
        let standardiser = Standardiser::fit(&train.x, train.n, train.dim_x)?;
        let targets = fit_target_scaling(cfg.target_scaling, train)?;
        let z = standardiser.transform(&train.x);
        let z_val = val.map(|v| standardiser.transform(&v.x));
        let mut trainers = Vec::new();
        let mut fitted = Vec::new();
        for (k, (name, cols, net_cfg)) in cfg.nets().into_iter().enumerate() {
            let pca = match net_cfg.n_components {
                Some(c) => Some(Pca::fit(
                    &z,
                    train.n,
                    train.dim_x,
                    Components::Count(c),
                    cfg.pc_scaling,
                )?),
                None => None,
            };
            let inputs = net_inputs(pca.as_ref(), &z);
            let data = NetData::new(inputs, train, &cols, &targets)?;
            let val_data = match (val, &z_val) {
                (Some(v), Some(zv)) => Some(NetData::new(
                    net_inputs(pca.as_ref(), zv),
                    v,
                    &cols,
                    &targets,
                )?),
                _ => None,
            };
            let mut sizes = vec![data.set.dim_x];
            sizes.extend(&net_cfg.hidden);
            sizes.push(cols.len());
            let layers = Layers::new(&sizes, cfg.seed.wrapping_add(k as u64))?;
            trainers.push(Trainer::new(
                name, layers, cfg, net_cfg, data, val_data, k as u64,
            ));
            fitted.push(FittedNet {
                name: name.to_string(),
                targets: cols,
                pca,
                layers: Layers::new(&sizes, 0)?,
            });
        }
        let history = train_nets(&mut trainers, cfg.epochs, progress)?;
        for (f, t) in fitted.iter_mut().zip(trainers) {
            f.layers = t.into_layers();
        }
        Ok((
            PoseModel {
                config: cfg.clone(),
                standardiser,
                targets,
                nets: fitted,
                predictor: OnceLock::new(),
            },
            history,
        ))
    }

    /// Predict `[r mm, theta deg]` from one displacement vector.
    pub fn predict(&self, displacement: &[f32]) -> Result<[f64; 2], LearnError> {
        if displacement.len() != self.input_dim() {
            return Err(LearnError::DimensionMismatch {
                expected: self.input_dim(),
                got: displacement.len(),
            });
        }
        let mut out = Vec::with_capacity(1);
        self.predict_into(displacement, &mut out)?;
        Ok(out[0])
    }

    /// Predict every row of `rows` (row-major, [`Self::input_dim`] values
    /// a row): `[r mm, theta deg]` per row, as [`Self::predict`] gives them
    /// one at a time, computed a block of rows at a time (faster).
    pub fn predict_rows(&self, rows: &[f32]) -> Result<Vec<[f64; 2]>, LearnError> {
        let dim = self.input_dim();
        if !rows.len().is_multiple_of(dim) {
            return Err(LearnError::DimensionMismatch {
                expected: dim,
                got: rows.len(),
            });
        }
        let mut out = Vec::with_capacity(rows.len() / dim);
        self.predict_into(rows, &mut out)?;
        Ok(out)
    }

    /// Predict every sample of `ds`.
    pub fn predict_batch(&self, ds: &Dataset) -> Result<Vec<[f64; 2]>, LearnError> {
        if ds.dim_x != self.input_dim() {
            return Err(LearnError::DimensionMismatch {
                expected: self.input_dim(),
                got: ds.dim_x,
            });
        }
        self.predict_rows(&ds.x)
    }

    /// Multiply-adds of one prediction, `(f64, f32)`: the projections onto
    /// the principal components (once for nets that share them), then
    /// every layer's weights (the sigmoids not counted).
    pub fn multiply_adds(&self) -> (usize, usize) {
        self.predictor().multiply_adds(self)
    }

    fn predictor(&self) -> &Predictor {
        self.predictor.get_or_init(|| Predictor::new(self))
    }

    /// Checks that `rows` are finite (the error names the first value that
    /// is not) and appends their predictions to `out`.
    fn predict_into(&self, rows: &[f32], out: &mut Vec<[f64; 2]>) -> Result<(), LearnError> {
        let dim = self.input_dim();
        if let Some(k) = rows.iter().position(|v| !v.is_finite()) {
            return Err(LearnError::NonFinite {
                what: "input",
                row: k / dim,
                column: k % dim,
                value: rows[k],
            });
        }
        self.predictor().predict_rows(self, rows, out);
        Ok(())
    }

    /// Displacement-vector length the model expects.
    pub fn input_dim(&self) -> usize {
        self.standardiser.dim()
    }

    /// The configuration it was trained with.
    pub fn config(&self) -> &ModelConfig {
        &self.config
    }

    /// Which model family.
    pub fn kind(&self) -> ModelKind {
        self.config.kind
    }

    /// Layer sizes of each net, by name.
    pub fn architecture(&self) -> Vec<(String, Vec<usize>)> {
        self.nets
            .iter()
            .map(|n| (n.name.clone(), n.layers.sizes().to_vec()))
            .collect()
    }
}

/// Project standardised rows through `pca`, or pass them through.
fn net_inputs(pca: Option<&Pca>, z: &[f64]) -> Vec<f64> {
    match pca {
        Some(p) => p.transform(z),
        None => z.to_vec(),
    }
}

fn fit_target_scaling(scaling: TargetScaling, train: &Dataset) -> Result<Standardiser, LearnError> {
    match scaling {
        TargetScaling::Standardise => Standardiser::fit(&train.y, train.n, train.dim_y),
        TargetScaling::None => {
            Standardiser::from_parts(vec![0.0; train.dim_y], vec![1.0; train.dim_y])
        }
    }
}
