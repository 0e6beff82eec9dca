//! Pose models (report ch. 4.2): standardiser, PCA per net, one or more
//! nets and target scaling, fitted together and predicting N named targets
//! ([`ModelTarget`]: mm or deg, circular angles as sine and cosine) from one
//! pin-displacement vector; the edge pose `[r mm, theta deg]` for a model of
//! one position and one angle. An ensemble ([`ModelConfig::ensemble`]) is
//! the same model with its nets trained once per member (seeds derived
//! from the run's) on the same standardiser, PCA and target scaling, the
//! members' scaled outputs averaged.
use crate::config::{ModelConfig, ModelKind};
use crate::dataset::Dataset;
use crate::error::LearnError;
use crate::fit_members::{fit_members, net_inputs};
use crate::pca::Pca;
use crate::pin_features::{FeatureMap, PinFeatures};
use crate::predict::Predictor;
use crate::reflections::{self, MirrorViews};
use crate::rotations;
use crate::standardise::Standardiser;
use crate::targets::{self, ModelTarget, Unit};
pub use crate::trainer::{EpochReport, NetEpoch, TrainingHistory};
use crate::turned_views::TurnedViews;
use crate::Layers;
use std::sync::OnceLock;

/// One fitted network with its input projection and target columns.
#[derive(Debug, Clone)]
pub(crate) struct FittedNet {
    pub name: String,
    /// Encoded target columns this net predicts (for the edge task 0 = r,
    /// 1 = theta; a circular target takes two, its sine and cosine).
    pub targets: Vec<usize>,
    /// `None` feeds the standardised displacements directly.
    pub pca: Option<Pca>,
    pub layers: Layers,
    /// How often its member's learning rates were halved after a
    /// divergence, beyond the model configuration's (an ensemble's member
    /// that restarted alone; 0 for a single model, whose configuration
    /// holds the rates it trained with).
    pub lr_halvings: usize,
}

/// A trained pose model.
#[derive(Debug, Clone)]
pub struct PoseModel {
    pub(crate) config: ModelConfig,
    pub(crate) standardiser: Standardiser,
    /// Scaling of the encoded target columns (mean 0 / std 1 identity when
    /// `TargetScaling::None`).
    pub(crate) targets: Standardiser,
    pub(crate) nets: Vec<FittedNet>,
    /// What it predicts, in order.
    pub(crate) outputs: Vec<ModelTarget>,
    /// The features the nets see, when not the displacements themselves
    /// ([`crate::PinFeatures`]); the standardiser is fitted on them.
    pub(crate) features: Option<FeatureMap>,
    /// The layout and turns of a model fitted with
    /// [`ModelConfig::rotations`] (absent without, or in a file written
    /// before they were recorded): what averaging over turned views needs.
    pub(crate) views: Option<TurnedViews>,
    /// The layout and mirror of a model fitted with
    /// [`ModelConfig::reflections`]: what averaging a tap with its mirror
    /// copy needs.
    pub(crate) mirror: Option<MirrorViews>,
    /// Epochs its nets trained before this fit's `config.epochs`: 0 for a
    /// model fitted from fresh weights, the starting model's total for one
    /// continued from it ([`PoseModel::continue_on_pins`]).
    pub(crate) epochs_before: usize,
    /// The fast prediction path of an edge model (`[r mm, theta deg]`,
    /// neither circular), laid out at the first prediction.
    pub(crate) predictor: OnceLock<Predictor>,
}

impl PoseModel {
    /// Fit on `train` (inputs: displacements; targets: `[r mm, theta
    /// deg]`, the edge task), calling `progress` after every epoch.
    pub fn fit(
        cfg: &ModelConfig,
        train: &Dataset,
        progress: &mut dyn FnMut(&EpochReport),
    ) -> Result<(PoseModel, TrainingHistory), LearnError> {
        Self::fit_with_validation(cfg, train, None, progress)
    }

    /// As [`Self::fit`], also reporting each net's loss on `val` per epoch
    /// (never used for fitting), for the edge task's two targets.
    pub fn fit_with_validation(
        cfg: &ModelConfig,
        train: &Dataset,
        val: Option<&Dataset>,
        progress: &mut dyn FnMut(&EpochReport),
    ) -> Result<(PoseModel, TrainingHistory), LearnError> {
        Self::fit_targets(cfg, &targets::edge_targets(), train, val, progress)
    }

    /// Fit a model of `outputs` (the columns of `train`'s targets, in
    /// order), reporting each net's loss on `val` per epoch (never used for
    /// fitting). A divergence restarts the diverged member alone with
    /// halved learning rates up to `cfg.divergence_retries` times; the
    /// other members keep their results (the history counts the halvings,
    /// per member for an ensemble; a single model's config holds the rates
    /// used, an ensemble's nets their member's halvings). An ensemble's
    /// members train together, in parallel.
    pub fn fit_targets(
        cfg: &ModelConfig,
        outputs: &[ModelTarget],
        train: &Dataset,
        val: Option<&Dataset>,
        progress: &mut dyn FnMut(&EpochReport),
    ) -> Result<(PoseModel, TrainingHistory), LearnError> {
        Self::fit_targets_on_pins(cfg, outputs, train, val, None, progress)
    }

    /// As [`Self::fit_targets`], for data whose displacements are laid
    /// out against `reference_pins` (px, in input order): the layout
    /// [`ModelConfig::pin_features`] other than the displacements and
    /// [`ModelConfig::rotations`] need (an error without it), recorded in
    /// the model for the features. With `rotations` the model is fitted on
    /// `train` and its turned copies (`val` as given) and keeps the turns
    /// for averaging over turned views at prediction.
    pub fn fit_targets_on_pins(
        cfg: &ModelConfig,
        outputs: &[ModelTarget],
        train: &Dataset,
        val: Option<&Dataset>,
        reference_pins: Option<&[[f64; 2]]>,
        progress: &mut dyn FnMut(&EpochReport),
    ) -> Result<(PoseModel, TrainingHistory), LearnError> {
        let data = PinData::prepare(cfg, outputs, train, val, reference_pins)?;
        let (train, val) = data.sets(train, val);
        let (train, val) = checked_encoded(outputs, train, val)?;
        let (mut model, history) = fit_members(cfg, outputs, &train, val.as_ref(), progress)?;
        data.attach(&mut model);
        Ok((model, history))
    }

    /// Predict the edge pose `[r mm, theta deg]` from one displacement
    /// vector: the model's position (mm) and angle (deg) targets, refused
    /// ([`LearnError::NotAnEdgeModel`]) for a model of other targets.
    pub fn predict(&self, displacement: &[f32]) -> Result<[f64; 2], LearnError> {
        if self.is_plain_edge() {
            self.check_dim(displacement.len())?;
            let mut out = Vec::with_capacity(1);
            self.predict_into(displacement, &mut out)?;
            return Ok(out[0]);
        }
        let [r, theta] = self.edge_roles()?;
        let values = self.predict_targets(displacement)?;
        Ok([values[r], values[theta]])
    }

    /// Predict every target, in [`Self::outputs`]' order and units
    /// (circular angles within (-180, 180] deg), from one displacement
    /// vector.
    pub fn predict_targets(&self, displacement: &[f32]) -> Result<Vec<f64>, LearnError> {
        self.check_dim(displacement.len())?;
        if self.is_plain_edge() {
            return self.predict(displacement).map(|p| p.to_vec());
        }
        let encoded = match (self.averaged_views(), self.averaged_mirror()) {
            (Some(views), _) => {
                views.average(&self.outputs, displacement, |d| self.predict_columns(d))?
            }
            (None, Some(mirror)) => mirror.average(displacement, |d| self.predict_columns(d))?,
            (None, None) => self.predict_columns(displacement)?,
        };
        Ok(targets::decode(&self.outputs, &encoded))
    }

    /// The nets' columns of one displacement vector (members averaged,
    /// target scaling undone): the encoded targets before decoding.
    fn predict_columns(&self, displacement: &[f32]) -> Result<Vec<f64>, LearnError> {
        let mut z = vec![0.0f64; self.standardiser.dim()];
        match &self.features {
            Some(map) => {
                let mut features = Vec::with_capacity(map.output_dim());
                map.extend(displacement, &mut features);
                self.standardiser.transform_into(&features, &mut z);
            }
            None => self.standardiser.transform_into(displacement, &mut z),
        }
        let width = self.targets.dim();
        let mut scaled = vec![0.0f64; width];
        for net in &self.nets {
            let input: Vec<f32> = net_inputs(net.pca.as_ref(), &z)
                .into_iter()
                .map(|v| v as f32)
                .collect();
            let mut out = vec![0.0f32; net.targets.len()];
            net.layers.predict(&input, &mut out)?;
            for (&col, &o) in net.targets.iter().zip(&out) {
                scaled[col] += o as f64;
            }
        }
        self.average_members(&mut scaled);
        let mut encoded = vec![0.0f64; width];
        self.targets.inverse_into(&scaled, &mut encoded);
        Ok(encoded)
    }

    /// The turned views every prediction averages over: `Some` when the
    /// configuration's [`crate::Rotations::at_prediction`] is set.
    fn averaged_views(&self) -> Option<&TurnedViews> {
        let on = self.config.rotations.is_some_and(|r| r.at_prediction);
        self.views.as_ref().filter(|_| on)
    }

    /// The mirror every prediction averages over: `Some` when the
    /// configuration's [`crate::Reflections::at_prediction`] is set.
    fn averaged_mirror(&self) -> Option<&MirrorViews> {
        let on = self
            .config
            .reflections
            .as_ref()
            .is_some_and(|r| r.at_prediction);
        self.mirror.as_ref().filter(|_| on)
    }

    /// Whether every prediction averages the tap's turned views
    /// ([`crate::Rotations::at_prediction`]).
    pub fn averages_turned_views(&self) -> bool {
        self.averaged_views().is_some()
    }

    /// Whether every prediction averages the tap's turned views (or, for
    /// a model fitted with `reflections`, the tap and its mirror copy);
    /// `None` for a model fitted with neither, which has no views to
    /// average.
    pub fn views_at_prediction(&self) -> Option<bool> {
        if self.config.reflections.is_some() {
            return Some(self.averaged_mirror().is_some());
        }
        self.config.rotations.map(|_| self.averages_turned_views())
    }

    /// Switch averaging over turned views at prediction on or off (the
    /// configuration's [`crate::Rotations::at_prediction`], or for a model
    /// fitted with mirror copies [`crate::Reflections::at_prediction`]);
    /// refused for a model with neither or whose file predates the
    /// recorded layout.
    pub fn set_turned_views(&mut self, on: bool) -> Result<(), LearnError> {
        let has_mirror = self.mirror.is_some();
        if let Some(refl) = self.config.reflections.as_mut() {
            if on && !has_mirror {
                return Err(LearnError::Config {
                    field: "reflections.at_prediction",
                    reason: "the model does not record its layout's mirror".into(),
                });
            }
            refl.at_prediction = on;
            self.predictor = OnceLock::new();
            return Ok(());
        }
        let refuse = |reason: &str| LearnError::Config {
            field: "rotations.at_prediction",
            reason: reason.into(),
        };
        let Some(rot) = self.config.rotations.as_mut() else {
            return Err(refuse(
                "the model was not fitted with rotations (nor with reflections)",
            ));
        };
        if on && self.views.is_none() {
            return Err(refuse(
                "the model does not record its layout's turns (fitted before they were kept)",
            ));
        }
        rot.at_prediction = on;
        self.predictor = OnceLock::new();
        Ok(())
    }

    /// Predict every row of `rows` (row-major, [`Self::input_dim`] values
    /// a row): `[r mm, theta deg]` per row, as [`Self::predict`] gives them
    /// one at a time; for a plain edge model a block of rows at a time
    /// (faster).
    pub fn predict_rows(&self, rows: &[f32]) -> Result<Vec<[f64; 2]>, LearnError> {
        let dim = self.input_dim();
        if !rows.len().is_multiple_of(dim) {
            return Err(LearnError::DimensionMismatch {
                expected: dim,
                got: rows.len(),
            });
        }
        if self.is_plain_edge() {
            let mut out = Vec::with_capacity(rows.len() / dim);
            self.predict_into(rows, &mut out)?;
            return Ok(out);
        }
        rows.chunks(dim).map(|row| self.predict(row)).collect()
    }

    /// Divide the sums of the members' scaled outputs by their number
    /// (nothing to do for a single model).
    pub(crate) fn average_members(&self, scaled: &mut [f64]) {
        if self.config.ensemble > 1 {
            let k = self.config.ensemble as f64;
            scaled.iter_mut().for_each(|v| *v /= k);
        }
    }

    /// Members of the ensemble (1: a single model).
    pub fn ensemble(&self) -> usize {
        self.config.ensemble
    }

    /// An edge model whose targets are `[r mm, theta deg]` in that order,
    /// neither circular: the one the fast path ([`Predictor`]) serves.
    fn is_plain_edge(&self) -> bool {
        matches!(self.outputs.as_slice(), [r, t]
            if r.unit == Unit::Mm && t.unit == Unit::Deg && !r.circular && !t.circular)
            && self.targets.dim() == 2
            && self.features.is_none()
            && self.averaged_views().is_none()
            && self.averaged_mirror().is_none()
    }

    fn check_dim(&self, got: usize) -> Result<(), LearnError> {
        if got != self.input_dim() {
            return Err(LearnError::DimensionMismatch {
                expected: self.input_dim(),
                got,
            });
        }
        Ok(())
    }

    /// Predict the edge pose of every sample of `ds` ([`Self::predict`]).
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

    /// Predict every target of every sample of `ds`
    /// ([`Self::predict_targets`]).
    pub fn predict_targets_batch(&self, ds: &Dataset) -> Result<Vec<Vec<f64>>, LearnError> {
        if self.is_plain_edge() {
            let rows = self.predict_batch(ds)?;
            return Ok(rows.into_iter().map(|p| p.to_vec()).collect());
        }
        (0..ds.n)
            .map(|i| self.predict_targets(ds.x_row(i)))
            .collect()
    }

    /// What the model predicts, in order.
    pub fn outputs(&self) -> &[ModelTarget] {
        &self.outputs
    }

    /// The indices of the position (mm) and angle (deg) targets of an edge
    /// model ([`crate::edge_roles`]).
    pub fn edge_roles(&self) -> Result<[usize; 2], LearnError> {
        crate::targets::edge_roles(&self.outputs)
    }

    /// Displacement-vector length the model expects.
    pub fn input_dim(&self) -> usize {
        self.features
            .as_ref()
            .map_or(self.standardiser.dim(), FeatureMap::input_dim)
    }

    /// What the nets see of a tap ([`ModelConfig::pin_features`]).
    pub fn pin_features(&self) -> PinFeatures {
        self.features
            .as_ref()
            .map_or(PinFeatures::Displacements, FeatureMap::kind)
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

/// `data` with its targets encoded for the networks (a circular target as
/// its sine and cosine); the same data when no target is circular.
fn encode(outputs: &[ModelTarget], data: &Dataset) -> Result<Dataset, LearnError> {
    if outputs.iter().all(|t| !t.circular) {
        return Ok(data.clone());
    }
    let width: usize = outputs.iter().map(ModelTarget::width).sum();
    let mut y = Vec::with_capacity(data.n * width);
    for i in 0..data.n {
        targets::encode_into(outputs, data.y_row(i), &mut y);
    }
    Dataset::new(data.x.clone(), y, data.n, data.dim_x, width)
}

/// The training rows the nets see, and what the model keeps of how they
/// were made: the turned or mirrored copies, the feature map, the views.
pub(crate) struct PinData {
    /// The training rows with their copies, as features when `features`.
    train: Option<Dataset>,
    /// The validation rows as features (`None`: as given).
    val: Option<Dataset>,
    features: Option<FeatureMap>,
    views: Option<TurnedViews>,
    mirror: Option<MirrorViews>,
}

impl PinData {
    /// `train` with the copies of `cfg.rotations` or `cfg.reflections`
    /// over `reference_pins`, and both sets as `cfg.pin_features`.
    pub(crate) fn prepare(
        cfg: &ModelConfig,
        outputs: &[ModelTarget],
        train: &Dataset,
        val: Option<&Dataset>,
        reference_pins: Option<&[[f64; 2]]>,
    ) -> Result<Self, LearnError> {
        let turned = turned_training_data(cfg, outputs, train, reference_pins)?;
        let views = match (&cfg.rotations, reference_pins) {
            (Some(rot), Some(pins)) => Some(TurnedViews::new(rot, pins)?),
            _ => None,
        };
        let mirrored = reflections::mirrored_training_data(cfg, outputs, train, reference_pins)?;
        let mirror = reflections::mirror_views(cfg, outputs, reference_pins)?;
        let copied = turned.or(mirrored);
        let mut data = PinData {
            train: None,
            val: None,
            features: None,
            views,
            mirror,
        };
        let rows = copied.as_ref().unwrap_or(train);
        let Some(map) = feature_map(cfg.pin_features, reference_pins, rows.dim_x)? else {
            data.train = copied;
            return Ok(data);
        };
        let featured =
            |d: &Dataset| Dataset::new(map.rows(&d.x), d.y.clone(), d.n, map.output_dim(), d.dim_y);
        data.train = Some(featured(rows)?);
        data.val = val.map(featured).transpose()?;
        data.features = Some(map);
        Ok(data)
    }

    /// The training and validation rows the nets see (`train` and `val`
    /// themselves when nothing was made of them).
    pub(crate) fn sets<'a>(
        &'a self,
        train: &'a Dataset,
        val: Option<&'a Dataset>,
    ) -> (&'a Dataset, Option<&'a Dataset>) {
        let val = if self.features.is_some() {
            self.val.as_ref()
        } else {
            val
        };
        (self.train.as_ref().unwrap_or(train), val)
    }

    /// Whether `model` was fitted on rows made this way (the same feature
    /// map, turned views and mirror, over the same pins).
    pub(crate) fn made_as(&self, model: &PoseModel) -> bool {
        self.features == model.features && self.views == model.views && self.mirror == model.mirror
    }

    /// Give `model` the feature map and views these rows were made with.
    pub(crate) fn attach(self, model: &mut PoseModel) {
        model.features = self.features;
        model.views = self.views;
        model.mirror = self.mirror;
        model.predictor = OnceLock::new();
    }
}

/// `train` and `val` checked against `outputs` and encoded (a circular
/// target as its sine and cosine).
pub(crate) fn checked_encoded(
    outputs: &[ModelTarget],
    train: &Dataset,
    val: Option<&Dataset>,
) -> Result<(Dataset, Option<Dataset>), LearnError> {
    targets::check_targets(outputs)?;
    for d in std::iter::once(train).chain(val) {
        if d.dim_y != outputs.len() {
            return Err(LearnError::Shape {
                what: "targets per sample",
                expected: outputs.len(),
                got: d.dim_y,
            });
        }
    }
    if let Some(v) = val {
        if v.dim_x != train.dim_x {
            return Err(LearnError::DimensionMismatch {
                expected: train.dim_x,
                got: v.dim_x,
            });
        }
    }
    let train = encode(outputs, train)?;
    let val = val.map(|v| encode(outputs, v)).transpose()?;
    Ok((train, val))
}

/// `train` with its copies turned by `cfg.rotations` over `reference_pins`;
/// `None` without rotations.
fn turned_training_data(
    cfg: &ModelConfig,
    outputs: &[ModelTarget],
    train: &Dataset,
    reference_pins: Option<&[[f64; 2]]>,
) -> Result<Option<Dataset>, LearnError> {
    let Some(rot) = &cfg.rotations else {
        return Ok(None);
    };
    let pins = reference_pins.ok_or_else(|| LearnError::Config {
        field: "rotations",
        reason: "turned copies of the taps need the reference pins".into(),
    })?;
    rotations::turned_copies(train, outputs, rot, pins).map(Some)
}

/// The feature map `kind` needs over `reference_pins` for inputs of
/// `dim_x` values; `None` for the displacements themselves.
fn feature_map(
    kind: PinFeatures,
    reference_pins: Option<&[[f64; 2]]>,
    dim_x: usize,
) -> Result<Option<FeatureMap>, LearnError> {
    if kind.is_displacements() {
        return Ok(None);
    }
    let pins = reference_pins.ok_or_else(|| LearnError::Config {
        field: "pin_features",
        reason: "features beyond the displacements need the reference pins".into(),
    })?;
    if 2 * pins.len() != dim_x {
        return Err(LearnError::DimensionMismatch {
            expected: 2 * pins.len(),
            got: dim_x,
        });
    }
    FeatureMap::new(kind, pins).map(Some)
}
