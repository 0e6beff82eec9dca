//! What every 3D run (surface or edge, simulated or in the real-frame
//! world) writes the same way: the trajectory's pose columns,
//! `metrics.json` (the run's scores with how the loop ended), the 3D
//! figure over the object's wire mesh, the error curves, `replay.html`,
//! and the means the scores are made of.
use crate::error::Result;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use tactrace_arm::Pose;
use tactrace_report::plot::{chart, chart_3d, Axes, Chart3d, Series, Style};
use tactrace_report::replay_3d::{replay_3d_html, Replay3dPage, Replay3dStep};
use tactrace_report::ReportError;
use tactrace_servo::{Ending, LoopSummary, Step3d};
use tactrace_shape3d::{surface_point, Surface, Vec3};
use tactrace_store::write_atomic;

/// A trajectory's commanded pose columns (every 3D run's).
pub(super) const POSE_COLUMNS: [&str; 6] = ["x_mm", "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg"];

/// A trajectory's last columns: the pose the arm reached (every 3D run's).
pub(super) const REACHED_COLUMNS: [&str; 6] = [
    "x_reached_mm",
    "y_reached_mm",
    "z_reached_mm",
    "rx_reached_deg",
    "ry_reached_deg",
    "rz_reached_deg",
];

/// A pose's six cells (mm, deg) for a trajectory row.
pub(super) fn pose_cells(p: Pose) -> impl Iterator<Item = String> {
    [p.x, p.y, p.z, p.rx, p.ry, p.rz]
        .into_iter()
        .map(|v| format!("{v:.4}"))
}

/// `metrics.json`: a run's scores, then how its loop ended.
#[derive(Serialize)]
struct MetricsDocument<'a, M: Serialize> {
    #[serde(flatten)]
    metrics: &'a M,
    ending: Ending,
    succeeded: bool,
    message: &'a str,
}

/// Write `dir/metrics.json`: `metrics` beside the loop's ending, whether
/// it succeeded and its message.
pub(super) fn write_metrics(
    dir: &Path,
    metrics: &impl Serialize,
    summary: &LoopSummary,
) -> Result<()> {
    let doc = MetricsDocument {
        metrics,
        ending: summary.ending,
        succeeded: summary.ending.succeeded(),
        message: &summary.message,
    };
    let json = serde_json::to_string_pretty(&doc).expect("metrics serialise");
    write_atomic(&dir.join("metrics.json"), json.as_bytes())?;
    Ok(())
}

/// `dir/trajectory_3d.svg/.png`: the `paths` (named point lists, mm) over
/// the `wire` lines.
pub(super) fn write_chart_3d(
    dir: &Path,
    title: &str,
    wire: &[Vec<[f64; 3]>],
    paths: &[(&str, Vec<[f64; 3]>)],
) -> Result<()> {
    chart_3d(&dir.join("trajectory_3d"), &Chart3d { title, wire, paths })
        .map_err(ReportError::from)?;
    Ok(())
}

/// A named error curve: what it plots of each step's truth.
pub(super) type ErrorCurve<'a, T> = (&'a str, &'a dyn Fn(&T) -> f64);

/// `dir/errors.svg/.png`: each of `curves` over the steps' `truths`, under
/// `title`.
pub(super) fn write_error_curves<T>(
    dir: &Path,
    title: &str,
    truths: &[T],
    curves: &[ErrorCurve<'_, T>],
) -> Result<()> {
    let series: Vec<Series> = curves
        .iter()
        .map(|(label, f)| Series {
            name: (*label).into(),
            points: truths
                .iter()
                .enumerate()
                .map(|(i, t)| (i as f64, f(t)))
                .collect(),
            style: Style::Line,
        })
        .collect();
    let axes = Axes::new(title, "step", "mm / deg");
    chart(&dir.join("errors"), &axes, &series).map_err(ReportError::from)?;
    Ok(())
}

/// The mean and the largest of a score over the scored steps (0 for
/// none).
pub(super) struct Scored<'a, T>(pub &'a [T]);

impl<T> Scored<'_, T> {
    /// The mean of `f` over the scored steps.
    pub fn mean(&self, f: impl Fn(&T) -> f64) -> f64 {
        self.0.iter().map(f).sum::<f64>() / self.0.len().max(1) as f64
    }

    /// The largest `f` over the scored steps, at least 0.
    pub fn max(&self, f: impl Fn(&T) -> f64) -> f64 {
        self.0.iter().map(f).fold(0.0, f64::max)
    }
}

/// The model's mean absolute error of each component `sensed`, by its
/// name (`tactrace_control::COMPONENTS`); `errors(k)` are component k's
/// absolute errors over the scored steps.
pub(super) fn mean_abs_errors(
    sensed: [bool; 6],
    errors: impl Fn(usize) -> Vec<f64>,
) -> BTreeMap<&'static str, f64> {
    let mut means = BTreeMap::new();
    for k in (0..6).filter(|k| sensed[*k]) {
        let errs = errors(k);
        let m = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
        means.insert(tactrace_control::COMPONENTS[k], m);
    }
    means
}

/// Lines of the surface every 5 mm over the path's box widened by 20 mm.
pub(super) fn wire_mesh(object: &Surface, steps: &[Step3d]) -> Vec<Vec<[f64; 3]>> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for s in steps {
        for (k, v) in [s.pose.x, s.pose.y].into_iter().enumerate() {
            lo[k] = lo[k].min(v - 20.0);
            hi[k] = hi[k].max(v + 20.0);
        }
    }
    if !(lo[0].is_finite() && hi[0].is_finite()) {
        return Vec::new();
    }
    let ticks = |k: usize| {
        let n = ((hi[k] - lo[k]) / 5.0).ceil() as usize;
        (0..=n).map(move |i| lo[k] + i as f64 * 5.0)
    };
    let at = |x: f64, y: f64| surface_point(object.as_ref(), x, y).map(|q| [q.x, q.y, q.z]);
    let mut lines: Vec<Vec<[f64; 3]>> = Vec::new();
    for x in ticks(0) {
        lines.push(ticks(1).filter_map(|y| at(x, y)).collect());
    }
    for y in ticks(1) {
        lines.push(ticks(0).filter_map(|x| at(x, y)).collect());
    }
    lines.retain(|l| l.len() > 1);
    lines
}

/// `replay.html` of a 3D run: every step's pose (position and the sensor's
/// axis) and label, beside its true depth error (mm) and normal error
/// (deg) from `errors`, over the object's wire mesh.
pub(super) fn write_replay_page(
    dir: &Path,
    title: &str,
    wire: &[Vec<[f64; 3]>],
    steps: &[Step3d],
    errors: impl Iterator<Item = (f64, f64)>,
) -> Result<()> {
    let page_steps: Vec<Replay3dStep> = steps
        .iter()
        .zip(errors)
        .map(|(s, (depth_error_mm, normal_error_deg))| {
            let axis = s.pose.to_isometry().rotation * Vec3::z();
            Replay3dStep {
                pose: [s.pose.x, s.pose.y, s.pose.z, axis.x, axis.y, axis.z],
                label: s.label,
                depth_error_mm,
                normal_error_deg,
            }
        })
        .collect();
    let html = replay_3d_html(&Replay3dPage {
        title,
        wire,
        steps: &page_steps,
    });
    write_atomic(&dir.join("replay.html"), html.as_bytes())?;
    Ok(())
}
