//! Image models (`conv-dennn`, `conv-mlp`): the `ImageModel` class over
//! `tactrace_store::StoredImageModel` and `tactrace_lab::train_image`, as
//! `tactrace train --model conv-dennn|conv-mlp`, `validate` and `predict`
//! use them. `load_model` and `train` (model.rs) hand one back for an
//! image model's folder or kind.
use crate::arrays::{contiguous, json_to_py, serde_to_py, shape_text, to_matrix};
use crate::errors::{input, lab, store};
use crate::interrupt::{checkpoint, run_detached};
use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use tactrace_convnet::TrainingHistory;
use tactrace_lab::image_fit::{fit_fresh_image, store_fitted_image, FreshImage};
use tactrace_lab::train_image as ti;
use tactrace_lab::train_sets::TrainingSets;
use tactrace_store::{LoadedModel, StoredImageModel};

/// A trained image model: grey frames (uint8) in, its N targets out.
#[pyclass(module = "tactrace", frozen)]
pub struct ImageModel {
    stored: StoredImageModel,
    history: TrainingHistory,
}

impl ImageModel {
    pub(crate) fn new(stored: StoredImageModel) -> Self {
        Self {
            stored,
            history: TrainingHistory::default(),
        }
    }

    /// The model with its input recipe and training record.
    pub(crate) fn stored(&self) -> &StoredImageModel {
        &self.stored
    }

    /// The model with its turned views at prediction switched as `views`
    /// says (as it is when `None`); refused, naming the model, for one
    /// fitted without rotations.
    fn with_views(&self, views: Option<bool>) -> PyResult<Cow<'_, StoredImageModel>> {
        let Some(on) = views else {
            return Ok(Cow::Borrowed(&self.stored));
        };
        let mut stored = self.stored.clone();
        stored.set_turned_views(on).map_err(store)?;
        Ok(Cow::Owned(stored))
    }
}

#[pymethods]
impl ImageModel {
    /// Every target for each frame: ``frames`` is one H x W grey frame or
    /// an N x H x W stack (any dtype, used as uint8), of any size: each is
    /// area-averaged to the model's input (as ``frames.npy`` was made from
    /// the frames the pin detector sees). Returns N x T float64 (one row
    /// for one frame), in ``targets``' order and units. ``views`` as
    /// ``Model.predict``'s: with / without the mean over each frame's turned
    /// views (None: as the model's file says).
    #[pyo3(signature = (frames, *, views = None))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        frames: &Bound<'py, PyAny>,
        views: Option<bool>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let a = contiguous::<u8>(frames, "uint8", "frames")?;
        let shape = a.shape().to_vec();
        let (n, h, w) = match shape[..] {
            [h, w] => (1, h, w),
            [n, h, w] => (n, h, w),
            _ => {
                return Err(input(format!(
                    "frames must be an H x W frame or an N x H x W stack, got shape {}",
                    shape_text(&shape)
                )))
            }
        };
        if h == 0 || w == 0 {
            return Err(input("frames: empty frames"));
        }
        let pixels = a.to_vec().map_err(|e| input(format!("frames: {e}")))?;
        let stored = self.with_views(views)?;
        let net = stored.model();
        let (ih, iw) = net.input_size();
        let t = net.outputs().len();
        let out = run_detached(py, || -> Result<Vec<f64>, tactrace_learn::LearnError> {
            let mut out = Vec::with_capacity(n * t);
            for frame in pixels.chunks_exact(h * w) {
                let small = tactrace_convnet::area_resample(frame, (h, w), (ih, iw));
                out.extend(net.predict_targets(&small)?);
            }
            Ok(out)
        })?
        .map_err(|e| lab(e.into()))?;
        to_matrix(py, out, n, t)
    }

    /// Mean absolute errors on the dataset folder ``data`` (with
    /// ``frames.npy``, from ``import --frames-size``) as ``tactrace
    /// validate --json`` gives them: ``position_mae_mm``,
    /// ``angle_mae_deg``, ``per_target``, ``samples``,
    /// ``rows_seen_in_training`` and, for a model fitted with rotations,
    /// ``turned_views``. ``views`` as ``predict``'s.
    #[pyo3(signature = (data, *, views = None))]
    fn validate<'py>(
        &self,
        py: Python<'py>,
        data: PathBuf,
        views: Option<bool>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let loaded = LoadedModel::Image(self.with_views(views)?.into_owned());
        let v = py
            .detach(|| {
                let d = tactrace_store::read_dataset(&data)?;
                ti::validate_loaded(&loaded, &d, &data, None)
            })
            .map_err(lab)?;
        if let Some(w) = v.seen_warning() {
            crate::follow::warn(py, &w)?;
        }
        serde_to_py(py, &v)
    }

    /// What the model predicts, in order: dicts with ``name``, ``unit``,
    /// ``circular`` and ``role`` when marked.
    #[getter]
    fn targets<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, self.stored.model().outputs())
    }

    /// "conv-dennn" or "conv-mlp".
    #[getter]
    fn kind(&self) -> &'static str {
        self.stored.model().kind_name()
    }

    /// The frame size the network takes, ``(height, width)`` px.
    #[getter]
    fn input_size(&self) -> (usize, usize) {
        self.stored.model().input_size()
    }

    /// The network's configuration and seed, as in its ``model.json``.
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let net = self.stored.model().network();
        let mut v = serde_json::to_value(net.config()).map_err(|e| input(e.to_string()))?;
        if let Some(o) = v.as_object_mut() {
            o.insert("seed".into(), net.seed().into());
        }
        json_to_py(py, &v)
    }

    /// Which rows of which dataset it was trained on (``training.json``),
    /// or None.
    #[getter]
    fn training<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.stored
            .training()
            .map(|t| serde_to_py(py, t))
            .transpose()
    }

    /// The per-epoch history of a model trained in this session (empty for
    /// a loaded one: its folder has history.csv).
    #[getter]
    fn history<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        serde_to_py(py, &self.history.epochs)
    }

    /// Write the model folder ``tactrace train`` writes; an existing
    /// non-empty folder is refused unless ``force=True``.
    #[pyo3(signature = (dir, *, force = false))]
    fn save(&self, py: Python<'_>, dir: PathBuf, force: bool) -> PyResult<PathBuf> {
        py.detach(|| ti::save_image_model(&dir, &self.stored, &self.history, force, &[]))
            .map_err(lab)
    }

    fn __repr__(&self) -> String {
        let (h, w) = self.stored.model().input_size();
        format!(
            "ImageModel(kind='{}', input={h}x{w}, source='{}')",
            self.kind(),
            self.stored.source().display()
        )
    }
}

/// Load an image model folder (`load_model` of an image model's folder).
pub(crate) fn load(py: Python<'_>, dir: &Path) -> PyResult<ImageModel> {
    let stored = py.detach(|| StoredImageModel::load(dir)).map_err(store)?;
    Ok(ImageModel::new(stored))
}

/// `train` of an image model `kind` on the dataset folders `dirs` (with
/// frames.npy; several joined in order), as `tactrace train --model
/// conv-dennn|conv-mlp` does.
pub(crate) fn train(
    py: Python<'_>,
    kind: tactrace_convnet::ModelKind,
    dirs: &[PathBuf],
    (config, epochs, seed): (Option<&str>, Option<usize>, Option<u64>),
    held_out: Option<(f64, u64)>,
) -> PyResult<ImageModel> {
    let (cfg, base) = ti::resolve_image_settings(kind, config, epochs).map_err(lab)?;
    let sets = py.detach(|| TrainingSets::read(dirs)).map_err(lab)?;
    let frames = py.detach(|| sets.frames()).map_err(lab)?;
    let split = sets.split(held_out).map_err(lab)?;
    let train_frames = frames.subset(&split.record.train_rows);
    let val_frames = split.record.split.as_ref().map(|s| frames.subset(&s.rows));
    let val = split.val.as_ref().zip(val_frames.as_ref());
    let in_first = split.record.in_first_dataset();
    let fresh = FreshImage {
        cfg: &cfg,
        base: base.as_ref(),
        seed: seed.unwrap_or(0),
        in_first: &in_first,
    };
    let data = (&split.train, &train_frames);
    let fitted = run_detached(py, || {
        fit_fresh_image(fresh, data, val, &mut |_| checkpoint())
    })?;
    let (model, history, folds) = fitted.map_err(lab)?;
    let pins = sets.data.meta.reference_pins.clone();
    let stored = store_fitted_image(model, folds, frames.info.clone(), split.record, pins);
    Ok(ImageModel { stored, history })
}
