//! The worker's side of a remote executor: `prepare(name, context)`
//! builds an evaluation once (its data read), `evaluate(name, context,
//! config)` runs the same Rust evaluation the command would run locally
//! (`tactrace_lab::remote::evaluate`) and returns its score as JSON text.
//! `tactrace.ray_executor` calls it inside each Ray task.
use crate::errors::lab;
use crate::interrupt::run_detached;
use pyo3::prelude::*;

/// Evaluate the evaluation `name`, rebuilt from its `context` (JSON), on
/// one configuration (JSON); the score as JSON. Runs with the GIL
/// released. Bad input raises `InputError`, a failed evaluation
/// `RunFailedError`.
#[pyfunction]
pub fn evaluate(py: Python<'_>, name: &str, context: &str, config: &str) -> PyResult<String> {
    run_detached(py, || tactrace_lab::remote::evaluate(name, context, config))?.map_err(lab)
}

/// Build the evaluation `name` from its `context` (JSON) and keep it for
/// the `evaluate` calls that follow; whether it was built now (false: it
/// was kept from an earlier call in this process). Runs with the GIL
/// released; errors as `evaluate`'s.
#[pyfunction]
pub fn prepare(py: Python<'_>, name: &str, context: &str) -> PyResult<bool> {
    run_detached(py, || tactrace_lab::remote::prepare(name, context))?.map_err(lab)
}
