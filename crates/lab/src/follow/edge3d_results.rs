//! What an edge run writes and how it is scored against the object's edge
//! curve (which the loop never sees): `trajectory.csv` row by row with the
//! true errors beside the prediction, then `metrics.json`, the 3D figure
//! (`trajectory_3d.svg/.png`: the edge, the surface's wire mesh and the
//! tip's path), the error curves (`errors.svg/.png`) and `replay.html`.
//!
//! The truth at a pose the arm reached (its repeatability noise included;
//! the commanded poses are in `trajectory.csv` beside them), from the
//! edge sample nearest its pole:
//! the pose in that sample's edge frame ([`tactrace_shape3d::EdgeSample::frame`]) is the
//! true label (x across the edge, z the depth, rx, ry, rz), as the
//! collection's labels. Metrics, over the steps after `settle_steps`:
//! - `mean_distance_mm`, `max_distance_mm`: the distance of the tip from
//!   the edge curve, the tip being the dome's pole moved back the
//!   reference depth along the sensor's axis (where the undeformed dome
//!   first touches: on the edge when the pose is the reference);
//! - `mean_offset_mm` (|true x - reference x|) and `mean_depth_error_mm`
//!   (|true depth - reference depth|), the distance's two parts;
//! - `mean_normal_error_deg`, `max_normal_error_deg`: the angle between
//!   the sensor's axis and the pressed face's normal at that sample;
//! - `coverage`: the fraction of the edge's samples passed (each step
//!   within 3 mm of the edge marks the samples between its nearest one and
//!   the previous step's, the shorter way round), all steps;
//! - `closed`: the loop stopped by closing (came back to its start);
//! - `mean_abs_error`: the model's error per sensed component against the
//!   true label (rz wrapped to +-180 deg).
use super::edge3d::Edge3dConfig;
use super::recorder3d::StepRows;
use super::results3d::{
    mean_abs_errors, pose_cells, wire_mesh, write_chart_3d, write_error_curves, write_metrics,
    write_replay_page, Scored, POSE_COLUMNS, REACHED_COLUMNS,
};
use crate::error::Result;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use tactrace_arm::Pose;
use tactrace_learn::wrap_deg;
use tactrace_servo::{lifted, Ending, LoopSummary, Step3d};
use tactrace_shape3d::{EdgeCurve, Surface, Vec3};
use tactrace_store::row_file::RowFile;

/// An edge run's scores (see the module header).
#[derive(Debug, Clone, Serialize)]
pub struct Edge3dMetrics {
    pub task: &'static str,
    pub object: String,
    pub steps: usize,
    pub settle_steps: usize,
    pub mean_distance_mm: f64,
    pub max_distance_mm: f64,
    pub mean_offset_mm: f64,
    pub mean_depth_error_mm: f64,
    pub mean_normal_error_deg: f64,
    pub max_normal_error_deg: f64,
    pub coverage: f64,
    pub closed: bool,
    pub path_length_mm: f64,
    pub edge_length_mm: f64,
    /// The model's mean absolute error per sensed component (mm, deg).
    pub mean_abs_error: BTreeMap<&'static str, f64>,
}

/// The truth at one (reached) pose.
#[derive(Debug, Clone, Copy)]
pub struct EdgeTruth {
    /// The index of the edge sample nearest the pole.
    pub sample: usize,
    /// The tip's distance from the edge curve, mm.
    pub distance_mm: f64,
    /// The true label in the edge frame (x, y, z mm with z the depth; rx,
    /// ry, rz deg).
    pub label: [f64; 6],
    /// The angle between the sensor's axis and the face normal, deg.
    pub normal_error_deg: f64,
    /// The tip (the pole moved back the reference depth), mm.
    pub tip: Vec3,
}

/// The truth of `pose` against `edge` for the reference `reference`.
pub fn edge_truth(edge: &EdgeCurve, pose: Pose, reference: [f64; 6]) -> EdgeTruth {
    let p = Vec3::new(pose.x, pose.y, pose.z);
    let sample = (0..edge.samples.len())
        .min_by(|a, b| {
            let d = |k: &usize| (edge.samples[*k].point - p).norm_squared();
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    let s = &edge.samples[sample];
    let local = Pose::from_isometry(&(s.frame().inverse() * pose.to_isometry()));
    let tip = lifted(pose, reference[2]);
    let tip = Vec3::new(tip.x, tip.y, tip.z);
    let axis = pose.to_isometry().rotation * Vec3::z();
    EdgeTruth {
        sample,
        distance_mm: edge.distance(tip),
        label: [local.x, local.y, -local.z, local.rx, local.ry, local.rz],
        normal_error_deg: axis.angle(&s.normals[0]).to_degrees(),
        tip,
    }
}

/// `trajectory.csv` of an edge run, a whole row flushed per step.
pub struct EdgeCsv {
    rows: RowFile<std::fs::File>,
    edge: EdgeCurve,
    reference: [f64; 6],
}

impl EdgeCsv {
    /// `dir/trajectory.csv` with its header.
    pub fn create(dir: &Path, edge: &EdgeCurve, reference: [f64; 6]) -> Result<Self> {
        let mut rows = RowFile::create(&dir.join("trajectory.csv"))?;
        let pred = ["x_pred_mm", "z_pred_mm", "rx_pred_deg", "ry_pred_deg"];
        let rest = [
            "rz_pred_deg",
            "mean_displacement_px",
            "contact",
            "distance_mm",
            "x_true_mm",
            "depth_true_mm",
            "rz_true_deg",
            "normal_error_deg",
        ];
        let header = ["step"]
            .iter()
            .chain(&POSE_COLUMNS)
            .chain(&pred)
            .chain(&rest)
            .chain(&REACHED_COLUMNS);
        rows.write_row(header.copied())?;
        Ok(Self {
            rows,
            edge: edge.clone(),
            reference,
        })
    }
}

impl StepRows for EdgeCsv {
    /// One step's row: the commanded pose and prediction, then the truth
    /// at `reached` (the pose the arm reached) and that pose.
    fn write(&mut self, s: &Step3d, reached: Pose) -> tactrace_store::Result<()> {
        let t = edge_truth(&self.edge, reached, self.reference);
        let (p, l) = (s.pose, s.label);
        let nums = [
            p.x, p.y, p.z, p.rx, p.ry, p.rz, l[0], l[2], l[3], l[4], l[5],
        ];
        let mut row = vec![s.step.to_string()];
        row.extend(nums.iter().map(|v| format!("{v:.4}")));
        row.push(format!("{:.4}", s.mean_displacement_px));
        row.push(s.contact.to_string());
        let truth = [t.distance_mm, t.label[0], t.label[2], t.label[5]];
        row.extend(truth.iter().map(|v| format!("{v:.4}")));
        row.push(format!("{:.4}", t.normal_error_deg));
        row.extend(pose_cells(reached));
        self.rows.write_row(row)
    }
}

/// Score the run at the poses the arm reached (`reached`, one per step)
/// and write `metrics.json`, the figures and `replay.html` into `dir`.
pub fn write_edge_results(
    dir: &Path,
    (name, object, edge): (&str, &Surface, &EdgeCurve),
    cfg: &Edge3dConfig,
    (steps, reached): (&[Step3d], &[Pose]),
    summary: &LoopSummary,
) -> Result<Edge3dMetrics> {
    let reference = cfg.controller.reference;
    let truths: Vec<EdgeTruth> = reached
        .iter()
        .map(|p| edge_truth(edge, *p, reference))
        .collect();
    let metrics = score(name, cfg, (edge, steps, &truths), summary);
    write_metrics(dir, &metrics, summary)?;
    let task = cfg.controller.task;
    let mut wire = wire_mesh(object, steps);
    let mut rim: Vec<[f64; 3]> = edge
        .samples
        .iter()
        .map(|s| [s.point.x, s.point.y, s.point.z])
        .collect();
    if edge.closed {
        rim.extend(rim.first().copied());
    }
    wire.push(rim);
    if !steps.is_empty() {
        let title = format!("{task} round the {name}'s edge");
        let tips: Vec<[f64; 3]> = truths.iter().map(|t| [t.tip.x, t.tip.y, t.tip.z]).collect();
        write_chart_3d(dir, &title, &wire, &[("sensor tip", tips)])?;
        error_figure(dir, &title, &truths, reference)?;
    }
    let errors = truths
        .iter()
        .map(|t| (t.label[2] - reference[2], t.normal_error_deg));
    let title = format!("{task} round the {name}'s edge: {}", summary.message);
    write_replay_page(dir, &title, &wire, steps, errors)?;
    Ok(metrics)
}

fn score(
    name: &str,
    cfg: &Edge3dConfig,
    (edge, steps, truths): (&EdgeCurve, &[Step3d], &[EdgeTruth]),
    summary: &LoopSummary,
) -> Edge3dMetrics {
    let reference = cfg.controller.reference;
    let settle = cfg.run.settle_steps.min(truths.len().saturating_sub(1));
    let scored = Scored(&truths[settle.min(truths.len())..]);
    let path_length_mm: f64 = truths
        .windows(2)
        .map(|w| (w[1].tip - w[0].tip).norm())
        .sum();
    let task = cfg.controller.task;
    let steps_scored = &steps[settle.min(steps.len())..];
    let mean_abs_error = mean_abs_errors(task.sensed(), |k| {
        let err = |s: &Step3d, t: &EdgeTruth| {
            let d = s.label[k] - t.label[k];
            if k == 5 {
                wrap_deg(d).abs()
            } else {
                d.abs()
            }
        };
        steps_scored
            .iter()
            .zip(scored.0)
            .map(|(s, t)| err(s, t))
            .collect()
    });
    Edge3dMetrics {
        task: task.name(),
        object: name.to_string(),
        steps: steps.len(),
        settle_steps: settle,
        mean_distance_mm: scored.mean(|t| t.distance_mm),
        max_distance_mm: scored.max(|t| t.distance_mm),
        mean_offset_mm: scored.mean(|t| (t.label[0] - reference[0]).abs()),
        mean_depth_error_mm: scored.mean(|t| (t.label[2] - reference[2]).abs()),
        mean_normal_error_deg: scored.mean(|t| t.normal_error_deg),
        max_normal_error_deg: scored.max(|t| t.normal_error_deg),
        coverage: coverage(edge, truths, summary.ending == Ending::Closed),
        closed: summary.ending == Ending::Closed,
        path_length_mm,
        edge_length_mm: edge.length(),
        mean_abs_error,
    }
}

/// The fraction of the edge's samples passed (see the module header).
fn coverage(edge: &EdgeCurve, truths: &[EdgeTruth], closed: bool) -> f64 {
    const NEAR_MM: f64 = 3.0;
    let n = edge.samples.len();
    if n == 0 {
        return 0.0;
    }
    let mut covered = vec![false; n];
    let mut prev: Option<usize> = None;
    let mark = |from: usize, to: usize, covered: &mut Vec<bool>| {
        let forward = (to + n - from) % n;
        let (start, len) = if !edge.closed {
            (from.min(to), from.abs_diff(to))
        } else if forward <= n - forward {
            (from, forward)
        } else {
            (to, n - forward)
        };
        for k in 0..=len {
            covered[(start + k) % n] = true;
        }
    };
    for t in truths {
        if t.distance_mm > NEAR_MM {
            prev = None;
            continue;
        }
        mark(prev.unwrap_or(t.sample), t.sample, &mut covered);
        prev = Some(t.sample);
    }
    if let (true, Some(last), Some(first)) = (closed, prev, truths.first()) {
        if first.distance_mm <= NEAR_MM {
            mark(last, first.sample, &mut covered);
        }
    }
    covered.iter().filter(|c| **c).count() as f64 / n as f64
}

/// The true distance, offset and depth error (mm) and normal error (deg)
/// at every step.
fn error_figure(dir: &Path, title: &str, truths: &[EdgeTruth], reference: [f64; 6]) -> Result<()> {
    let offset = |t: &EdgeTruth| t.label[0] - reference[0];
    let depth_error = |t: &EdgeTruth| t.label[2] - reference[2];
    write_error_curves(
        dir,
        &format!("{title}: true errors"),
        truths,
        &[
            ("distance from the edge (mm)", &|t: &EdgeTruth| {
                t.distance_mm
            }),
            ("offset x (mm)", &offset),
            ("depth error (mm)", &depth_error),
            ("normal error (deg)", &|t: &EdgeTruth| t.normal_error_deg),
        ],
    )
}
