//! tactrace's pictures and documents: the only user of plotters and fonts.
//!
//! [`plot`] is a small plotting vocabulary (charts, grids, pin pictures);
//! [`figures`] draws the report's figures with it; [`document`] writes
//! `reproduce`'s report.md, a self-contained report.html ([`html`]) and
//! metrics.json from the measured [`results`]; [`replay_html`] writes a
//! follow run's interactive, self-contained replay page.

pub mod document;
pub mod document3d;
pub mod error;
pub mod figures;
pub mod html;
pub mod plot;
pub mod replay_3d;
pub mod replay_html;
pub mod results;

pub use error::{ReportError, Result};
pub use results::{CalibrationRow, NetRow, ReplayShapeRow, ReproduceResults, ShapeRow};
