//! The crates' typed errors as Python exceptions: `TactraceError` is the
//! base; bad input (what the CLI exits 2 for) is an `InputError`, also a
//! `ValueError`; a run that failed (exit 1) is a `RunFailedError`. The
//! message is the CLI's: the error and its sources joined by ": ".
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    tactrace,
    TactraceError,
    PyException,
    "Base class of tactrace's errors."
);
pyo3::create_exception!(
    tactrace,
    RunFailedError,
    TactraceError,
    "A run that failed (the CLI's exit code 1): lost contact, a refused move, a fault, an output that could not be written."
);

/// `InputError(TactraceError, ValueError)`: made at import time, as a
/// Rust-declared exception has one base.
pub struct InputError;

impl InputError {
    /// The exception with `msg`.
    pub fn new_err(msg: String) -> PyErr {
        Python::attach(|py| match input_error_type(py) {
            Ok(t) => PyErr::from_type(t, msg),
            Err(e) => e,
        })
    }
}

static INPUT_ERROR: pyo3::sync::PyOnceLock<Py<pyo3::types::PyType>> = pyo3::sync::PyOnceLock::new();

/// The `InputError` class (created once, with both bases, by calling
/// `type` as Python's `class` statement does).
pub fn input_error_type(py: Python<'_>) -> PyResult<Bound<'_, pyo3::types::PyType>> {
    use pyo3::types::{PyDict, PyTuple, PyType};
    let t = INPUT_ERROR.get_or_try_init(py, || -> PyResult<_> {
        let bases = PyTuple::new(
            py,
            [
                py.get_type::<TactraceError>(),
                py.get_type::<PyValueError>(),
            ],
        )?;
        let body = PyDict::new(py);
        body.set_item("__module__", "tactrace")?;
        body.set_item(
            "__doc__",
            "Bad input (the CLI's exit code 2): a file, argument, configuration or array \
             that cannot be used. Also a ValueError.",
        )?;
        let t = py
            .get_type::<PyType>()
            .call1(("InputError", bases, body))?
            .cast_into::<PyType>()?;
        Ok(t.unbind())
    })?;
    Ok(t.bind(py).clone())
}

/// The message of `err` and its sources, as the CLI prints it (each
/// cause once).
pub fn chain_message(err: &(dyn std::error::Error + 'static)) -> String {
    tactrace_lab::error::error_chain(err)
}

/// A lab error as a Python exception.
pub fn lab(err: tactrace_lab::LabError) -> PyErr {
    let msg = chain_message(&err);
    if err.is_bad_input() {
        InputError::new_err(msg)
    } else {
        RunFailedError::new_err(msg)
    }
}

/// A store error as a Python exception.
pub fn store(err: tactrace_store::StoreError) -> PyErr {
    let msg = chain_message(&err);
    if err.is_bad_input() {
        InputError::new_err(msg)
    } else {
        RunFailedError::new_err(msg)
    }
}

/// Any core crate's error, through the lab's classification.
pub fn core(err: impl Into<tactrace_lab::LabError>) -> PyErr {
    lab(err.into())
}

/// Bad input described by `msg`.
pub fn input(msg: impl Into<String>) -> PyErr {
    InputError::new_err(msg.into())
}
