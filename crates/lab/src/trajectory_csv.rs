//! A follow run's `trajectory.csv`, written step by step as the loop runs:
//! every row whole and flushed ([`tactrace_store::row_file`]), so a run
//! stopped by a full disk or a kill leaves whole rows in `OUT.partial`.
use std::path::Path;
use tactrace_servo::{StepRecord, StepSink};
use tactrace_store::row_file::{RowFile, Truncate};

/// The trajectory's columns.
pub const HEADER: [&str; 8] = [
    "step",
    "x_mm",
    "y_mm",
    "angle_deg",
    "r_pred_mm",
    "theta_pred_deg",
    "mean_displacement_px",
    "contact",
];

/// Writes each step to `trajectory.csv` as it happens.
pub struct TrajectoryCsv<W: Truncate>(RowFile<W>);

impl TrajectoryCsv<std::fs::File> {
    /// Create `path` with its header row.
    pub fn create(path: &Path) -> tactrace_store::Result<Self> {
        Self::new(RowFile::create(path)?)
    }
}

impl<W: Truncate> TrajectoryCsv<W> {
    /// The trajectory into `rows` (empty), starting with the header.
    pub fn new(mut rows: RowFile<W>) -> tactrace_store::Result<Self> {
        rows.write_row(HEADER)?;
        Ok(Self(rows))
    }
}

type SinkResult = std::result::Result<(), Box<dyn std::error::Error + Send + Sync>>;

impl<W: Truncate> StepSink for TrajectoryCsv<W> {
    fn on_step(&mut self, r: &StepRecord) -> SinkResult {
        let p = &r.percept;
        let f = |v: f64| format!("{v:.4}");
        self.0.write_row([
            r.step.to_string(),
            f(r.pose.x),
            f(r.pose.y),
            f(r.pose.rz),
            f(p.r_mm),
            f(p.theta_deg),
            f(p.mean_displacement_px),
            p.contact.to_string(),
        ])?;
        Ok(())
    }
}
