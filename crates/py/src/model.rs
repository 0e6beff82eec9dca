//! Pose models: `load_model`, `train` and the `Model` class over
//! `tactrace_store::StoredModel` and `tactrace_lab::train`, as
//! `tactrace train` / `validate` / `predict` use them.
use crate::arrays::{points_array, py_to_json, serde_to_py, to_matrix};
use crate::errors::{core, input, lab, store};
use crate::interrupt::{checkpoint, run_detached};
use crate::samples::Samples;
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use tactrace_lab::train::Validation;
use tactrace_lab::train_sets::TrainingSets;
use tactrace_learn::{ModelKind, PoseModel, Preset, TrainingHistory};
use tactrace_store::StoredModel;

/// Rows predicted between two Ctrl-C checks.
const ROWS_PER_CHECK: usize = 4096;

/// A trained pose model with the reference pins of its training data:
/// displacement vectors (pins in ``reference_pins`` order) in, edge pose
/// ``(r mm, theta deg)`` out.
#[pyclass(module = "tactrace", frozen)]
pub struct Model {
    pub(crate) stored: StoredModel,
    /// The network, reached once through the pin-order check against the
    /// model's own pins.
    net: PoseModel,
    /// The last reference pins that passed the check (the check costs
    /// ~0.3 ms: a loop predicting one vector at a time with the same pins
    /// pays it once).
    accepted: Mutex<Vec<[f64; 2]>>,
    history: TrainingHistory,
    validation: Option<tactrace_lab::train::Validation>,
}

impl Model {
    /// A model and the network of it, for the model's own pins.
    fn new(
        stored: StoredModel,
        history: TrainingHistory,
        validation: Option<tactrace_lab::train::Validation>,
    ) -> PyResult<Self> {
        let net = stored
            .for_pins(stored.reference_pins(), Path::new("the model"))
            .map_err(store)?
            .clone();
        Ok(Self {
            accepted: Mutex::new(stored.reference_pins().to_vec()),
            stored,
            net,
            history,
            validation,
        })
    }

    /// The network, for samples ordered against `samples.pins`: refused
    /// when they are ordered otherwise than the model's training data.
    /// The model's net for `samples` (as [`Self::net_for`]) and the
    /// samples' width, refused unless it is the net's input width.
    fn net_taking(&self, samples: &Samples) -> PyResult<(&PoseModel, usize)> {
        let net = self.net_for(samples)?;
        let cols = samples.cols;
        if cols != net.input_dim() {
            return Err(input(format!(
                "the model takes {} inputs per sample (2 x {} pins), inputs has {cols}",
                net.input_dim(),
                net.input_dim() / 2
            )));
        }
        Ok((net, cols))
    }

    fn net_for(&self, samples: &Samples) -> PyResult<&PoseModel> {
        let mut accepted = self.accepted.lock().unwrap_or_else(|e| e.into_inner());
        if *accepted != samples.pins {
            self.stored
                .for_pins(&samples.pins, &samples.what)
                .map_err(store)?;
            accepted.clone_from(&samples.pins);
        }
        Ok(&self.net)
    }

    /// Every target for each sample of `data` (N x T, or (T,) for one row).
    fn predict_all<'py>(
        &self,
        py: Python<'py>,
        data: &Bound<'py, PyAny>,
        reference_pins: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let samples = Samples::read(data, None, reference_pins, false)?;
        let (net, cols) = self.net_taking(&samples)?;
        let t = net.outputs().len();
        let flat = &samples.inputs;
        let out = run_detached(py, || {
            let mut out = Vec::with_capacity(samples.rows * t);
            for (i, row) in flat.chunks_exact(cols).enumerate() {
                if i % ROWS_PER_CHECK == ROWS_PER_CHECK - 1 {
                    checkpoint();
                }
                out.extend(net.predict_targets(row)?);
            }
            Ok::<_, tactrace_learn::LearnError>(out)
        })?
        .map_err(core)?;
        let arr = to_matrix(py, out, samples.rows, t)?;
        if samples.one_row {
            return arr.reshape(vec![t]);
        }
        Ok(arr)
    }

    /// The network, for the model's own pins (configuration, kind).
    fn own_net(&self) -> &PoseModel {
        &self.net
    }

    /// `net` with its turned views at prediction switched as `views` says
    /// (as it is when `None`); refused, naming the model, for a model
    /// fitted without rotations or reflections (the CLI's `--views`).
    fn with_views<'a>(
        &self,
        net: &'a PoseModel,
        views: Option<bool>,
    ) -> PyResult<Cow<'a, PoseModel>> {
        let Some(on) = views else {
            return Ok(Cow::Borrowed(net));
        };
        let mut switched = self.stored.clone();
        switched.set_turned_views(on).map_err(store)?;
        let own = self.stored.reference_pins();
        let net = switched.into_model_for(own, Path::new("the model"));
        Ok(Cow::Owned(net.map_err(store)?))
    }

    /// A validation of `samples`, with the training rows among them
    /// counted when the model knows what it was trained on.
    fn validation_of(
        &self,
        py: Python<'_>,
        samples: &Samples,
        views: Option<bool>,
    ) -> PyResult<Validation> {
        let net = self.with_views(self.net_for(samples)?, views)?;
        let data = samples.to_tap_data()?;
        let mut v =
            run_detached(py, || tactrace_lab::train::validate_net(&net, &data))?.map_err(lab)?;
        v.rows_seen_in_training = self.stored.training().map(|t| t.rows_seen(&data));
        Ok(v)
    }
}

#[pymethods]
impl Model {
    /// Predict ``(r mm, theta deg)`` for each sample of ``data``: a dataset
    /// folder, the ``(inputs, targets, meta)`` tuple ``load_dataset``
    /// returns, or an N x 2P array (any dtype, used as float32 like the
    /// CLI; pixels) with ``reference_pins``, the P x 2 pins (px) its
    /// columns are ordered by (``meta["reference_pins"]``,
    /// ``PinExtractor.reference_pins``). Data ordered otherwise than the
    /// model's training data is refused, and so are arrays without
    /// ``reference_pins``. A single row (2P,) gives a (2,) array, else an N
    /// x 2 float64 array. ``views=True`` / ``False`` predicts with / without
    /// the mean over each sample's turned views (a model fitted on turned
    /// copies; or the sample and its mirror copy, for a model fitted on
    /// mirror copies; the CLI's ``--views on|off``); None, the default, as
    /// the model's file says. Refused for a model fitted with neither.
    #[pyo3(signature = (data, *, reference_pins = None, views = None))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        data: &Bound<'py, PyAny>,
        reference_pins: Option<&Bound<'py, PyAny>>,
        views: Option<bool>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let samples = Samples::read(data, None, reference_pins, false)?;
        let (net, cols) = self.net_taking(&samples)?;
        let net = self.with_views(net, views)?;
        let flat = &samples.inputs;
        let out = run_detached(py, || predict_rows(&net, flat, cols))?.map_err(core)?;
        let arr = to_matrix(py, out, samples.rows, 2)?;
        if samples.one_row {
            return arr.reshape(vec![2]);
        }
        Ok(arr)
    }

    /// Predict every target of the model (``Model.targets``: names, units,
    /// circular flags) for each sample of ``data`` (as ``predict``): an N
    /// x T float64 array in the targets' units (circular angles within
    /// (-180, 180] deg), or (T,) for a single row. With ``named=True`` a
    /// dict instead: each target's column name -> its (N,) array (a float
    /// for a single row), in the model's order.
    #[pyo3(signature = (data, *, reference_pins = None, named = false))]
    fn predict_targets<'py>(
        &self,
        py: Python<'py>,
        data: &Bound<'py, PyAny>,
        reference_pins: Option<&Bound<'py, PyAny>>,
        named: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let arr = self.predict_all(py, data, reference_pins)?;
        if !named {
            return Ok(arr.into_any());
        }
        let dict = pyo3::types::PyDict::new(py);
        let one_row = arr.ndim() == 1;
        for (k, target) in self.own_net().outputs().iter().enumerate() {
            let column = match one_row {
                true => arr.get_item(k)?,
                false => arr.get_item((pyo3::types::PySlice::full(py), k))?,
            };
            dict.set_item(&target.name, column)?;
        }
        Ok(dict.into_any())
    }

    /// What the model predicts, in order: a list of dicts with ``name``
    /// (the label column), ``unit`` (``"mm"`` or ``"deg"``) and
    /// ``circular`` (an angle over the full circle, learnt as sine and
    /// cosine, its errors wrapped), and ``role`` (``"position"`` or
    /// ``"angle"``) when the import marked it.
    #[getter]
    fn targets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, self.own_net().outputs())
    }

    /// Mean absolute errors on ``data`` as ``tactrace validate --json``
    /// gives them: a dict with ``position_mae_mm``, ``angle_mae_deg``,
    /// ``per_target`` (every target's ``mae``, ``unit``, ``circular``, by
    /// its column; circular errors wrapped), ``samples`` and ``rows_seen_in_training`` (how many samples the
    /// model was trained on; None when its folder does not say). ``data``
    /// is a dataset folder, ``load_dataset``'s tuple, or an N x 2P array
    /// with ``targets`` (N x 2: r mm, theta deg) and ``reference_pins``
    /// (as ``predict``). Warns (``UserWarning``) when some samples were
    /// training rows. ``views`` as ``predict``'s; the result says which
    /// (``turned_views``, for a model fitted with rotations).
    #[pyo3(signature = (data, targets = None, *, reference_pins = None, views = None))]
    fn validate<'py>(
        &self,
        py: Python<'py>,
        data: &Bound<'py, PyAny>,
        targets: Option<&Bound<'py, PyAny>>,
        reference_pins: Option<&Bound<'py, PyAny>>,
        views: Option<bool>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let samples = Samples::read(data, targets, reference_pins, true)?;
        let v = self.validation_of(py, &samples, views)?;
        if let Some(w) = v.seen_warning() {
            crate::follow::warn(py, &w)?;
        }
        serde_to_py(py, &v)
    }

    /// Which rows of which dataset the model was trained on (the model
    /// folder's ``training.json`` as a dict: the dataset's content hash,
    /// ``train_rows``, the held-out ``split``, ``row_hashes``, the image
    /// names of real frames), or None for a folder that does not record it.
    #[getter]
    fn training<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.stored
            .training()
            .map(|t| serde_to_py(py, t))
            .transpose()
    }

    /// The training data's reference pins, P x 2 float64 (px): the order
    /// every input vector lists its pins in.
    #[getter]
    fn reference_pins<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        points_array(py, self.stored.reference_pins())
    }

    /// The model's configuration (kind, epochs, seed, nets), as in its
    /// ``model.json``.
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let net = self.own_net();
        serde_to_py(py, net.config())
    }

    /// The kind of model ("pdennn", "pcadennn", "disdennn" or "mlp").
    #[getter]
    fn kind(&self) -> PyResult<&'static str> {
        Ok(kind_name(self.own_net().kind()))
    }

    /// Number of inputs per sample (2 x pins).
    #[getter]
    fn input_dim(&self) -> PyResult<usize> {
        Ok(self.own_net().input_dim())
    }

    /// The per-epoch training history (a list of dicts) of a model trained
    /// in this session; empty for a loaded one (its folder has history.csv).
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.history.epochs)
    }

    /// The held-out validation of ``train(..., val_fraction=f)``, as
    /// ``validate`` gives it, or None.
    #[getter]
    fn validation<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.validation
            .as_ref()
            .map(|v| serde_to_py(py, v))
            .transpose()
    }

    /// Write the model folder ``tactrace train`` writes (model.json,
    /// weights.safetensors, pins.json, training.json when what it was
    /// trained on is known, history.csv, the loss figure); it appears only
    /// when complete; an existing non-empty folder is refused unless
    /// ``force=True``. Returns the folder's path.
    #[pyo3(signature = (dir, *, force = false))]
    fn save(&self, py: Python<'_>, dir: PathBuf, force: bool) -> PyResult<PathBuf> {
        py.detach(|| tactrace_lab::train::save_model(&dir, &self.stored, &self.history, force, &[]))
            .map_err(lab)
    }

    fn __repr__(&self) -> PyResult<String> {
        let net = self.own_net();
        Ok(format!(
            "Model(kind='{}', pins={}, source='{}')",
            kind_name(net.kind()),
            self.stored.reference_pins().len(),
            self.stored.source().display()
        ))
    }
}

/// Predict every row of `flat` (rows of `cols`), a block of
/// [`ROWS_PER_CHECK`] rows at a time through the batched path, checking
/// for Ctrl-C between blocks; a non-finite value is named by its row in
/// `flat`.
fn predict_rows(
    net: &PoseModel,
    flat: &[f32],
    cols: usize,
) -> Result<Vec<f64>, tactrace_learn::LearnError> {
    use tactrace_learn::LearnError;
    let mut out = Vec::with_capacity(flat.len() / cols.max(1) * 2);
    for (b, block) in flat.chunks(ROWS_PER_CHECK * cols.max(1)).enumerate() {
        if b > 0 {
            checkpoint();
        }
        let rows = net.predict_rows(block).map_err(|e| match e {
            LearnError::NonFinite {
                what,
                row,
                column,
                value,
            } => LearnError::NonFinite {
                what,
                row: row + b * ROWS_PER_CHECK,
                column,
                value,
            },
            e => e,
        })?;
        out.extend(rows.into_iter().flatten());
    }
    Ok(out)
}

fn kind_name(k: ModelKind) -> &'static str {
    match k {
        ModelKind::PDenNN => "pdennn",
        ModelKind::PcaDenNN => "pcadennn",
        ModelKind::DisDenNN => "disdennn",
        ModelKind::Mlp => "mlp",
    }
}

fn parse_kind(s: &str) -> PyResult<ModelKind> {
    match s.to_ascii_lowercase().as_str() {
        "pdennn" => Ok(ModelKind::PDenNN),
        "pcadennn" => Ok(ModelKind::PcaDenNN),
        "disdennn" => Ok(ModelKind::DisDenNN),
        "mlp" => Ok(ModelKind::Mlp),
        _ => Err(input(format!(
            "unknown model kind `{s}`: choose pdennn, pcadennn, disdennn or mlp (as `tactrace train --model`)"
        ))),
    }
}

fn parse_preset(s: &str) -> PyResult<Preset> {
    match s {
        "default" => Ok(Preset::Default),
        "report" => Ok(Preset::Report),
        _ => Err(input(format!(
            "unknown preset `{s}`: choose default or report"
        ))),
    }
}

/// The hyper-parameter overrides: a TOML file's path, or a dict of the
/// same keys.
fn config_text(config: Option<&Bound<'_, PyAny>>) -> PyResult<Option<String>> {
    let Some(c) = config else { return Ok(None) };
    if c.is_instance_of::<pyo3::types::PyDict>() {
        let v = py_to_json(c, "config")?;
        return toml::to_string(&v)
            .map(Some)
            .map_err(|e| input(format!("config: {e}")));
    }
    let path: PathBuf = c
        .extract()
        .map_err(|_| input("config must be a dict or the path of a TOML file"))?;
    tactrace_store::read_text(&path).map(Some).map_err(store)
}

/// Load a model folder written by ``tactrace train`` (or ``save``): a
/// ``Model`` (pin model), or an ``ImageModel`` for a conv-dennn or
/// conv-mlp folder.
#[pyfunction]
pub fn load_model(py: Python<'_>, dir: PathBuf) -> PyResult<Py<PyAny>> {
    if tactrace_store::image_model_dir::is_image_model_dir(&dir) {
        let m = crate::image_model::load(py, &dir)?;
        return Ok(Py::new(py, m)?.into_any());
    }
    let stored = py.detach(|| StoredModel::load(&dir)).map_err(store)?;
    Ok(Py::new(py, Model::new(stored, TrainingHistory::default(), None)?)?.into_any())
}

/// Train a pose model, as ``tactrace train`` does.
///
/// ``kind`` is one of "pdennn", "pcadennn", "disdennn", "mlp" (``train
/// --model``), or an image model's, "conv-dennn" or "conv-mlp": then
/// ``data`` is a dataset folder with frames (``import --frames-size``)
/// or a list of them,
/// ``config`` overrides the network's settings, ``seed`` seeds it (0 by
/// default), and an ``ImageModel`` is returned. ``data`` is a dataset folder,
/// a list of dataset folders (trained on as one, rows joined in order, as
/// ``train --train A --train B``: each must have the first's pins, targets
/// and frames), the ``(inputs, targets, meta)`` tuple ``load_dataset`` returns, or an N x 2P array of inputs
/// with ``targets`` (N x 2: r mm, theta deg) and ``reference_pins`` (P x 2
/// px, the pins the inputs are ordered by); any dtype (used as float32).
/// ``epochs`` overrides the preset's; ``seed`` the model seed (None: the
/// preset's, as the CLI); ``preset`` "default" or "report"; ``config`` a
/// dict or TOML path of hyper-parameter overrides (``train --config``).
/// ``val_fraction`` holds out that fraction (seeded by ``split_seed``, as
/// ``--val-fraction`` / ``--split-seed``): the model never sees it, and
/// ``Model.validation`` reports on it. The model records which rows it was
/// trained on (``Model.training``; ``Model.save`` writes it). The GIL is
/// released while training; Ctrl-C stops it after the current epoch.
#[pyfunction]
#[pyo3(signature = (kind, data, targets = None, reference_pins = None, *, epochs = None,
    seed = None, preset = "default", config = None, val_fraction = None, split_seed = 1))]
#[allow(clippy::too_many_arguments)]
pub fn train(
    py: Python<'_>,
    kind: &str,
    data: &Bound<'_, PyAny>,
    targets: Option<&Bound<'_, PyAny>>,
    reference_pins: Option<&Bound<'_, PyAny>>,
    epochs: Option<usize>,
    seed: Option<u64>,
    preset: &str,
    config: Option<&Bound<'_, PyAny>>,
    val_fraction: Option<f64>,
    split_seed: u64,
) -> PyResult<Py<PyAny>> {
    let text = config_text(config)?;
    if let Some(image) = image_kind(kind) {
        let dirs = dataset_folders(data).ok_or_else(|| {
            input(format!(
                "{kind} trains on a dataset folder with frames (frames.npy), or a list of them"
            ))
        })?;
        if preset != "default" || targets.is_some() || reference_pins.is_some() {
            return Err(input(format!(
                "{kind}: preset, targets and reference_pins are the pin models'"
            )));
        }
        let settings = (text.as_deref(), epochs, seed);
        let held_out = val_fraction.map(|f| (f, split_seed));
        let m = crate::image_model::train(py, image, &dirs, settings, held_out)?;
        return Ok(Py::new(py, m)?.into_any());
    }
    let mut cfg = tactrace_lab::train::resolve_config(
        parse_kind(kind)?,
        parse_preset(preset)?,
        text.as_deref(),
        epochs,
    )
    .map_err(lab)?;
    if let Some(s) = seed {
        cfg.seed = s;
    }
    let held_out = val_fraction.map(|f| (f, split_seed));
    let list = data.is_instance_of::<pyo3::types::PyList>();
    let (samples, split) = match dataset_folders(data).filter(|_| list) {
        Some(dirs) => {
            if targets.is_some() || reference_pins.is_some() {
                return Err(input(
                    "targets and reference_pins are given with arrays only: a dataset carries \
                     its own",
                ));
            }
            let sets = py.detach(|| TrainingSets::read(&dirs)).map_err(lab)?;
            let split = sets.split(held_out).map_err(lab)?;
            (Samples::from_tap_data(sets.data, None), split)
        }
        None => {
            let samples = Samples::read(data, targets, reference_pins, true)?;
            let all = samples.to_tap_data()?;
            let folder = samples.folder.as_deref();
            let split = tactrace_lab::train::training_split(&all, folder, held_out).map_err(lab)?;
            (samples, split)
        }
    };
    let (data, val) = (&split.train, split.val.as_ref());
    let fitted = run_detached(py, || {
        tactrace_lab::train::train_with_validation(&cfg, data, val, &mut |_| checkpoint())
    })?;
    let (model, history) = fitted.map_err(lab)?;
    let stored = StoredModel::new(model, samples.pins.clone()).with_training(split.record);
    let mut m = Model::new(stored, history, None)?;
    if let Some(v) = val {
        let samples = Samples::from_tap_data(v.clone(), None);
        m.validation = Some(m.validation_of(py, &samples, None)?);
    }
    Ok(Py::new(py, m)?.into_any())
}

/// The dataset folders `data` names: one folder, or a list of them
/// (trained on as one, `train --train A --train B`); `None` for anything
/// else (arrays, `load_dataset`'s tuple).
fn dataset_folders(data: &Bound<'_, PyAny>) -> Option<Vec<PathBuf>> {
    if data.is_instance_of::<pyo3::types::PyList>() {
        return data
            .extract::<Vec<PathBuf>>()
            .ok()
            .filter(|d| !d.is_empty());
    }
    data.extract::<PathBuf>().ok().map(|d| vec![d])
}

/// The image model of `kind`, if it names one.
fn image_kind(kind: &str) -> Option<tactrace_convnet::ModelKind> {
    use tactrace_convnet::ModelKind as K;
    [K::ConvDennn, K::ConvMlp]
        .into_iter()
        .find(|k| k.name() == kind)
}
