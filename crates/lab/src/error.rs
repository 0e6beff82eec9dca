//! Typed errors of the experiments, each kind mapped to an exit code by
//! [`LabError::is_bad_input`]: every failure names the file or setting at
//! fault, and the source errors of the other crates stay typed inside.
use std::path::PathBuf;
pub use tactrace_servo::error_chain;
use tactrace_servo::Ending;

/// What can go wrong running an experiment.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LabError {
    /// A file was read but its content is not what it should be.
    #[error("{path}: {reason}")]
    Format { path: PathBuf, reason: String },
    /// A reference frame (`--reference`) that is no undeformed frame of the
    /// sensor: `source` says what did not fit.
    #[error("{path}: {reason}")]
    Reference {
        path: PathBuf,
        reason: String,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A configuration or argument value that cannot work.
    #[error("invalid configuration: {0}")]
    Config(String),
    /// A run that started but did not do what was asked (lost contact,
    /// step cap, refused move, fault). Its outputs are kept.
    #[error("the run failed ({ending}): {message}")]
    RunFailed { ending: Ending, message: String },
    /// Every trial of a search, sim-fit or tune failed (diverged, not a
    /// valid candidate, or a run that gave no number): there is no best to
    /// write. What was tried is kept where `kept` says.
    #[error(
        "every one of the {tried} {what} failed ({reason}): there is no best to write{}",
        kept_suffix(.kept)
    )]
    AllFailed {
        what: String,
        tried: usize,
        reason: String,
        kept: Option<PathBuf>,
    },
    /// A result that is not a number (a NaN or infinite error, loss or
    /// metric): never reported as success.
    #[error("{what}: {metric} is {value}, not a number{}", hint_suffix(.hint))]
    NotANumber {
        what: String,
        metric: String,
        value: f64,
        hint: String,
    },
    /// Too few training samples for the model: `held_out` more were set
    /// aside for validation.
    #[error(
        "too few training samples ({got}): at least {needed} are needed ({reason}); {}",
        more_samples_hint(*.held_out)
    )]
    TooFewSamples {
        got: usize,
        needed: usize,
        reason: String,
        held_out: usize,
    },
    /// Training data whose pins never move: every displacement 0, or every
    /// row the same ([`crate::import_checks::still_pins`]).
    #[error("{what}: {reason}")]
    StillPins { what: String, reason: String },
    /// A controller setting that cannot work.
    #[error(transparent)]
    Control(#[from] tactrace_control::ControlError),
    /// An optimiser set-up that cannot work, or its misuse.
    #[error(transparent)]
    Optim(#[from] tactrace_optim::OptimError),
    #[error(transparent)]
    Store(#[from] tactrace_store::StoreError),
    /// The taps cannot calibrate the sensor (too few, not spanning, ...).
    #[error(transparent)]
    Calib(#[from] tactrace_calib::CalibError),
    #[error(transparent)]
    Report(#[from] tactrace_report::ReportError),
    #[error(transparent)]
    Servo(#[from] tactrace_servo::ServoError),
    #[error(transparent)]
    Geometry(#[from] tactrace_geometry::GeometryError),
    /// A 3D object that cannot be built (its settings or its mesh file).
    #[error(transparent)]
    Shape3d(#[from] tactrace_shape3d::Shape3dError),
    #[error(transparent)]
    Sensor(#[from] tactrace_sensor::SensorError),
    #[error(transparent)]
    Vision(#[from] tactrace_vision::VisionError),
    #[error(transparent)]
    Learn(#[from] tactrace_learn::LearnError),
    #[error(transparent)]
    Arm(#[from] tactrace_arm::ArmError),
    /// The remote (Ray) executor could not run a batch.
    #[error(transparent)]
    Remote(#[from] crate::remote::RemoteError),
    #[cfg(feature = "hardware")]
    #[error(transparent)]
    Hardware(#[from] tactrace_hw::HwError),
    /// The real arm could not move to the run's start: the limiter refused
    /// the move (the arm is too far from the start: the set-up, exit 2) or
    /// the arm failed on the way (a fault, exit 1).
    #[cfg(feature = "hardware")]
    #[error("cannot move the arm to the start{}", start_hint(.source))]
    StartMove {
        #[source]
        source: tactrace_arm::ArmError,
    },
    /// A hardware run stopped by SIGINT or SIGTERM: the arm, if it was
    /// connected (`arm_stopped`), was sent `stopl`; what the run did so far
    /// is kept in `kept`, if anything.
    #[cfg(feature = "hardware")]
    #[error(
        "interrupted by {signal}: {}{}",
        if *.arm_stopped { "the arm was sent stopl" } else { "before the arm was connected" },
        kept_text(.kept)
    )]
    Interrupted {
        signal: tactrace_hw::StopSignal,
        arm_stopped: bool,
        kept: Option<PathBuf>,
    },
}

/// Whether an arm error is the limiter's refusal of a move (the set-up),
/// not a failure of the arm.
#[cfg(feature = "hardware")]
fn refused(e: &tactrace_arm::ArmError) -> bool {
    use tactrace_arm::ArmError as A;
    matches!(
        e,
        A::OutsideWorkspace { .. }
            | A::StepTooLarge { .. }
            | A::RotationTooLarge { .. }
            | A::TiltTooLarge { .. }
            | A::NonFinitePose { .. }
            | A::InvalidConfig { .. }
    )
}

#[cfg(feature = "hardware")]
fn start_hint(e: &tactrace_arm::ArmError) -> &'static str {
    if refused(e) {
        " (jog the arm to within the workspace's step limits of it first; \
         `tactrace rig check` says how far it is)"
    } else {
        ""
    }
}

#[cfg(feature = "hardware")]
fn kept_text(kept: &Option<PathBuf>) -> String {
    kept.as_ref()
        .map(|p| format!("; the run so far is in {}", p.display()))
        .unwrap_or_default()
}

impl LabError {
    /// Whether the failure lies in what the user gave (files, arguments,
    /// configuration, data: exit code 2) rather than in a run that went
    /// wrong (exit code 1).
    pub fn is_bad_input(&self) -> bool {
        use tactrace_sensor::SensorError as S;
        match self {
            LabError::Format { .. }
            | LabError::Reference { .. }
            | LabError::Config(_)
            | LabError::Geometry(_)
            | LabError::Shape3d(_)
            | LabError::TooFewSamples { .. }
            | LabError::StillPins { .. }
            | LabError::Calib(_) => true,
            LabError::Control(e) => {
                !matches!(e, tactrace_control::ControlError::NonFiniteInput { .. })
            }
            LabError::RunFailed { .. }
            | LabError::AllFailed { .. }
            | LabError::NotANumber { .. }
            | LabError::Report(_) => false,
            LabError::Optim(e) => matches!(e, tactrace_optim::OptimError::Config(_)),
            LabError::Store(e) => e.is_bad_input(),
            LabError::Servo(e) => e.is_bad_input(),
            LabError::Sensor(e) => !matches!(e, S::ReplayExhausted { .. }),
            LabError::Vision(_) => true,
            LabError::Learn(e) => !e.is_diverged(),
            LabError::Arm(e) => matches!(e, tactrace_arm::ArmError::InvalidConfig { .. }),
            LabError::Remote(e) => e.is_bad_input(),
            #[cfg(feature = "hardware")]
            LabError::Hardware(e) => matches!(
                e,
                tactrace_hw::HwError::Config { .. }
                    | tactrace_hw::HwError::Preprocess { .. }
                    | tactrace_hw::HwError::CameraMissing { .. }
                    | tactrace_hw::HwError::NotACamera { .. }
            ),
            #[cfg(feature = "hardware")]
            LabError::StartMove { source } => refused(source),
            #[cfg(feature = "hardware")]
            LabError::Interrupted { .. } => false,
        }
    }

    /// For a hardware run stopped by a signal, the exit code of a process
    /// that signal ended (130 SIGINT, 143 SIGTERM); `None` otherwise.
    pub fn signal_exit_code(&self) -> Option<u8> {
        match self {
            #[cfg(feature = "hardware")]
            LabError::Interrupted { signal, .. } => Some(signal.exit_code()),
            _ => None,
        }
    }
}

/// What to do about too few training samples.
fn more_samples_hint(held_out: usize) -> String {
    if held_out > 0 {
        format!(
            "{held_out} more were held out for validation (a smaller --val-fraction, or a \
             separate --val set, leaves more to train on)"
        )
    } else {
        "collect more taps, or lower n_components (--config)".into()
    }
}

/// `; what was tried is in {kept}` when something was kept.
fn kept_suffix(kept: &Option<PathBuf>) -> String {
    kept.as_ref()
        .map(|p| format!("; what was tried is in {}", p.display()))
        .unwrap_or_default()
}

/// `; {hint}` when there is a hint.
fn hint_suffix(hint: &str) -> String {
    if hint.is_empty() {
        String::new()
    } else {
        format!("; {hint}")
    }
}

/// Result with [`LabError`].
pub type Result<T, E = LabError> = std::result::Result<T, E>;

impl From<tactrace_store::collection::CollectionError> for LabError {
    fn from(e: tactrace_store::collection::CollectionError) -> Self {
        LabError::Store(e.into())
    }
}
