//! The learning crate's one error type, so callers can tell bad data from a
//! bad model file from a bad configuration without parsing strings.
use thiserror::Error;

/// Everything that can go wrong while fitting, predicting or (de)serialising.
#[derive(Debug, Error)]
pub enum LearnError {
    /// A buffer does not have the length its declared shape implies.
    #[error("{what}: expected {expected} values, got {got}")]
    Shape {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    /// A dataset needs at least one sample and one column.
    #[error("empty dataset ({n} samples, {dim_x} inputs, {dim_y} targets)")]
    Empty {
        n: usize,
        dim_x: usize,
        dim_y: usize,
    },
    /// A value in the data is NaN or infinite.
    #[error("non-finite {what} value {value} at row {row}, column {column}")]
    NonFinite {
        what: &'static str,
        row: usize,
        column: usize,
        value: f32,
    },
    /// The input vector handed to a model has the wrong length.
    #[error("dimension mismatch: the model expects {expected} inputs, got {got}")]
    DimensionMismatch { expected: usize, got: usize },
    /// A configuration value is out of range.
    #[error("invalid configuration: {field}: {reason}")]
    Config { field: &'static str, reason: String },
    /// A value of one net's table (`[position]`, `[angle]`, `[pose]`) is
    /// out of range: `field` is the key of that table.
    #[error("invalid configuration: [{net}] {field}: {reason}")]
    NetConfig {
        net: &'static str,
        field: &'static str,
        reason: String,
    },
    /// Fewer training samples than the model can be fitted on
    /// ([`crate::ModelConfig::min_train_samples`]).
    #[error("too few training samples ({got}): at least {needed} are needed ({reason})")]
    TooFewSamples {
        got: usize,
        needed: usize,
        reason: String,
    },
    /// A serialised model has another format version.
    #[error(
        "model format version {found} is not supported (this build reads version {supported})"
    )]
    Version { found: u32, supported: u32 },
    /// A target list a model cannot have (none, a name twice, a circular
    /// target not in degrees), or data whose targets are not the model's.
    #[error("targets: {reason}")]
    Targets { reason: String },
    /// A model asked for the edge pose `[r, theta]` whose targets are not
    /// one position (mm) and one angle (deg), nor mark one of each.
    #[error(
        "the model predicts {targets}, not an edge pose: one position in mm and one angle \
         in deg, or, beside other targets, one of each marked at import (`--target \
         COLUMN:mm:position`, `--target COLUMN:deg[:circular]:angle`)"
    )]
    NotAnEdgeModel { targets: String },
    /// The image model's network (bad frames, configuration, file; or
    /// a fit that diverged: [`LearnError::is_diverged`]).
    #[error(transparent)]
    Image(#[from] tactrace_convnet::ConvError),
    /// A serialised model could not be parsed or is inconsistent.
    #[error("corrupt model data: {reason}")]
    Corrupt { reason: String },
    /// Training diverged (learning rate or beta too large): non-finite
    /// weights or loss, or a loss above `limit`, the divergence limit
    /// (`trainer::divergence_limit`; infinite when the loss is not finite).
    #[error(
        "training diverged in network {net} at epoch {epoch}: loss {loss:.4e} {}; \
         lower the learning rate (or beta), e.g. with --config",
        diverged_because(*.loss, *.limit)
    )]
    Diverged {
        net: String,
        epoch: usize,
        loss: f64,
        limit: f64,
    },
}

impl LearnError {
    /// Whether training diverged (a run that failed, not bad input).
    pub fn is_diverged(&self) -> bool {
        match self {
            LearnError::Diverged { .. } => true,
            LearnError::Image(e) => !e.is_bad_input(),
            _ => false,
        }
    }
}

/// Why a loss counts as diverged, for [`LearnError::Diverged`].
fn diverged_because(loss: f64, limit: f64) -> String {
    if !loss.is_finite() {
        "is not a finite number (or the weights are not)".into()
    } else if limit.is_finite() {
        format!(
            "exceeds {limit:.4e}, {} times the loss of predicting the training mean \
             (at least 0.5 a target)",
            crate::trainer::DIVERGENCE_FACTOR
        )
    } else {
        "with non-finite weights".into()
    }
}
