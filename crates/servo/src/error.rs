//! Typed errors of the servo loop and the simulated rig.

/// Why the loop could not run or had to stop with an error (a run that
/// ends safely, e.g. by losing contact, is a [`crate::LoopSummary`], not an
/// error).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ServoError {
    /// A loop setting that cannot work (bad input).
    #[error("invalid servo setting: {0}")]
    Config(String),
    /// The start pose cannot be used (bad input).
    #[error("{0}")]
    Start(String),
    /// The model does not fit the sensor (bad input).
    #[error("the model expects {expected} inputs but the sensor gives {got} (2 x pins)")]
    InputSize { expected: usize, got: usize },
    /// The model predicted a non-finite pose: the run is stopped.
    #[error(
        "the model predicted a non-finite pose (r = {r_mm}, theta = {theta_deg}) at step {step}"
    )]
    NonFinitePrediction {
        step: usize,
        r_mm: f64,
        theta_deg: f64,
    },
    /// A sink failed (e.g. the trajectory file could not be written).
    #[error("recording step {step} failed")]
    Sink {
        step: usize,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    #[error(transparent)]
    Arm(#[from] tactrace_arm::ArmError),
    #[error(transparent)]
    Sensor(#[from] tactrace_sensor::SensorError),
    #[error(transparent)]
    Vision(#[from] tactrace_vision::VisionError),
    #[error(transparent)]
    Learn(#[from] tactrace_learn::LearnError),
    #[error(transparent)]
    Geometry(#[from] tactrace_geometry::GeometryError),
}

/// Result with [`ServoError`].
pub type Result<T, E = ServoError> = std::result::Result<T, E>;
