//! Long calls run with the GIL released and honour Ctrl-C: at checkpoints
//! (every epoch, every step, every few thousand rows) [`checkpoint`] takes
//! the GIL for a moment and asks Python whether a signal is pending; if
//! its handler raised (KeyboardInterrupt), the call unwinds to
//! [`run_detached`], which hands the exception to Python. Unwinding needs
//! no hook in the crates: the callbacks they already take are enough.
use pyo3::prelude::*;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};

/// The payload of an unwind started by a pending signal.
struct Interrupted(PyErr);

/// Run `f` with the GIL released; an interrupt at a [`checkpoint`] inside
/// becomes the Python exception its signal handler raised.
pub fn run_detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    let got = py.detach(|| catch_unwind(AssertUnwindSafe(f)));
    match got {
        Ok(v) => Ok(v),
        Err(payload) => match payload.downcast::<Interrupted>() {
            Ok(i) => Err(i.0),
            Err(other) => resume_unwind(other),
        },
    }
}

/// Let Python run its signal handlers; unwind to [`run_detached`] when
/// one raised. Call only inside [`run_detached`].
pub fn checkpoint() {
    if let Err(e) = Python::attach(|py| py.check_signals()) {
        resume_unwind(Box::new(Interrupted(e)));
    }
}

/// Stop the call with `err` (a Python exception met inside a detached
/// call, e.g. raised by a user's arm): unwinds to [`run_detached`].
pub fn raise(err: PyErr) -> ! {
    resume_unwind(Box::new(Interrupted(err)))
}
