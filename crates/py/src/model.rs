//! Pose models: `load_model`, `train` and the `Model` class over
//! `tactrace_store::StoredModel` and `tactrace_lab::train`, as
//! `tactrace train` / `validate` / `predict` use them.
use crate::arrays::{json_to_py, matrix, points, points_array, py_to_json, to_matrix};
use crate::errors::{core, input, lab, store};
use crate::interrupt::{checkpoint, run_detached};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use tactrace_learn::{ModelKind, PoseModel, Preset, TrainingHistory};
use tactrace_store::{DatasetMeta, StoredModel, TapData};

/// Rows predicted between two Ctrl-C checks.
const ROWS_PER_CHECK: usize = 4096;

/// A trained pose model with the reference pins of its training data:
/// displacement vectors (pins in ``reference_pins`` order) in, edge pose
/// ``(r mm, theta deg)`` out.
#[pyclass(module = "tactrace", frozen)]
pub struct Model {
    pub(crate) stored: StoredModel,
    /// The network, reached once through the pin-order check against the
    /// model's own pins (the check costs ~0.3 ms: not on every call).
    net: PoseModel,
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
            stored,
            net,
            history,
            validation,
        })
    }

    /// The network, after checking `pins` (if given) against the model's.
    fn net(&self, pins: Option<&Bound<'_, PyAny>>) -> PyResult<&PoseModel> {
        if let Some(p) = pins {
            let pins = points(p, "reference_pins")?;
            self.stored
                .for_pins(&pins, Path::new("reference_pins"))
                .map_err(store)?;
        }
        Ok(&self.net)
    }
}

#[pymethods]
impl Model {
    /// Predict ``(r mm, theta deg)`` for each row of ``inputs`` (N x 2P, any
    /// dtype, used as float32 like the CLI; pixels, ordered like
    /// ``reference_pins``). A single row (2P,) gives a (2,) array, else an
    /// N x 2 float64 array. With ``reference_pins`` (those of the data, e.g.
    /// ``meta["reference_pins"]``) data ordered otherwise is refused.
    #[pyo3(signature = (inputs, *, reference_pins = None))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        inputs: &Bound<'py, PyAny>,
        reference_pins: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let net = self.net(reference_pins)?;
        let (x, rows, cols) = matrix::<f32>(inputs, "float32", "inputs", None, true)?;
        if cols != net.input_dim() {
            return Err(input(format!(
                "the model takes {} inputs per sample (2 x {} pins), inputs has {cols}",
                net.input_dim(),
                net.input_dim() / 2
            )));
        }
        let ro = x.readonly();
        let flat = ro.as_slice()?;
        let out = run_detached(py, || predict_rows(net, flat, cols))?.map_err(core)?;
        let one_row = x.ndim() == 1;
        let arr = to_matrix(py, out, rows, 2)?;
        if one_row {
            return arr.reshape(vec![2]);
        }
        Ok(arr)
    }

    /// Mean absolute errors on ``(inputs, targets)`` as ``tactrace
    /// validate --json`` gives them: a dict with ``position_mae_mm``,
    /// ``angle_mae_deg`` and ``samples``.
    #[pyo3(signature = (inputs, targets, *, reference_pins = None))]
    fn validate<'py>(
        &self,
        py: Python<'py>,
        inputs: &Bound<'py, PyAny>,
        targets: &Bound<'py, PyAny>,
        reference_pins: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let net = self.net(reference_pins)?;
        let data = tap_data(inputs, targets, self.stored.reference_pins())?;
        let v = run_detached(py, || tactrace_lab::train::validate_net(net, &data))?.map_err(lab)?;
        json_to_py(
            py,
            &serde_json::to_value(&v).map_err(|e| input(e.to_string()))?,
        )
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
        let net = self.net(None)?;
        let v = serde_json::to_value(net.config()).map_err(|e| input(e.to_string()))?;
        json_to_py(py, &v)
    }

    /// The kind of model ("pdennn", "pcadennn", "disdennn" or "mlp").
    #[getter]
    fn kind(&self) -> PyResult<&'static str> {
        Ok(kind_name(self.net(None)?.kind()))
    }

    /// Number of inputs per sample (2 x pins).
    #[getter]
    fn input_dim(&self) -> PyResult<usize> {
        Ok(self.net(None)?.input_dim())
    }

    /// The per-epoch training history (a list of dicts) of a model trained
    /// in this session; empty for a loaded one (its folder has history.csv).
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(&self.history.epochs).map_err(|e| input(e.to_string()))?;
        json_to_py(py, &v)
    }

    /// The held-out validation of ``train(..., val_fraction=f)``, as
    /// ``validate`` gives it, or None.
    #[getter]
    fn validation<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.validation
            .as_ref()
            .map(|v| {
                json_to_py(
                    py,
                    &serde_json::to_value(v).map_err(|e| input(e.to_string()))?,
                )
            })
            .transpose()
    }

    /// Write the model folder ``tactrace train`` writes (model.json,
    /// weights.safetensors, pins.json, history.csv, the loss figure); it
    /// appears only when complete; an existing non-empty folder is refused
    /// unless ``force=True``. Returns the folder's path.
    #[pyo3(signature = (dir, *, force = false))]
    fn save(&self, py: Python<'_>, dir: PathBuf, force: bool) -> PyResult<PathBuf> {
        let net = self.net(None)?;
        let pins = self.stored.reference_pins();
        py.detach(|| tactrace_lab::train::save_model(&dir, net, pins, &self.history, force, &[]))
            .map_err(lab)
    }

    fn __repr__(&self) -> PyResult<String> {
        let net = self.net(None)?;
        Ok(format!(
            "Model(kind={:?}, pins={}, source={:?})",
            kind_name(net.kind()),
            self.stored.reference_pins().len(),
            self.stored.source().display().to_string()
        ))
    }
}

/// Predict every row of `flat` (rows of `cols`), checking for Ctrl-C.
fn predict_rows(
    net: &PoseModel,
    flat: &[f32],
    cols: usize,
) -> Result<Vec<f64>, tactrace_learn::LearnError> {
    let mut out = Vec::with_capacity(flat.len() / cols.max(1) * 2);
    for (i, row) in flat.chunks_exact(cols).enumerate() {
        if i % ROWS_PER_CHECK == ROWS_PER_CHECK - 1 {
            checkpoint();
        }
        out.extend(net.predict(row)?);
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
            "unknown model kind {s:?}: choose pdennn, pcadennn, disdennn or mlp (as `tactrace train --model`)"
        ))),
    }
}

fn parse_preset(s: &str) -> PyResult<Preset> {
    match s {
        "default" => Ok(Preset::Default),
        "report" => Ok(Preset::Report),
        _ => Err(input(format!(
            "unknown preset {s:?}: choose default or report"
        ))),
    }
}

/// Arrays as a dataset ordered against `pins`.
fn tap_data(
    inputs: &Bound<'_, PyAny>,
    targets: &Bound<'_, PyAny>,
    pins: &[[f64; 2]],
) -> PyResult<TapData> {
    let (x, n, d) = matrix::<f32>(inputs, "float32", "inputs", None, false)?;
    let (y, m, _) = matrix::<f32>(targets, "float32", "targets", Some(2), false)?;
    if n != m {
        return Err(input(format!(
            "inputs has {n} rows but targets has {m}: one target row per sample"
        )));
    }
    if d != 2 * pins.len() {
        return Err(input(format!(
            "inputs has {d} columns but there are {} reference pins (2 x pins)",
            pins.len()
        )));
    }
    let meta = DatasetMeta {
        source: "python".into(),
        origin: String::new(),
        seed: None,
        samples: n,
        pins: pins.len(),
        targets: ["r_mm".into(), "theta_deg".into()],
        frames_with_missing_pins: 0,
        reference_pins: pins.to_vec(),
        settings: serde_json::Value::Null,
        tactrace_version: tactrace_lab::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
    };
    Ok(TapData {
        inputs: x.readonly().as_slice()?.to_vec(),
        targets: y.readonly().as_slice()?.to_vec(),
        meta,
    })
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

/// Load a model folder written by ``tactrace train`` (or ``Model.save``).
#[pyfunction]
pub fn load_model(py: Python<'_>, dir: PathBuf) -> PyResult<Model> {
    let stored = py.detach(|| StoredModel::load(&dir)).map_err(store)?;
    Model::new(stored, TrainingHistory::default(), None)
}

/// Train a pose model, as ``tactrace train`` does.
///
/// ``kind`` is one of "pdennn", "pcadennn", "disdennn", "mlp" (``train
/// --model``); ``inputs`` N x 2P and ``targets`` N x 2 (r mm, theta deg),
/// any dtype (used as float32); ``reference_pins`` P x 2 px, the pins the
/// inputs are ordered by (``meta["reference_pins"]`` of ``load_dataset``).
/// ``epochs`` overrides the preset's; ``seed`` the model seed (None: the
/// preset's, as the CLI); ``preset`` "default" or "report"; ``config`` a
/// dict or TOML path of hyper-parameter overrides (``train --config``).
/// ``val_fraction`` holds out that fraction (seeded by ``split_seed``, as
/// ``--val-fraction`` / ``--split-seed``): the model never sees it, and
/// ``Model.validation`` reports on it. The GIL is released while training;
/// Ctrl-C stops it after the current epoch.
#[pyfunction]
#[pyo3(signature = (kind, inputs, targets, reference_pins, *, epochs = None, seed = None,
    preset = "default", config = None, val_fraction = None, split_seed = 1))]
#[allow(clippy::too_many_arguments)]
pub fn train(
    py: Python<'_>,
    kind: &str,
    inputs: &Bound<'_, PyAny>,
    targets: &Bound<'_, PyAny>,
    reference_pins: &Bound<'_, PyAny>,
    epochs: Option<usize>,
    seed: Option<u64>,
    preset: &str,
    config: Option<&Bound<'_, PyAny>>,
    val_fraction: Option<f64>,
    split_seed: u64,
) -> PyResult<Model> {
    let text = config_text(config)?;
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
    let pins = points(reference_pins, "reference_pins")?;
    let data = tap_data(inputs, targets, &pins)?;
    let (data, val) = match val_fraction {
        Some(f) => {
            let (tr, va) = tactrace_lab::train::holdout(&data, f, split_seed).map_err(lab)?;
            (tr, Some(va))
        }
        None => (data, None),
    };
    let fitted = run_detached(py, || {
        let (model, history) =
            tactrace_lab::train::train_with_validation(&cfg, &data, val.as_ref(), &mut |_| {
                checkpoint()
            })?;
        let validation = val
            .as_ref()
            .map(|v| tactrace_lab::train::validate_net(&model, v))
            .transpose()?;
        Ok::<_, tactrace_lab::LabError>((model, history, validation))
    })?;
    let (model, history, validation) = fitted.map_err(lab)?;
    Model::new(StoredModel::new(model, pins), history, validation)
}
