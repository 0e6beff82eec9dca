//! Typed errors of the remote (Ray) executor.
use std::path::PathBuf;

/// Why a batch could not run on the Ray executor, or a remote evaluation
/// failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RemoteError {
    /// The Python interpreter could not be started.
    #[error(
        "cannot start the Python interpreter {} (give one with --python or TACTRACE_PYTHON)",
        python.display()
    )]
    PythonNotFound {
        python: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The interpreter runs but lacks Ray or the tactrace package.
    #[error(
        "{} cannot run the Ray executor: {reason} (install the tactrace Python package and \
         ray==2.60.0 into it)",
        python.display()
    )]
    Setup { python: PathBuf, reason: String },
    /// `ray.init` could not join the cluster.
    #[error("the Ray cluster at {address} cannot be reached: {reason}")]
    Unreachable { address: String, reason: String },
    /// An evaluation failed on a worker; `bad_input` when the worker's
    /// error was one of bad input (exit 2 on the CLI).
    #[error("{evaluation} failed on a Ray worker: {message}")]
    Evaluation {
        evaluation: String,
        message: String,
        bad_input: bool,
    },
    /// The Ray executor's process stopped answering or answered nonsense.
    #[error("the Ray executor's process {what}")]
    Protocol { what: String },
    /// Writing to or reading from the Ray executor's process failed.
    #[error("the Ray executor's pipe")]
    Pipe(#[source] std::io::Error),
    /// An evaluation without a remote form was given to a remote executor.
    #[error("{evaluation} cannot run on a remote executor: it has no remote form")]
    NotRemote { evaluation: String },
    /// A worker was asked for an evaluation it does not know.
    #[error("no evaluation is named {name}")]
    UnknownEvaluation { name: String },
    /// A remote evaluation's context, configuration or score did not
    /// (de)serialise.
    #[error("the {what} of {evaluation} as JSON")]
    Json {
        evaluation: String,
        what: &'static str,
        #[source]
        source: serde_json::Error,
    },
}

impl RemoteError {
    /// Whether the failure lies in what the user gave (interpreter,
    /// inputs: exit 2) rather than in a run that went wrong (exit 1).
    pub fn is_bad_input(&self) -> bool {
        match self {
            RemoteError::PythonNotFound { .. }
            | RemoteError::Setup { .. }
            | RemoteError::NotRemote { .. }
            | RemoteError::UnknownEvaluation { .. }
            | RemoteError::Json { .. } => true,
            RemoteError::Evaluation { bad_input, .. } => *bad_input,
            RemoteError::Unreachable { .. }
            | RemoteError::Protocol { .. }
            | RemoteError::Pipe(_) => false,
        }
    }
}
