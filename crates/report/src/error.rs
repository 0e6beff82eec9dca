//! Typed errors of the figures and documents.

/// Why a figure or document could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    #[error(transparent)]
    Store(#[from] tactrace_store::StoreError),
    /// The pins of a frame to draw could not be extracted.
    #[error(transparent)]
    Vision(#[from] tactrace_vision::VisionError),
}

/// Result with [`ReportError`].
pub type Result<T, E = ReportError> = std::result::Result<T, E>;
