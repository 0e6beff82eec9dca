//! `tactrace._tactrace`: tactrace's crates as a Python extension module.
//!
//! Thin wrappers only: every function calls the same crates the CLI calls
//! (store, learn, vision, sensor, servo, lab), takes numpy arrays of any
//! dtype, millimetres and degrees, and turns the crates' typed errors into
//! Python exceptions carrying the CLI's messages (`errors.rs`). Long calls
//! run with the GIL released and stop on Ctrl-C (`interrupt.rs`).
//! The Python package `tactrace` (crates/py/python) re-exports it.

mod arrays;
mod data;
mod errors;
mod follow;
mod image_model;
mod interrupt;
mod model;
mod remote;
mod rig;
mod samples;
mod sight;
mod sim;
mod vision;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _tactrace(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", tactrace_lab::VERSION)?;
    m.add("TactraceError", py.get_type::<errors::TactraceError>())?;
    m.add("InputError", errors::input_error_type(py)?)?;
    m.add("RunFailedError", py.get_type::<errors::RunFailedError>())?;
    m.add_function(wrap_pyfunction!(data::load_dataset, m)?)?;
    m.add_function(wrap_pyfunction!(data::save_dataset, m)?)?;
    m.add_function(wrap_pyfunction!(data::import_dataset, m)?)?;
    m.add_class::<model::Model>()?;
    m.add_class::<image_model::ImageModel>()?;
    m.add_function(wrap_pyfunction!(model::load_model, m)?)?;
    m.add_function(wrap_pyfunction!(model::train, m)?)?;
    m.add_function(wrap_pyfunction!(vision::read_frame, m)?)?;
    m.add_class::<vision::PinExtractor>()?;
    m.add_function(wrap_pyfunction!(sight::preprocess, m)?)?;
    m.add_function(wrap_pyfunction!(sight::inspect_sensor, m)?)?;
    m.add_class::<sight::PinReader>()?;
    m.add_class::<sim::SimTacTip>()?;
    m.add_function(wrap_pyfunction!(follow::follow, m)?)?;
    m.add_function(wrap_pyfunction!(rig::follow_rig, m)?)?;
    m.add_function(wrap_pyfunction!(remote::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(remote::prepare, m)?)?;
    Ok(())
}
