//! Typed errors of the lab: every failure names the file or setting at fault.
use std::path::PathBuf;

/// What can go wrong running an experiment or reading/writing its files.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// A file or folder could not be read or written.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A file was read but its content is not what it should be.
    #[error("{path}: {reason}")]
    Format { path: PathBuf, reason: String },
    /// A configuration or argument value that cannot work.
    #[error("invalid configuration: {0}")]
    Config(String),
    /// The output exists and would be overwritten.
    #[error("{path} already exists and is not empty; choose another --out or pass --force")]
    OutputExists { path: PathBuf },
    #[error(transparent)]
    Geometry(#[from] tactrace_geometry::GeometryError),
    #[error(transparent)]
    Sensor(#[from] tactrace_sensor::SensorError),
    #[error(transparent)]
    Vision(#[from] tactrace_vision::VisionError),
    #[error(transparent)]
    Learn(#[from] tactrace_learn::LearnError),
    #[error(transparent)]
    Arm(#[from] tactrace_arm::ArmError),
    /// The servo loop lost the object or could not start.
    #[error("servo: {0}")]
    Servo(String),
}

impl LabError {
    /// Whether the failure lies in what the user gave (files, arguments,
    /// configuration, data) rather than in a run that went wrong. The binary
    /// maps this to its exit code (2 for bad input, 1 for a failed run).
    pub fn is_bad_input(&self) -> bool {
        use tactrace_learn::LearnError as L;
        use tactrace_sensor::SensorError as S;
        use tactrace_vision::VisionError as V;
        match self {
            LabError::Io { .. }
            | LabError::Format { .. }
            | LabError::Config(_)
            | LabError::OutputExists { .. }
            | LabError::Geometry(_) => true,
            LabError::Sensor(e) => !matches!(e, S::ReplayExhausted { .. }),
            LabError::Vision(e) => !matches!(e, V::TooFewPins { .. }),
            LabError::Learn(e) => !matches!(e, L::Diverged { .. }),
            LabError::Arm(e) => matches!(e, tactrace_arm::ArmError::InvalidConfig { .. }),
            LabError::Servo(_) => false,
        }
    }
}

/// Result with [`LabError`].
pub type Result<T, E = LabError> = std::result::Result<T, E>;

/// Attach a path to an I/O error.
pub(crate) fn io_err(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> LabError {
    let path = path.into();
    move |source| LabError::Io { path, source }
}
