//! Typed errors of tactrace's files: every failure names the file.
use std::path::PathBuf;

/// What can go wrong reading or writing tactrace's files.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StoreError {
    /// A file or folder could not be read (bad input).
    #[error("cannot read {path}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file or folder could not be written (the run failed).
    #[error("cannot write {path}")]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file was read but its content is not what it should be.
    #[error("{path}: {reason}")]
    Format { path: PathBuf, reason: String },
    /// A configuration file that cannot be used.
    #[error("{what}: {reason}")]
    Config { what: String, reason: String },
    /// The output exists and would be overwritten.
    #[error("{path} already exists and is not empty; choose another --out or pass --force")]
    OutputExists { path: PathBuf },
    /// Data whose pins are ordered against other reference pins than the
    /// model's training data.
    #[error("{path}: not ordered like the model's training data")]
    PinOrder {
        path: PathBuf,
        #[source]
        source: crate::pin_order::PinOrderError,
    },
}

impl StoreError {
    /// Whether the failure lies in what the user gave (exit code 2) rather
    /// than in writing the results (exit code 1).
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, StoreError::Write { .. })
    }
}

/// Result with [`StoreError`].
pub type Result<T, E = StoreError> = std::result::Result<T, E>;

/// Attach a path to an error reading it.
pub fn read_err(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> StoreError {
    let path = path.into();
    move |source| StoreError::Read { path, source }
}

/// Attach a path to an error writing it.
pub fn write_err(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> StoreError {
    let path = path.into();
    move |source| StoreError::Write { path, source }
}
