//! Datasets: `load_dataset` / `save_dataset` over `tactrace_store::dataset`
//! (the folders `tactrace collect`, `import` and `twin` write), and
//! `import_dataset` (`tactrace import`: real frames with named targets).
use crate::arrays::{json_to_py, matrix, py_to_json, to_matrix};
use crate::errors::{input, lab, store};
use crate::interrupt::{checkpoint, run_detached};
use numpy::{PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use tactrace_lab::import_request::ImportRequest;
use tactrace_store::collection::CollectionEdits;
use tactrace_store::fsutil;
use tactrace_store::{DatasetMeta, TapData};

/// Read a dataset folder (`inputs.npy`, `targets.npy`, `meta.json`).
///
/// Returns ``(inputs, targets, meta)``: inputs an N x 2P float32 array of
/// pin displacements in pixels (the P x-displacements, then the P
/// y-displacements, pins in ``meta["reference_pins"]`` order), targets N x T
/// float32 (the targets ``meta["target_names"]``, ``meta["target_units"]``
/// and ``meta["target_circular"]`` list, in order; the edge task's r in mm
/// and theta in degrees when meta names none), meta the ``meta.json`` dict. Raises ``InputError`` naming the file at fault.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn load_dataset<'py>(
    py: Python<'py>,
    dir: PathBuf,
) -> PyResult<(
    Bound<'py, PyArrayDyn<f32>>,
    Bound<'py, PyArrayDyn<f32>>,
    Bound<'py, PyAny>,
)> {
    let data = py
        .detach(|| tactrace_store::read_dataset(&dir))
        .map_err(store)?;
    let (n, d, t) = (data.len(), data.dim(), data.n_targets());
    let meta = serde_json::to_value(&data.meta).map_err(|e| input(e.to_string()))?;
    Ok((
        to_matrix(py, data.inputs, n, d)?,
        to_matrix(py, data.targets, n, t)?,
        json_to_py(py, &meta)?,
    ))
}

/// Write a dataset folder that tactrace (and ``load_dataset``) reads.
///
/// ``inputs`` is N x 2P (pixels; the x-displacements, then the
/// y-displacements), ``targets`` N x T, any dtype (stored as float32): the
/// edge task's r mm and theta deg (T = 2), or the targets ``meta`` names in
/// ``target_names`` and ``target_units`` (``"mm"``/``"deg"``; optional
/// ``target_circular``). ``meta`` must hold ``reference_pins`` (P x 2, px:
/// the order of the inputs); missing keys get defaults (source "python"), and
/// ``samples`` / ``pins`` are set from the arrays. The folder appears only
/// when complete; an existing non-empty folder is refused unless
/// ``force=True``. Returns the folder's path.
#[pyfunction]
#[pyo3(signature = (dir, inputs, targets, meta, *, force = false))]
pub fn save_dataset(
    py: Python<'_>,
    dir: PathBuf,
    inputs: &Bound<'_, PyAny>,
    targets: &Bound<'_, PyAny>,
    meta: &Bound<'_, PyDict>,
    force: bool,
) -> PyResult<PathBuf> {
    let (x, n, d) = matrix::<f32>(inputs, "float32", "inputs", None, false)?;
    let (y, m, t) = matrix::<f32>(targets, "float32", "targets", None, false)?;
    if n != m {
        return Err(input(format!(
            "inputs has {n} rows but targets has {m}: one target row per sample"
        )));
    }
    let meta = dataset_meta(meta, n, d)?;
    if meta.targets.len() != t {
        return Err(input(format!(
            "targets has {t} columns, meta names {} targets ({}): name each target \
             (target_names, target_units)",
            meta.targets.len(),
            meta.targets.join(", ")
        )));
    }
    let data = TapData {
        inputs: x.readonly().as_slice()?.to_vec(),
        targets: y.readonly().as_slice()?.to_vec(),
        meta,
    };
    py.detach(|| tactrace_store::write_dataset(&dir, &data, &[], force))
        .map_err(store)
}

/// `meta` over the defaults, with the counts of an `n x d` input array.
fn dataset_meta(meta: &Bound<'_, PyDict>, n: usize, d: usize) -> PyResult<DatasetMeta> {
    let given = py_to_json(meta.as_any(), "meta")?;
    let mut doc = serde_json::json!({
        "source": "python",
        "origin": "",
        "seed": null,
        "targets": ["r_mm", "theta_deg"],
        "frames_with_missing_pins": 0,
        "settings": null,
        "tactrace_version": tactrace_lab::VERSION,
    });
    let (Some(doc_map), Some(given_map)) = (doc.as_object_mut(), given.as_object()) else {
        return Err(input("meta must be a dict"));
    };
    for (k, v) in given_map {
        doc_map.insert(k.clone(), v.clone());
    }
    doc_map.insert("samples".into(), n.into());
    doc_map.insert("pins".into(), (d / 2).into());
    let meta: DatasetMeta = serde_json::from_value(doc)
        .map_err(|e| input(format!("meta: {e} (reference_pins, P x 2 px, is required)")))?;
    // Named targets: shown as `name (unit)` unless meta shows them itself.
    let mut meta = meta;
    if !meta.target_columns.target_names.is_empty() {
        let targets = meta.model_targets().or_else(|_| {
            let mut named = meta.clone();
            named.targets = named.target_columns.target_names.clone();
            named.model_targets()
        });
        let targets = targets.map_err(|e| input(format!("meta: {e}")))?;
        if meta.targets.len() != targets.len() {
            meta.targets = tactrace_store::TargetColumns::display(&targets);
        }
    }
    if 2 * meta.reference_pins.len() != d {
        return Err(input(format!(
            "meta has {} reference pins, but inputs has {d} columns (2 x pins)",
            meta.reference_pins.len()
        )));
    }
    Ok(meta)
}

/// Import a labelled collection of real frames into a dataset folder, as
/// ``tactrace import`` does (the same request, the same reading).
///
/// ``frames`` is the frames folder, ``labels`` the labels CSV (one row a
/// frame), ``out`` the dataset folder to write (appears only when
/// complete; an existing one is refused unless ``force=True``).
/// ``target`` lists the targets as ``"COLUMN:UNIT[:circular][:ROLE]"``
/// (unit ``mm`` or ``deg``, role ``position`` or ``angle``; ``--target``), in
/// order; or ``r_column`` / ``theta_column`` name the edge task's two
/// (default ``pose_2``, ``pose_6``). ``image_column`` names the frame file
/// column. ``sensor`` is a sensor file (``inspect_sensor(out=...)``);
/// ``reference`` an undeformed frame or a dataset folder (its rest pins
/// and sensor settings); with neither the rest layout is estimated from
/// the taps and recorded. ``params`` a blob detector TOML file (default:
/// the real256 preset); ``like`` a dataset folder whose preprocessing,
/// reference and targets to use for another split (excludes the
/// others); ``limit`` the first N rows. Returns a dict: ``dir``,
/// ``samples``, ``frames_total``, ``frames_fully_tracked``,
/// ``frames_with_missing_pins``, ``rejected`` (frame names and why),
/// ``estimated_rest`` (``pins``, ``residual_px``, ``frames``, or None);
/// what the CLI warns about is a ``UserWarning``.
#[pyfunction]
#[pyo3(signature = (frames, labels, out, *, target = vec![], image_column = None,
    r_column = None, theta_column = None, sensor = None, reference = None, params = None,
    like = None, limit = None, force = false))]
#[allow(clippy::too_many_arguments)]
pub fn import_dataset<'py>(
    py: Python<'py>,
    frames: PathBuf,
    labels: PathBuf,
    out: PathBuf,
    target: Vec<String>,
    image_column: Option<String>,
    r_column: Option<String>,
    theta_column: Option<String>,
    sensor: Option<PathBuf>,
    reference: Option<PathBuf>,
    params: Option<PathBuf>,
    like: Option<PathBuf>,
    limit: Option<usize>,
    force: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let others = !target.is_empty()
        || [&image_column, &r_column, &theta_column]
            .iter()
            .any(|c| c.is_some())
        || sensor.is_some()
        || reference.is_some()
        || params.is_some();
    if like.is_some() && others {
        return Err(input(
            "like takes the targets, image column, sensor settings, reference and blob \
             detector of its dataset: give only frames, labels, out and limit with it",
        ));
    }
    if sensor.is_some() && params.is_some() {
        return Err(input(
            "give either sensor or params: the sensor file has its detector",
        ));
    }
    let blob =
        crate::vision::blob_params(params, tactrace_store::collection::bristol::BLOB_PRESET)?;
    let request = ImportRequest {
        frames,
        targets: labels,
        reference,
        sensor,
        like,
        edits: CollectionEdits {
            image_column,
            r_column,
            theta_column,
            target_list: target,
            limit,
            blob: Some(blob),
            ..CollectionEdits::default()
        },
    };
    let got = run_detached(py, || -> Result<_, tactrace_lab::LabError> {
        let _lock = fsutil::check_output_dir(&out, force)?;
        let plan = request.plan()?;
        let got = tactrace_lab::import::import(&plan.collection, &checkpoint)?;
        plan.check(&got.data)?;
        let dir = tactrace_store::write_dataset(&out, &got.data, &[], force)?;
        Ok((dir, got))
    })?
    .map_err(lab)?;
    let (dir, got) = got;
    for w in &got.warnings {
        crate::follow::warn(py, w)?;
    }
    let t = got.data.meta.tracking;
    let summary = serde_json::json!({
        "dir": dir.display().to_string(),
        "samples": got.data.len(),
        "frames_total": t.frames_total,
        "frames_fully_tracked": t.frames_fully_tracked,
        "frames_with_missing_pins": got.frames_with_missing_pins,
        "rejected": got.rejected,
        "estimated_rest": got.estimated_rest,
    });
    json_to_py(py, &summary)
}
