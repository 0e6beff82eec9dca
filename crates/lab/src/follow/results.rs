//! What a finished follow run writes besides its trajectory:
//! `metrics.json` (scored against the true contour when it is known, and
//! how the run ended), the trajectory and L2 figures, and `replay.html`
//! (the run step by step, with the taps' pin fields and, in the
//! real-frame world, the frames that answered).
use crate::error::Result;
use crate::world::ReplayStats;
use serde::Serialize;
use std::path::Path;
use tactrace_geometry::{Contour, Vec2};
use tactrace_report::figures;
use tactrace_report::replay_html::{replay_html, PinFields, ReplayPage, StepFrames};
use tactrace_servo::{evaluate, l2_curve, FollowMetrics, LoopConfig, LoopSummary, StepRecord};
use tactrace_store::write_atomic;

/// metrics.json of a follow run: every metric at the top level (the keys
/// scripts read: `mean_l2_mm`, `closed`, `steps`, ...) and how it ended.
#[derive(Serialize)]
struct MetricsDocument<'a> {
    #[serde(flatten)]
    metrics: Option<&'a FollowMetrics>,
    /// The loop's step count when there are no metrics (which have their
    /// own `steps`: one key, not two).
    #[serde(skip_serializing_if = "Option::is_none")]
    steps: Option<usize>,
    ending: tactrace_servo::Ending,
    succeeded: bool,
    message: &'a str,
    /// Why the metrics may say little (a contour smaller than the sensor,
    /// real frames far from the poses reached).
    #[serde(skip_serializing_if = "Option::is_none")]
    warning: Option<String>,
    /// The real-frame world: how near the answered frames' labels were.
    #[serde(skip_serializing_if = "Option::is_none")]
    replay: Option<&'a ReplayStats>,
    /// Whether the model predicted with the mean of each tap's turned
    /// views (`follow --views`, else its file's setting); absent for a
    /// model fitted without rotations.
    #[serde(skip_serializing_if = "Option::is_none")]
    turned_views: Option<bool>,
}

/// What a run knows besides its trajectory: the real-frame world's label
/// distances, and the taps' displacement vectors with the reference pins
/// (px) they are ordered by.
#[derive(Default)]
pub struct RunExtras<'a> {
    pub replay: Option<&'a ReplayStats>,
    pub fields: Option<PinFields<'a>>,
    /// The frames the taps saw (the real-frame world's answers).
    pub frames: Option<StepFrames<'a>>,
    /// The model's turned views at prediction, on or off (`None`: a model
    /// fitted without rotations).
    pub turned_views: Option<bool>,
}

/// The diameter of the real TacTip's dome, mm (the simulated one's is in
/// its configuration).
pub fn tactip_diameter_mm() -> f64 {
    2.0 * tactrace_sensor::SkinGeometry::default().dome_radius_mm
}

/// A contour smaller than the sensor (`sensor_diameter_mm` across) cannot
/// be followed, and its metrics say little: often a contour in metres
/// where millimetres are meant. The warning, if so.
pub fn size_warning(name: &str, contour: &Contour, sensor_diameter_mm: f64) -> Option<String> {
    let (min, max) = contour.bounds();
    let across = (max - min).max();
    (across < sensor_diameter_mm).then(|| {
        format!(
            "the contour {name} is {across:.3} mm across, smaller than the sensor \
             ({sensor_diameter_mm:.0} mm): it cannot be followed and its metrics say \
             little (contours are in millimetres)"
        )
    })
}

/// Score a finished run against the true contour `shape` (named `name`),
/// if known (report ch. 5.3 and beyond), write `metrics.json` and the
/// figures into `dir`. `sensor_diameter_mm` flags contours smaller than
/// the sensor ([`size_warning`]).
pub fn write_results(
    shape: Option<(&str, &Contour)>,
    records: &[StepRecord],
    summary: &LoopSummary,
    follow: &LoopConfig,
    sensor_diameter_mm: f64,
    dir: &Path,
) -> Result<(Option<FollowMetrics>, Vec<f64>)> {
    let extras = RunExtras::default();
    write_results_with(
        shape,
        records,
        summary,
        follow,
        sensor_diameter_mm,
        dir,
        &extras,
    )
}

/// As [`write_results`], with what else the run knows (`extras`).
pub fn write_results_with(
    shape: Option<(&str, &Contour)>,
    records: &[StepRecord],
    summary: &LoopSummary,
    follow: &LoopConfig,
    sensor_diameter_mm: f64,
    dir: &Path,
    extras: &RunExtras,
) -> Result<(Option<FollowMetrics>, Vec<f64>)> {
    let traj: Vec<Vec2> = records
        .iter()
        .map(|r| Vec2::new(r.pose.x, r.pose.y))
        .collect();
    let scored = shape.map(|(name, contour)| {
        let m = evaluate(
            contour,
            &traj,
            follow.close_radius_mm,
            follow.min_excursion_mm,
        );
        (name, contour, m, l2_curve(contour, &traj, 1000))
    });
    let document = MetricsDocument {
        metrics: scored.as_ref().map(|s| &s.2),
        steps: scored.is_none().then_some(summary.steps),
        ending: summary.ending,
        succeeded: summary.ending.succeeded(),
        message: &summary.message,
        warning: join_warnings([
            shape.and_then(|(name, c)| size_warning(name, c, sensor_diameter_mm)),
            extras.replay.and_then(ReplayStats::warning),
        ]),
        replay: extras.replay,
        turned_views: extras.turned_views,
    };
    let json = serde_json::to_string_pretty(&document).expect("metrics serialise");
    write_atomic(&dir.join("metrics.json"), json.as_bytes())?;
    let page = ReplayPage {
        title: &format!("{} ({})", shape.map_or("run", |s| s.0), world_name(extras)),
        contour: shape.map(|s| s.1),
        steps: records,
        sensor_radius_mm: sensor_diameter_mm / 2.0,
        fields: extras.fields,
        frames: extras.frames,
        notes: &page_notes(&document, extras),
    };
    write_atomic(&dir.join("replay.html"), replay_html(&page).as_bytes())?;
    let Some((name, contour, metrics, curve)) = scored else {
        return Ok((None, Vec::new()));
    };
    if !records.is_empty() {
        let xy: Vec<(f64, f64)> = traj.iter().map(|p| (p.x, p.y)).collect();
        figures::trajectory(&dir.join("trajectory"), name, contour, &xy)?;
        figures::error_curve(&dir.join("l2_error"), name, contour, &curve)?;
    }
    Ok((Some(metrics), curve))
}

/// Which world the run was in, for the replay page's title.
fn world_name(extras: &RunExtras) -> &'static str {
    if extras.replay.is_some() {
        "real-frame world"
    } else {
        "follow run"
    }
}

/// The replay page's summary lines: how the run ended, its metrics, its
/// label distances and warnings.
fn page_notes(doc: &MetricsDocument, extras: &RunExtras) -> Vec<String> {
    let mut notes = vec![format!("{}: {}", doc.ending, doc.message)];
    if let Some(m) = doc.metrics {
        notes.push(format!(
            "{} steps; mean L2 {:.3} mm, track error mean {:.3} / max {:.3} mm, coverage {:.0}%, closed: {}",
            m.steps,
            m.mean_l2_mm,
            m.mean_track_error_mm,
            m.max_track_error_mm,
            100.0 * m.coverage,
            m.closed
        ));
    }
    notes.extend(extras.replay.map(ReplayStats::summary));
    notes.extend(doc.warning.iter().map(|w| format!("warning: {w}")));
    notes
}

/// The warnings given, as one (`None` when there are none).
fn join_warnings<const N: usize>(warnings: [Option<String>; N]) -> Option<String> {
    let all: Vec<String> = warnings.into_iter().flatten().collect();
    (!all.is_empty()).then(|| all.join("; "))
}
