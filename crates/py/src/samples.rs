//! The samples a model is given, always with their pin order: a dataset
//! folder, the `(inputs, targets, meta)` tuple `load_dataset` returns, or
//! arrays with the `reference_pins` they are ordered by. There is no way
//! to hand a model inputs without saying which pins they list
//! (ARCHITECTURE invariant 7): arrays without `reference_pins` are
//! refused.
use crate::arrays::{matrix, points, py_to_json};
use crate::errors::{input, store};
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;
use tactrace_store::{DatasetMeta, TapData};

/// What to say when the pin order is missing.
const NEED_PINS: &str = "the pin order of the inputs is needed: give reference_pins= (the \
     pins they were extracted against: meta[\"reference_pins\"] of load_dataset, or \
     PinExtractor.reference_pins), or a dataset instead of arrays (a dataset folder, or \
     the (inputs, targets, meta) load_dataset returns); inputs in another pin order would \
     be read as nonsense";

/// Samples with their pin order.
pub struct Samples {
    /// N x D inputs, row-major (float32 as the CLI reads them).
    pub inputs: Vec<f32>,
    pub rows: usize,
    pub cols: usize,
    /// A single (D,) row was given.
    pub one_row: bool,
    /// N x 2 targets, when given.
    pub targets: Option<Vec<f32>>,
    /// The dataset's meta.json when a dataset was given (else a default
    /// one, source "python", made by [`Samples::to_tap_data`]).
    pub meta: Option<DatasetMeta>,
    /// The reference pins the inputs are ordered by (px).
    pub pins: Vec<[f64; 2]>,
    /// The dataset folder, when one was given.
    pub folder: Option<PathBuf>,
    /// What to name in a pin-order error.
    pub what: PathBuf,
}

impl Samples {
    /// Read `data` (a dataset folder, `load_dataset`'s tuple or an array)
    /// with `targets` and `reference_pins` for arrays; `need_targets`
    /// refuses arrays without targets.
    pub fn read(
        data: &Bound<'_, PyAny>,
        targets: Option<&Bound<'_, PyAny>>,
        reference_pins: Option<&Bound<'_, PyAny>>,
        need_targets: bool,
    ) -> PyResult<Self> {
        let given = |what: &str| {
            input(format!(
                "{what} are given with arrays only: a dataset carries its own"
            ))
        };
        if let Some(tuple) = dataset_tuple(data)? {
            if targets.is_some() || reference_pins.is_some() {
                return Err(given("targets and reference_pins"));
            }
            return Self::from_tuple(&tuple);
        }
        if let Ok(folder) = data.extract::<PathBuf>() {
            if targets.is_some() || reference_pins.is_some() {
                return Err(given("targets and reference_pins"));
            }
            let tap = data
                .py()
                .detach(|| tactrace_store::read_dataset(&folder))
                .map_err(store)?;
            return Ok(Self::from_tap_data(tap, Some(folder)));
        }
        let pins = reference_pins.ok_or_else(|| input(NEED_PINS))?;
        let pins = points(pins, "reference_pins")?;
        if need_targets && targets.is_none() {
            return Err(input(
                "targets are needed with input arrays (N x 2: r mm, theta deg)",
            ));
        }
        Self::from_arrays(data, targets, pins, None)
    }

    /// `(inputs, targets, meta)` as `load_dataset` returns it.
    fn from_tuple(tuple: &Bound<'_, PyTuple>) -> PyResult<Self> {
        let meta_obj = tuple.get_item(2)?;
        let meta = meta_from_dict(&meta_obj)?;
        let pins = meta.reference_pins.clone();
        let targets = tuple.get_item(1)?;
        let mut samples = Self::from_arrays(&tuple.get_item(0)?, Some(&targets), pins, Some(meta))?;
        samples.what = PathBuf::from("the dataset's meta[\"reference_pins\"]");
        Ok(samples)
    }

    fn from_arrays(
        inputs: &Bound<'_, PyAny>,
        targets: Option<&Bound<'_, PyAny>>,
        pins: Vec<[f64; 2]>,
        meta: Option<DatasetMeta>,
    ) -> PyResult<Self> {
        let (x, rows, cols) = matrix::<f32>(inputs, "float32", "inputs", None, true)?;
        let one_row = x.ndim() == 1;
        // A dataset's meta says how many targets a row has; arrays: r, theta.
        let width = meta.as_ref().map_or(2, |m| m.targets.len());
        let targets = match targets {
            Some(t) => {
                let (y, m, _) = matrix::<f32>(t, "float32", "targets", Some(width), false)?;
                if m != rows {
                    return Err(input(format!(
                        "inputs has {rows} rows but targets has {m}: one target row per sample"
                    )));
                }
                Some(y.readonly().as_slice()?.to_vec())
            }
            None => None,
        };
        if cols != 2 * pins.len() {
            return Err(input(format!(
                "inputs has {cols} columns but there are {} reference pins (2 x pins)",
                pins.len()
            )));
        }
        let inputs = x.readonly().as_slice()?.to_vec();
        Ok(Self {
            inputs,
            rows,
            cols,
            one_row,
            targets,
            meta,
            pins,
            folder: None,
            what: PathBuf::from("reference_pins"),
        })
    }

    /// A dataset read from `folder`.
    pub fn from_tap_data(tap: TapData, folder: Option<PathBuf>) -> Self {
        let (rows, cols) = (tap.len(), tap.dim());
        Self {
            pins: tap.meta.reference_pins.clone(),
            inputs: tap.inputs,
            rows,
            cols,
            one_row: false,
            targets: Some(tap.targets),
            meta: Some(tap.meta),
            what: folder.clone().unwrap_or_else(|| "reference_pins".into()),
            folder,
        }
    }

    /// As a dataset (targets needed), for validation and training.
    pub fn to_tap_data(&self) -> PyResult<TapData> {
        let targets = self
            .targets
            .clone()
            .ok_or_else(|| input("targets are needed (N x 2: r mm, theta deg)"))?;
        let mut meta = match &self.meta {
            Some(m) => m.clone(),
            None => python_meta(&self.pins),
        };
        meta.samples = self.rows;
        meta.pins = self.pins.len();
        if !meta.images.is_empty() && meta.images.len() != self.rows {
            return Err(input(format!(
                "meta lists {} images for {} samples",
                meta.images.len(),
                self.rows
            )));
        }
        Ok(TapData {
            inputs: self.inputs.clone(),
            targets,
            meta,
        })
    }
}

/// `data` as `load_dataset`'s `(inputs, targets, meta)` tuple, if it is a
/// 3-tuple whose last item is a dict.
fn dataset_tuple<'py>(data: &Bound<'py, PyAny>) -> PyResult<Option<Bound<'py, PyTuple>>> {
    let Ok(tuple) = data.cast::<PyTuple>() else {
        return Ok(None);
    };
    if tuple.len() == 3 && tuple.get_item(2)?.is_instance_of::<PyDict>() {
        return Ok(Some(tuple.clone()));
    }
    Ok(None)
}

/// A `meta` dict (as `load_dataset` returns it) as the dataset's meta.
fn meta_from_dict(meta: &Bound<'_, PyAny>) -> PyResult<DatasetMeta> {
    serde_json::from_value(py_to_json(meta, "meta")?).map_err(|e| {
        input(format!(
            "meta: {e} (the meta dict of load_dataset, with reference_pins)"
        ))
    })
}

/// The meta of arrays given from Python, ordered against `pins`.
pub fn python_meta(pins: &[[f64; 2]]) -> DatasetMeta {
    DatasetMeta {
        source: "python".into(),
        origin: String::new(),
        seed: None,
        samples: 0,
        pins: pins.len(),
        targets: vec!["r_mm".into(), "theta_deg".into()],
        target_columns: Default::default(),
        frames_with_missing_pins: 0,
        reference_pins: pins.to_vec(),
        settings: serde_json::Value::Null,
        tactrace_version: tactrace_lab::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
        tracking: tactrace_store::TrackTotals::default(),
    }
}
