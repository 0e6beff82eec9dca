//! Typed errors of the optimiser.

/// What can be wrong with an optimisation's set-up or input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OptimError {
    /// A start point, step size or population that cannot work.
    #[error("CMA-ES: {0}")]
    Config(String),
    /// `tell` got a different number of costs than `ask` gave points.
    #[error("CMA-ES: {got} costs for a generation of {expected} points")]
    Generation { expected: usize, got: usize },
    /// A TPE search space or setting that cannot work.
    #[error("TPE: {0}")]
    Tpe(String),
}
