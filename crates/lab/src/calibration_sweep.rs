//! `reproduce --real`: the simulator calibrated with few real taps
//! (docs/calibration.md). For 10, 30, 100 and all taps of the real
//! training part, and for the r and theta cross-splits (calibration taps
//! from one half of the range, scored on the other), `tactrace calibrate`
//! fits the sensor, `twin --sensor` makes its training set, and a PDenNN
//! trained on it is scored on held-out real frames, beside the twin's
//! field misfit on those frames before and after the correction.
use crate::calibrate::{calibrate_sensor, write_calibrated, CalibrateConfig};
use crate::error::Result;
use crate::reproduce::{rows_not_in, train_and_score, ReproduceConfig};
use crate::twin::{simulate_twin_calibrated, twin_rows};
use rayon::prelude::*;
use std::collections::HashSet;
use std::path::Path;
use tactrace_learn::ModelKind;
use tactrace_report::{CalibrationRow, NetRow};
use tactrace_store::{LabelledCollection, TapData};

/// Which labels a part keeps: (r mm, theta deg) -> kept.
type LabelFilter = fn(f32, f32) -> bool;

/// One calibration to run and score.
struct Case {
    /// Folder name under `calibration/`.
    folder: &'static str,
    taps: Option<usize>,
    pool: (&'static str, LabelFilter),
    scored: (&'static str, LabelFilter),
}

const ANY: LabelFilter = |_, _| true;

/// The cases of the table, in its order.
fn cases() -> Vec<Case> {
    let whole = |folder, taps| Case {
        folder,
        taps,
        pool: ("training part", ANY),
        scored: ("validation part", ANY),
    };
    vec![
        whole("taps-10", Some(10)),
        whole("taps-30", Some(30)),
        whole("taps-100", Some(100)),
        whole("taps-all", None),
        Case {
            folder: "cross-r",
            taps: Some(100),
            pool: ("training part, r < 0", |r, _| r < 0.0),
            scored: ("validation part, r > 0", |r, _| r > 0.0),
        },
        Case {
            folder: "cross-theta",
            taps: Some(100),
            pool: ("training part, theta < 0", |_, t| t < 0.0),
            scored: ("validation part, theta > 0", |_, t| t > 0.0),
        },
    ]
}

impl Case {
    fn name(&self) -> String {
        let taps = self.taps.map_or("all".into(), |n| n.to_string());
        format!("{taps} taps from the {}", self.pool.0)
    }

    /// The headline case: its sensor is kept as `sensor/` with the
    /// before/after figure, and its row joins the simulated-to-real table.
    fn is_headline(&self) -> bool {
        self.taps == Some(100) && self.pool.0 == "training part"
    }
}

/// The real split, the collection it was imported from (whose labels the
/// twins replay) and the twins' rendering seed.
pub(crate) struct Split<'a> {
    pub collection: &'a LabelledCollection,
    pub render_seed: u64,
    pub training: &'a TapData,
    pub validation: &'a TapData,
}

/// Every case of [`cases`], in parallel; returns the table's rows and the
/// headline case's row for the simulated-to-real table.
pub(crate) fn calibration_rows(
    cfg: &ReproduceConfig,
    split: &Split,
    out: &Path,
) -> Result<(Vec<CalibrationRow>, NetRow)> {
    let done: Vec<Result<(CalibrationRow, NetRow, bool)>> = cases()
        .par_iter()
        .map(|case| {
            let (row, net) = run_case(cfg, split, case, out)?;
            Ok((row, net, case.is_headline()))
        })
        .collect();
    let mut rows = Vec::new();
    let mut headline = None;
    for d in done {
        let (row, net, is_headline) = d?;
        if is_headline {
            headline = Some(net);
        }
        rows.push(row);
    }
    Ok((rows, headline.expect("the case list has a headline case")))
}

/// The label rows (CSV data-row indices) whose image is in `part` and
/// whose labels `keep` accepts.
fn rows_in(split: &Split, part: &TapData, keep: LabelFilter) -> Result<Vec<usize>> {
    let names: HashSet<&str> = part.meta.images.iter().map(String::as_str).collect();
    Ok(twin_rows(split.collection)?
        .iter()
        .filter(|row| names.contains(row.image.as_str()) && keep(row.targets[0], row.targets[1]))
        .map(|row| row.index)
        .collect())
}

/// The rows of `part` whose targets `keep` accepts.
fn part_where(part: &TapData, keep: LabelFilter) -> TapData {
    let rows: Vec<usize> = (0..part.len())
        .filter(|&i| keep(part.targets[2 * i], part.targets[2 * i + 1]))
        .collect();
    part.subset(&rows)
}

fn run_case(
    cfg: &ReproduceConfig,
    split: &Split,
    case: &Case,
    out: &Path,
) -> Result<(CalibrationRow, NetRow)> {
    let ccfg = CalibrateConfig {
        collection: split.collection.clone(),
        render_seed: split.render_seed,
        samples: case.taps,
        seed: cfg.seed,
        allowed_rows: Some(rows_in(split, split.training, case.pool.1)?),
        score_rows: Some(rows_in(split, split.validation, case.scored.1)?),
        fit_physics: false,
        labelled_depth: false,
        pin_jitter: Default::default(),
    };
    let got = calibrate_sensor(&ccfg, &cfg.follow.rig.sensor, &|| {})?;
    let dir = out.join("calibration").join(case.folder);
    let sensor_dir = if case.is_headline() {
        out.join("sensor")
    } else {
        dir.join("sensor")
    };
    write_calibrated(&got, &sensor_dir, true)?;
    let twin = simulate_twin_calibrated(
        split.collection,
        &got.sensor,
        split.render_seed,
        (true, None),
        &|| {},
    )?;
    let training = rows_not_in(&twin.data, split.validation);
    let scored = part_where(split.validation, case.scored.1);
    let name = if case.is_headline() {
        "PDenNN (calibrated sensor, 100 taps)".to_string()
    } else {
        format!("PDenNN (calibrated sensor, {})", case.name())
    };
    let (net, _) = train_and_score(ModelKind::PDenNN, &name, cfg, &training, &scored, &dir)?;
    let record = &got.sensor.spec.calibration;
    let (before, after) = (&record.held_out_before, &record.held_out_after);
    let row = CalibrationRow {
        taps: case.taps,
        taps_used: record.selection.indices.len(),
        pool: case.pool.0.into(),
        scored_on: case.scored.0.into(),
        position_mae_mm: net.position_mae_mm,
        angle_mae_deg: net.angle_mae_deg,
        field_rms_before_px: before.as_ref().map(|s| s.rms_px),
        field_rms_after_px: after.as_ref().map(|s| s.rms_px),
        cosine_before: before.as_ref().map(|s| s.mean_cosine),
        cosine_after: after.as_ref().map(|s| s.mean_cosine),
    };
    Ok((row, net))
}
