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

impl ServoError {
    /// Whether the error lies in what the user gave (a setting, the start,
    /// a model that does not fit the sensor, the sensor's or arm's or
    /// detector's configuration) rather than in a run that went wrong (a
    /// frame, a prediction, a move or a recording that failed).
    pub fn is_bad_input(&self) -> bool {
        use tactrace_learn::LearnError as L;
        match self {
            ServoError::Config(_)
            | ServoError::Start(_)
            | ServoError::InputSize { .. }
            | ServoError::Geometry(_) => true,
            ServoError::Sensor(e) => e.is_config(),
            ServoError::Vision(e) => e.is_config(),
            ServoError::Arm(e) => matches!(e, tactrace_arm::ArmError::InvalidConfig { .. }),
            ServoError::Learn(e) => matches!(
                e,
                L::Config { .. } | L::NetConfig { .. } | L::DimensionMismatch { .. }
            ),
            ServoError::NonFinitePrediction { .. } | ServoError::Sink { .. } => false,
        }
    }
}

/// `e` and its sources, outermost first, joined by ": ", each cause
/// printed once: the one rule for showing an error to people (the CLI's
/// `error:` line, a run's stop message). Our messages do not embed their
/// `#[source]`; a cause whose text the message before it already holds (a
/// third-party error that repeats its I/O cause, `... (os error 28): No
/// space left ... (os error 28)`) is skipped.
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut next = e.source();
    while let Some(cause) = next {
        let part = cause.to_string();
        if !part.is_empty() && !text.contains(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
        next = cause.source();
    }
    text
}

/// Result with [`ServoError`].
pub type Result<T, E = ServoError> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::error_chain;

    /// An error that embeds its cause's text and also gives it as source,
    /// as csv's and the npy writer's errors do.
    #[derive(Debug)]
    struct Repeats(std::io::Error);

    impl std::fmt::Display for Repeats {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "I/O error: {}", self.0)
        }
    }

    impl std::error::Error for Repeats {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn an_io_cause_is_printed_once() {
        let io = std::io::Error::from_raw_os_error(28);
        let wrapped = std::io::Error::other(Repeats(io));
        let err = super::ServoError::Sink {
            step: 3,
            source: Box::new(wrapped),
        };
        let text = error_chain(&err);
        assert_eq!(text.matches("os error 28").count(), 1, "{text}");
        assert!(
            text.starts_with("recording step 3 failed: I/O error: "),
            "{text}"
        );
    }
}
