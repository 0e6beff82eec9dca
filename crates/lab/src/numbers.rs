//! Results are numbers: every error, loss or metric a command reports as
//! its result is checked finite before the command calls it a success. A
//! NaN mean absolute error (a degenerate model or dataset) or a NaN track
//! error (a run with no step) is a [`LabError::NotANumber`], exit code 1.
use crate::error::{LabError, Result};
use tactrace_servo::FollowMetrics;

/// Error naming the first of `values` (`(name, value)`) that is NaN or
/// infinite; `what` says whose results they are, `hint` what to do.
pub fn require_finite(what: &str, values: &[(&str, f64)], hint: &str) -> Result<()> {
    match values.iter().find(|(_, v)| !v.is_finite()) {
        None => Ok(()),
        Some((metric, value)) => Err(LabError::NotANumber {
            what: what.to_string(),
            metric: (*metric).to_string(),
            value: *value,
            hint: hint.to_string(),
        }),
    }
}

/// A follow run's metrics by name, as in metrics.json.
pub fn follow_metrics(m: &FollowMetrics) -> [(&'static str, f64); 7] {
    [
        ("mean_l2_mm", m.mean_l2_mm),
        ("max_l2_mm", m.max_l2_mm),
        ("mean_track_error_mm", m.mean_track_error_mm),
        ("p95_track_error_mm", m.p95_track_error_mm),
        ("max_track_error_mm", m.max_track_error_mm),
        ("coverage", m.coverage),
        ("path_length_mm", m.path_length_mm),
    ]
}

/// Error unless every metric of the run on `shape` is a number.
pub fn require_finite_run(shape: &str, m: &FollowMetrics) -> Result<()> {
    require_finite(
        &format!("the run on {shape}"),
        &follow_metrics(m),
        "the run has no step to score",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_value_that_is_not_a_number_is_named() {
        let ok = [("a", 1.0), ("b", 0.0)];
        require_finite("x", &ok, "").unwrap();
        let bad = [("a", 1.0), ("position MAE", f64::NAN), ("c", f64::INFINITY)];
        let err = require_finite("validation", &bad, "retrain").unwrap_err();
        assert!(!err.is_bad_input(), "a failed result, exit 1");
        assert_eq!(
            err.to_string(),
            "validation: position MAE is NaN, not a number; retrain"
        );
    }

    #[test]
    fn a_run_without_a_step_has_no_metric_to_report() {
        let disk = tactrace_geometry::builtin_shape(tactrace_geometry::BuiltinShape::Disk);
        let empty = tactrace_servo::evaluate(&disk, &[], 3.0, 10.0);
        let err = require_finite_run("disk", &empty).unwrap_err();
        assert!(err.to_string().starts_with("the run on disk: "), "{err}");
        let one = tactrace_servo::evaluate(&disk, &[disk.at_arc_length(0.0).0], 3.0, 10.0);
        require_finite_run("disk", &one).unwrap();
    }
}
