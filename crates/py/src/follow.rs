//! Contour following in the simulated worlds: `follow` builds the world
//! (`tactrace_lab::world::World`: the simulated TacTip, a calibrated
//! sensor or the real-frame world) and runs it by
//! `tactrace_lab::follow::run`, as `tactrace follow` does; and what
//! `follow_rig` shares with it (model, shape and configuration arguments,
//! running a world with the GIL released, the result dict).
use crate::arrays::{matrix, py_to_json};
use crate::errors::{input, lab, store};
use crate::image_model::ImageModel;
use crate::interrupt::{checkpoint, run_detached};
use crate::model::Model;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::path::PathBuf;
use tactrace_geometry::{Contour, ShapeSpec, Vec2};
use tactrace_lab::follow::{FollowOutcome, RunHooks, SimFollowConfig};
use tactrace_lab::world::{OpenWorld, ReplayBank};
use tactrace_store::collection::CollectionEdits;
use tactrace_store::LoadedModel;

/// A model argument: a pin `Model`, an `ImageModel` or the path of either's
/// folder. The servo loop's perception then reads the taps' pins or their
/// pixels by the model, as `tactrace follow` does.
pub fn loaded_model(obj: &Bound<'_, PyAny>) -> PyResult<LoadedModel> {
    if let Ok(m) = obj.cast::<Model>() {
        return Ok(LoadedModel::Pins(m.get().stored.clone()));
    }
    if let Ok(m) = obj.cast::<ImageModel>() {
        return Ok(LoadedModel::Image(m.get().stored().clone()));
    }
    let dir: PathBuf = obj
        .extract()
        .map_err(|_| input("model must be a Model, an ImageModel or the path of a model folder"))?;
    LoadedModel::load(&dir).map_err(store)
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

/// Follow a contour, as ``tactrace follow``: in the simulated world, a
/// calibrated sensor's (``sensor``) or the real-frame world (``replay``).
///
/// ``model``: a ``Model``, an ``ImageModel`` (the taps' frames in, as
/// its training frames were made) or a model folder; ``shape``: a built-in name
/// ("flower", ...), a CSV path or an N x 2 array (mm); ``out``: the run
/// folder to write (config.toml, trajectory.csv, metrics.json, figures; as
/// the CLI's ``--out``), or None for none; ``steps``, ``seed`` and
/// ``config`` (a TOML path or a dict of its tables) as the CLI's flags.
/// ``sensor``: a calibrated sensor folder (``tactrace calibrate``), as
/// ``--sensor``: the simulated world is that sensor. ``replay``: a labelled
/// collection of real frames (frames/, targets.csv, frames/init_0.png), as
/// ``--replay DIR``: every tap is answered by the real frame whose labels
/// are nearest; or a dict with ``dir`` and any of the CLI's options
/// ``keep`` ("N%5==0"), ``targets``, ``reference``, ``image_column``,
/// ``r_column``, ``theta_column``, ``dz_column`` ("none": depth does not
/// count) and ``params`` (blob parameters TOML). Warnings (a contour
/// smaller than the sensor, real frames far from the poses reached or
/// that the model was trained on) are ``UserWarning``s.
/// Returns a dict with the keys of metrics.json (``mean_l2_mm``,
/// ``closed``, ``steps``, ``coverage``, ``ending``, ``succeeded``, and in
/// the real-frame world ``replay``), the trajectory as arrays (``x_mm``,
/// ``y_mm``, ``angle_deg``, ``r_pred_mm``, ``theta_pred_deg``,
/// ``mean_displacement_px``, ``contact``), ``l2_curve`` and ``dir`` (the
/// run folder or None). A run that did not do what was asked raises
/// ``RunFailedError`` (its folder is kept) unless ``check=False``. The GIL
/// is released; Ctrl-C stops the run after the current step, leaving
/// ``OUT.partial``.
#[pyfunction]
#[pyo3(signature = (model, shape, out = None, steps = None, config = None, seed = None, *,
    sensor = None, replay = None, force = false, check = true))]
#[allow(clippy::too_many_arguments)]
pub fn follow<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    shape: &Bound<'py, PyAny>,
    out: Option<PathBuf>,
    steps: Option<usize>,
    config: Option<&Bound<'py, PyAny>>,
    seed: Option<u64>,
    sensor: Option<PathBuf>,
    replay: Option<&Bound<'py, PyAny>>,
    force: bool,
    check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let mut cfg = follow_config(config, steps, seed)?;
    if sensor.is_some() {
        cfg.calibrated_sensor = sensor;
    }
    if let Some(r) = replay {
        cfg.replay = Some(replay_bank(r)?);
    }
    let (name, contour) = shape_contour(shape)?;
    let model = loaded_model(model)?;
    let world = cfg.world().open().map_err(lab)?;
    let res = run_world(py, world, &model, Some((&name, &contour)), (out, force))?.map_err(lab)?;
    if let Some(w) = res.replay.as_ref().and_then(|s| s.warning()) {
        warn(py, &w)?;
    }
    outcome_dict(py, &res, check)
}

/// A finished run and whether its folder is the caller's (`out` given) or
/// a temporary one, removed with it.
pub struct Finished {
    pub outcome: FollowOutcome,
    pub keep: bool,
    _tmp: Option<tempfile::TempDir>,
}

impl std::ops::Deref for Finished {
    type Target = FollowOutcome;

    fn deref(&self) -> &FollowOutcome {
        &self.outcome
    }
}

/// Run `world` with `model` on `shape` into `out` (or a temporary folder)
/// with the GIL released, stopping on Ctrl-C; the run's warnings become
/// `UserWarning`s (also when the run fails, whose error is returned).
pub fn run_world(
    py: Python<'_>,
    world: OpenWorld,
    model: &LoadedModel,
    shape: Option<(&str, &Contour)>,
    (out, force): (Option<PathBuf>, bool),
) -> PyResult<tactrace_lab::Result<Finished>> {
    let keep = out.is_some();
    let (dir, tmp) = run_dir(out)?;
    let mut warnings = Vec::new();
    let res = run_detached(py, || {
        let mut warn = |w: &str| warnings.push(w.to_string());
        let mut progress = |_: &tactrace_servo::StepRecord| checkpoint();
        let hooks = RunHooks {
            progress: Some(&mut progress),
            warn: Some(&mut warn),
            ..RunHooks::default()
        };
        tactrace_lab::follow::run_model(world, model, shape, (&dir, force), hooks)
    })?;
    for w in &warnings {
        warn(py, w)?;
    }
    Ok(res.map(|outcome| Finished {
        outcome,
        keep,
        _tmp: tmp,
    }))
}

/// The keys a `replay` dict may have besides `dir`.
const REPLAY_KEYS: &str =
    "keep, targets, reference, image_column, r_column, theta_column, dz_column, params";

/// A `replay` argument: a collection folder, or a dict with `dir` and the
/// CLI's `--replay` options.
fn replay_bank(obj: &Bound<'_, PyAny>) -> PyResult<ReplayBank> {
    let Ok(dict) = obj.cast::<PyDict>() else {
        let dir: PathBuf = obj.extract().map_err(|_| {
            input("replay must be the folder of a labelled collection or a dict with `dir`")
        })?;
        return ReplayBank::from_dir(&dir, &CollectionEdits::default()).map_err(lab);
    };
    let mut dir = None;
    let mut e = CollectionEdits::default();
    for (k, v) in dict.iter() {
        let key: String = k.extract()?;
        let text = || -> PyResult<String> {
            v.extract::<PathBuf>()
                .map(|p| p.to_string_lossy().into_owned())
                .map_err(|_| input(format!("replay: `{key}` must be a string or a path")))
        };
        match key.as_str() {
            "dir" => dir = Some(PathBuf::from(text()?)),
            "keep" => e.keep = Some(text()?),
            "targets" => e.targets = Some(text()?.into()),
            "reference" => e.reference = Some(text()?.into()),
            "image_column" => e.image_column = Some(text()?),
            "r_column" => e.r_column = Some(text()?),
            "theta_column" => e.theta_column = Some(text()?),
            "dz_column" => e.depth_column = Some(text()?),
            "params" => e.blob = Some(crate::vision::blob_params(Some(text()?.into()), "real256")?),
            _ => {
                return Err(input(format!(
                    "replay: unknown key `{key}`: give dir and any of {REPLAY_KEYS}"
                )))
            }
        }
    }
    let dir = dir.ok_or_else(|| input("replay: the dict needs `dir`, the collection's folder"))?;
    ReplayBank::from_dir(&dir, &e).map_err(lab)
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
    res: &Finished,
    check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let keep = res.keep;
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
            "the run failed ({}): {}{where_}",
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
