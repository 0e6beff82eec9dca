//! Contour following in the simulated world: `follow` over
//! `tactrace_lab::follow::follow_simulated`, as `tactrace follow` runs it,
//! and what `follow_rig` shares with it (model, shape and configuration
//! arguments, the result dict).
use crate::arrays::{matrix, py_to_json};
use crate::errors::{input, lab, store};
use crate::interrupt::{checkpoint, run_detached};
use crate::model::Model;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::path::PathBuf;
use tactrace_geometry::{Contour, ShapeSpec, Vec2};
use tactrace_lab::follow::{follow_simulated, size_warning, FollowOutcome, SimFollowConfig};
use tactrace_store::StoredModel;

/// A model argument: a `Model` or the path of a model folder.
pub fn stored_model(obj: &Bound<'_, PyAny>) -> PyResult<StoredModel> {
    if let Ok(m) = obj.cast::<Model>() {
        return Ok(m.get().stored.clone());
    }
    let dir: PathBuf = obj
        .extract()
        .map_err(|_| input("model must be a Model or the path of a model folder"))?;
    StoredModel::load(&dir).map_err(store)
}

/// A shape argument: a built-in name ("disk", "flower", "trine",
/// "teardrop"), the path of a CSV of x,y points (mm), or an N x 2 array
/// (mm). Returns its name and contour.
pub fn shape_contour(obj: &Bound<'_, PyAny>) -> PyResult<(String, Contour)> {
    if obj.is_instance_of::<PyString>() || obj.extract::<PathBuf>().is_ok() {
        let text: PathBuf = obj.extract()?;
        let spec = ShapeSpec::parse(&text.to_string_lossy());
        let contour = tactrace_store::load_shape(&spec).map_err(store)?;
        return Ok((spec.name(), contour));
    }
    let (a, _, _) = matrix::<f64>(obj, "float64", "shape", Some(2), false)?;
    let ro = a.readonly();
    let vertices = ro
        .as_slice()?
        .chunks_exact(2)
        .map(|p| Vec2::new(p[0], p[1]))
        .collect();
    let contour = Contour::new(vertices).map_err(crate::errors::core)?;
    Ok(("array".into(), contour))
}

/// A follow configuration: the defaults, then a TOML file (path) or a dict
/// of the same tables (rig, controller, follow, start), then `steps` and
/// `seed`.
pub fn follow_config(
    config: Option<&Bound<'_, PyAny>>,
    steps: Option<usize>,
    seed: Option<u64>,
) -> PyResult<SimFollowConfig> {
    let mut cfg: SimFollowConfig = match config {
        None => SimFollowConfig::default(),
        Some(c) if c.is_instance_of::<PyDict>() => {
            let text = toml::to_string(&py_to_json(c, "config")?)
                .map_err(|e| input(format!("config: {e}")))?;
            tactrace_store::overlay(&SimFollowConfig::default(), &text, "follow configuration")
                .map_err(store)?
        }
        Some(c) => {
            let path: PathBuf = c
                .extract()
                .map_err(|_| input("config must be a dict or the path of a TOML file"))?;
            tactrace_store::load_config(Some(&path), "follow configuration").map_err(store)?
        }
    };
    if steps.is_some() {
        cfg.follow.steps = steps;
    }
    if let Some(s) = seed {
        cfg.follow.seed = s;
    }
    Ok(cfg)
}

/// Where a run folder goes: `out`, or a temporary folder removed after.
pub fn run_dir(out: Option<PathBuf>) -> PyResult<(PathBuf, Option<tempfile::TempDir>)> {
    match out {
        Some(p) => Ok((p, None)),
        None => {
            let tmp = tempfile::tempdir()
                .map_err(|e| input(format!("cannot make a temporary run folder: {e}")))?;
            Ok((tmp.path().join("run"), Some(tmp)))
        }
    }
}

/// Follow a contour with the simulated rig, as ``tactrace follow``.
///
/// ``model``: a ``Model`` or a model folder; ``shape``: a built-in name
/// ("flower", ...), a CSV path or an N x 2 array (mm); ``out``: the run
/// folder to write (config.toml, trajectory.csv, metrics.json, figures; as
/// the CLI's ``--out``), or None for none; ``steps``, ``seed`` and
/// ``config`` (a TOML path or a dict of its tables) as the CLI's flags.
/// Returns a dict with the keys of metrics.json (``mean_l2_mm``,
/// ``closed``, ``steps``, ``coverage``, ``ending``, ``succeeded``, ...), the
/// trajectory as arrays (``x_mm``, ``y_mm``, ``angle_deg``, ``r_pred_mm``,
/// ``theta_pred_deg``, ``mean_displacement_px``, ``contact``), ``l2_curve``
/// and ``dir`` (the run folder or None). A run that did not do what was
/// asked raises ``RunFailedError`` (its folder is kept) unless
/// ``check=False``. The GIL is released; Ctrl-C stops the run after the
/// current step, leaving ``OUT.partial``.
#[pyfunction]
#[pyo3(signature = (model, shape, out = None, steps = None, config = None, seed = None, *,
    force = false, check = true))]
#[allow(clippy::too_many_arguments)]
pub fn follow<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    shape: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    steps: Option<usize>,
    config: Option<&Bound<'py, PyAny>>,
    seed: Option<u64>,
    force: bool,
    check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = follow_config(config, steps, seed)?;
    let (name, contour) = shape_contour(shape)?;
    let diameter = 2.0 * cfg.rig.sensor.geometry.dome_radius_mm;
    if let Some(w) = size_warning(&name, &contour, diameter) {
        warn(py, &w)?;
    }
    let model = stored_model(model)?;
    let keep = out.is_some();
    let (dir, _tmp) = run_dir(out)?;
    let res = run_detached(py, || {
        follow_simulated(&cfg, &model, (&name, &contour), (&dir, force), &mut |_| {
            checkpoint()
        })
    })?
    .map_err(lab)?;
    outcome_dict(py, &res, keep, check)
}

/// Issue a Python `UserWarning`.
pub fn warn(py: Python<'_>, msg: &str) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
    PyErr::warn(
        py,
        &category,
        &std::ffi::CString::new(msg).unwrap_or_default(),
        1,
    )
}

/// The result dict of a run (see `follow`); raises `RunFailedError` for a
/// failed run when `check`.
pub fn outcome_dict<'py>(
    py: Python<'py>,
    res: &FollowOutcome,
    keep: bool,
    check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    if check && !res.summary.ending.succeeded() {
        let where_ = if keep {
            format!(
                "; the run and its trajectory so far are in {}",
                res.dir.display()
            )
        } else {
            String::new()
        };
        return Err(crate::errors::RunFailedError::new_err(format!(
            "the run failed ({:?}): {}{where_}",
            res.summary.ending, res.summary.message
        )));
    }
    let text = tactrace_store::read_text(&res.dir.join("metrics.json")).map_err(store)?;
    // Python's json reads the file's shortest round-trip floats exactly
    // (serde_json here, built without float_roundtrip, may be 1 ulp off).
    let d = py
        .import("json")?
        .call_method1("loads", (text,))?
        .cast_into::<PyDict>()?;
    let col = |f: &dyn Fn(&tactrace_servo::StepRecord) -> f64| -> Vec<f64> {
        res.records.iter().map(f).collect()
    };
    d.set_item("x_mm", PyArray1::from_vec(py, col(&|r| r.pose.x)))?;
    d.set_item("y_mm", PyArray1::from_vec(py, col(&|r| r.pose.y)))?;
    d.set_item("angle_deg", PyArray1::from_vec(py, col(&|r| r.pose.rz)))?;
    d.set_item(
        "r_pred_mm",
        PyArray1::from_vec(py, col(&|r| r.percept.r_mm)),
    )?;
    d.set_item(
        "theta_pred_deg",
        PyArray1::from_vec(py, col(&|r| r.percept.theta_deg)),
    )?;
    d.set_item(
        "mean_displacement_px",
        PyArray1::from_vec(py, col(&|r| r.percept.mean_displacement_px)),
    )?;
    let contact: Vec<bool> = res.records.iter().map(|r| r.percept.contact).collect();
    d.set_item("contact", PyArray1::from_vec(py, contact))?;
    d.set_item("l2_curve", PyArray1::from_vec(py, res.l2_curve.clone()))?;
    d.set_item("dir", keep.then(|| res.dir.clone()))?;
    Ok(d)
}
