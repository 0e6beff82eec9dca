//! Surface following in the real-frame world (`follow --task surface_3d
//! --replay-data DATASET`): the simulated arm over a 3D object, every tap
//! answered by the bank's row whose labels are nearest the tool's true
//! pose against the surface there (the real collections are taps on a
//! flat surface: over a curved one the sensor never feels the curvature,
//! only the change of pose from tap to tap)
//! ([`crate::world::SurfaceBank`]), read by a model trained on another
//! part of the same collection. The path, controller and scoring are the
//! simulated surface run's ([`super::task3d`]), except that every answer
//! counts as contact (`contact_threshold_px` is not applied: each row is a
//! real tap); the run folder adds
//! `answers.csv` (each tap's row, image and label distance) and
//! `replay.json` (the label distances and the distinct rows).
use super::sim3d::sim_arm_3d;
use super::task3d::{follow_surface, start_pose, Surface3dConfig, Surface3dOutcome};
use super::RunFolder;
use crate::error::{LabError, Result};
use crate::world::{SurfaceAnswer, SurfaceBank};
use serde::Serialize;
use std::path::Path;
use tactrace_control::Task;
use tactrace_servo::{Perception3d, Step3d};
use tactrace_shape3d::{true_label, Surface};
use tactrace_store::row_file::RowFile;
use tactrace_store::{write_atomic, StoredModel};

/// How near the answers were (metrics.json's `replay`).
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceReplayStats {
    pub taps: usize,
    pub mean_label_distance: f64,
    pub max_label_distance: f64,
    pub distinct_rows: usize,
    pub bank_rows: usize,
    /// How many of the bank's rows the model was trained on (null: not
    /// known); above 0 the run's figures are not held-out ones.
    pub bank_rows_seen_in_training: Option<usize>,
}

/// Follow `object` (named `name`) in the real-frame world
/// of `bank` with `model` into `out`; as [`super::task3d::run_surface`].
pub fn run_surface_replay(
    cfg: &Surface3dConfig,
    (object, name): (&Surface, &str),
    bank: &SurfaceBank,
    model: &StoredModel,
    (out, force): (&Path, bool),
    progress: &mut dyn FnMut(&Step3d),
) -> Result<(Surface3dOutcome, SurfaceReplayStats)> {
    cfg.validate()?;
    let _claim = tactrace_store::check_output_dir(out, force)?;
    let start = start_pose(object, cfg)?;
    let (mut arm, probe) = sim_arm_3d(&cfg.run, start)?;
    let pins = bank.reference_pins().to_vec();
    let net = model.for_pins(&pins, Path::new("the bank's dataset"))?;
    // Every row of the bank is a tap in contact (a real frame's pins move
    // less than the simulated ones: 0.2-1 px on the 331-pin set), so the
    // contact threshold is not applied in this world.
    let perception =
        Perception3d::of_fields(pins.clone(), net.clone(), Task::Surface3d.sensed(), 0.0)?;
    let run = RunFolder::start(out, force, cfg)?;
    let mut answers: Vec<SurfaceAnswer> = Vec::new();
    let mut tap = || -> tactrace_servo::Result<tactrace_servo::Sensed> {
        let pose = probe.actual();
        let label = true_label(object.as_ref(), pose).ok_or_else(|| {
            tactrace_servo::ServoError::Config("the sensor faces away from the surface".into())
        })?;
        let answer = bank.nearest([label[2], label[3], label[4]]);
        let field = bank.input(answer.row).to_vec();
        answers.push(answer);
        perception.perceive_field(field)
    };
    let (summary, metrics) = follow_surface(
        cfg,
        (object, name),
        &run,
        (&mut arm, &mut tap, probe.clone()),
        &pins,
        progress,
    )?;
    let stats = write_answers(run.path(), bank, &answers)?;
    let dir = run.finish()?;
    Ok((
        Surface3dOutcome {
            summary,
            metrics,
            dir,
        },
        stats,
    ))
}

/// `answers.csv` and `replay.json` (the label distances) in `dir`.
fn write_answers(
    dir: &Path,
    bank: &SurfaceBank,
    answers: &[SurfaceAnswer],
) -> Result<SurfaceReplayStats> {
    let mut rows = RowFile::create(&dir.join("answers.csv"))?;
    rows.write_row([
        "step",
        "row",
        "image",
        "label_distance",
        "z_mm",
        "rx_deg",
        "ry_deg",
    ])?;
    for (step, a) in answers.iter().enumerate() {
        let l = bank.label(a.row);
        rows.write_row([
            step.to_string(),
            a.row.to_string(),
            bank.image(a.row),
            format!("{:.4}", a.distance),
            format!("{:.4}", l[0]),
            format!("{:.4}", l[1]),
            format!("{:.4}", l[2]),
        ])?;
    }
    let n = answers.len().max(1) as f64;
    let mut distinct: Vec<usize> = answers.iter().map(|a| a.row).collect();
    distinct.sort_unstable();
    distinct.dedup();
    let stats = SurfaceReplayStats {
        taps: answers.len(),
        mean_label_distance: answers.iter().map(|a| a.distance).sum::<f64>() / n,
        max_label_distance: answers.iter().map(|a| a.distance).fold(0.0, f64::max),
        distinct_rows: distinct.len(),
        bank_rows: bank.len(),
        bank_rows_seen_in_training: bank.rows_seen_in_training(),
    };
    if !stats.mean_label_distance.is_finite() {
        return Err(LabError::Config("a label distance is not a number".into()));
    }
    let json = serde_json::to_string_pretty(&stats).expect("stats serialise");
    write_atomic(&dir.join("replay.json"), json.as_bytes())?;
    Ok(stats)
}
