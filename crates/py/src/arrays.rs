//! numpy arrays in and out: any dtype accepted (converted as
//! `numpy.ascontiguousarray(x, dtype)` would), shapes checked with a
//! message naming the argument.
use crate::errors::input;
use numpy::{Element, PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A C-contiguous numpy array of `T` made from `obj`, without a copy when
/// it already is one.
pub fn contiguous<'py, T: Element>(
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    name: &str,
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    if let Ok(a) = obj.cast::<PyArrayDyn<T>>() {
        if a.is_c_contiguous() {
            return Ok(a.clone());
        }
    }
    let py = obj.py();
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", dtype)?;
    let converted = py
        .import("numpy")?
        .call_method("ascontiguousarray", (obj,), Some(&kwargs))
        .map_err(|e| input(format!("{name}: not convertible to a {dtype} array: {e}")))?;
    Ok(converted.cast_into::<PyArrayDyn<T>>()?)
}

/// A matrix of `T` with `cols` columns (any if `None`); a 1-D array is one
/// row when `allow_row`. Returns the array and (rows, cols).
pub fn matrix<'py, T: Element>(
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    name: &str,
    cols: Option<usize>,
    allow_row: bool,
) -> PyResult<(Bound<'py, PyArrayDyn<T>>, usize, usize)> {
    let a = contiguous::<T>(obj, dtype, name)?;
    let shape = a.shape().to_vec();
    let (rows, c) = match shape[..] {
        [r, c] => (r, c),
        [c] if allow_row => (1, c),
        _ => {
            let want = cols.map_or("N x M".to_string(), |c| format!("N x {c}"));
            return Err(input(format!(
                "{name} must be a {want} array{}, got shape {}",
                if allow_row { " (or one row)" } else { "" },
                shape_text(&shape)
            )));
        }
    };
    if let Some(want) = cols {
        if c != want {
            return Err(input(format!(
                "{name} must have {want} columns, got shape {}",
                shape_text(&shape)
            )));
        }
    }
    Ok((a, rows, c))
}

/// Points `(x, y)` from an N x 2 array-like (float64).
pub fn points(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<[f64; 2]>> {
    let (a, _, _) = matrix::<f64>(obj, "float64", name, Some(2), false)?;
    let ro = a.readonly();
    let flat = ro.as_slice()?;
    Ok(flat.chunks_exact(2).map(|p| [p[0], p[1]]).collect())
}

/// An `rows x cols` numpy array from row-major `data`.
pub fn to_matrix<T: Element>(
    py: Python<'_>,
    data: Vec<T>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'_, PyArrayDyn<T>>> {
    PyArray1::from_vec(py, data).reshape(vec![rows, cols])
}

/// Points as an N x 2 float64 array.
pub fn points_array<'py>(
    py: Python<'py>,
    pts: &[[f64; 2]],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    to_matrix(py, pts.iter().flatten().copied().collect(), pts.len(), 2)
}

/// A JSON value as a Python object (through the `json` module, so dicts,
/// lists and numbers are the ones `json.load` gives).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| input(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Any serialisable value as a Python object, as `json_to_py` gives it.
pub fn serde_to_py<'py, T: serde::Serialize + ?Sized>(
    py: Python<'py>,
    v: &T,
) -> PyResult<Bound<'py, PyAny>> {
    json_to_py(
        py,
        &serde_json::to_value(v).map_err(|e| input(e.to_string()))?,
    )
}

/// A Python object (dict, list, numbers, strings; numpy arrays as lists)
/// as a JSON value.
pub fn py_to_json(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<serde_json::Value> {
    let py = obj.py();
    let kwargs = PyDict::new(py);
    kwargs.set_item("default", py.eval(c"lambda o: o.tolist()", None, None)?)?;
    let text: String = py
        .import("json")?
        .call_method("dumps", (obj,), Some(&kwargs))
        .map_err(|e| input(format!("{name}: not JSON-like: {e}")))?
        .extract()?;
    serde_json::from_str(&text).map_err(|e| input(format!("{name}: {e}")))
}

/// An array shape as numpy prints it: `(3, 4)`, `(5,)`.
pub(crate) fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let parts: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
            format!("({})", parts.join(", "))
        }
    }
}

/// Numbers for a message, comma-separated (`1, 2.5, nan`).
pub(crate) fn numbers_text(values: &[f64]) -> String {
    let parts: Vec<String> = values.iter().map(|v| v.to_string()).collect();
    parts.join(", ")
}
