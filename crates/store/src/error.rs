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
    /// A single output file (or a file of a plots folder) exists and would
    /// be overwritten; `flag` is the option naming it (`--out`, `--plots`).
    #[error("{path} already exists; pass --force to replace it, or choose another {flag}")]
    OutputFileExists { path: PathBuf, flag: &'static str },
    /// Another process is writing the same output (it holds the output's
    /// lock, [`crate::lock`]).
    #[error(
        "{path} is being written by another tactrace run ({}); wait for it to end or \
         choose another output",
        pid_text(*.pid)
    )]
    OutputBusy { path: PathBuf, pid: Option<u32> },
    /// An output (`out_flag`) equal to or inside an input (`in_flag`),
    /// which the run would write into or, with `--force`, delete.
    #[error(
        "{out_flag} {out} is {} the input {in_flag} {input}: choose an output outside \
         the inputs",
        if *.equal { "the same as" } else { "inside" }
    )]
    OutputInInput {
        out_flag: &'static str,
        out: PathBuf,
        in_flag: &'static str,
        input: PathBuf,
        equal: bool,
    },
    /// An input inside an output folder that `--force` would replace.
    #[error(
        "the input {in_flag} {input} is inside {out_flag} {out}, which --force would \
         replace: choose another output"
    )]
    InputInOutput {
        out_flag: &'static str,
        out: PathBuf,
        in_flag: &'static str,
        input: PathBuf,
    },
    /// A labelled collection's description that cannot be used.
    #[error(transparent)]
    Collection(#[from] crate::collection::CollectionError),
    /// Two datasets given to be trained on together that differ in what a
    /// model needs alike (`train --train A --train B`).
    #[error("{first} and {other} cannot be trained on together")]
    Mismatch {
        first: PathBuf,
        other: PathBuf,
        #[source]
        mismatch: crate::dataset_join::DatasetMismatch,
    },
    /// A setting of a loaded model that it cannot take (turned views at
    /// prediction for a model fitted without rotations: `--views`).
    #[error("{path}: {source}")]
    ModelSetting {
        path: PathBuf,
        #[source]
        source: tactrace_learn::LearnError,
    },
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

/// "pid N", or that the holder has not written it yet.
fn pid_text(pid: Option<u32>) -> String {
    pid.map_or_else(|| "its pid not yet recorded".into(), |p| format!("pid {p}"))
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
