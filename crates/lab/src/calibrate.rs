//! `tactrace calibrate`: fit the simulated TacTip to a user's own labelled
//! taps on a straight edge (docs/calibration.md).
//!
//! The simulator is first laid out like the sensor's rest pins (an
//! undeformed frame's, or a rest layout estimated from the taps:
//! [`crate::sim_sight`], both pin layouts fitted and the better kept).
//! The real frames are imported, their labels replayed on the simulator
//! ([`crate::twin`]: same pin order, the real reference's rest layout),
//! the two joined on the image name, and `tactrace_calib::calibrate` picks
//! the calibration taps by its seeded spanning rule, fits the field
//! correction and scores it on the taps left out. The result is a
//! [`SensorFolder`]: the simulated sensor that `--sensor` gives every
//! command that simulates taps.
use crate::error::{LabError, Result};
use crate::import::{import_rows, Imported};
use crate::pin_jitter::{fit_pin_jitter, with_pin_jitter, PinJitter};
use crate::sim_sight::{lay_out, resolve_reference, sim_sight, LayoutReport, SimSight};
use crate::twin::{simulate_twin_rows, twin_rows};
use std::collections::HashSet;
use std::path::PathBuf;
use tactrace_calib::{
    calibrate, check_labels, field_stats, select_taps, CalibError, CalibrationPlan, Fields, Label,
    Selection, MIN_TAPS, RECOMMENDED_TAPS,
};
use tactrace_sensor::{
    ConventionFit, ConventionSearch, DepthFit, DepthSearch, FitSample, TacTipConfig, TacTipModel,
};
use tactrace_store::collection::{EstimatedRest, Reference};
use tactrace_store::sensor_file::{
    LabelColumnNames, SensorSpec, TrainingRecipe, SENSOR_FORMAT, SENSOR_FORMAT_VERSION,
};
use tactrace_store::{LabelledCollection, LabelledRow, SensorFolder};

/// What to calibrate on.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CalibrateConfig {
    /// The real taps: frames, labels (the edge task's two targets, depth
    /// and shear columns), reference (an undeformed frame, a recorded rest
    /// layout, or one to estimate from the taps) and sensor settings or
    /// blob detector.
    pub collection: LabelledCollection,
    /// Seed of the replayed taps' rendering noise.
    pub render_seed: u64,
    /// Calibration taps to pick (`None`: all, nothing held out).
    pub samples: Option<usize>,
    /// Seed of the tap selection.
    pub seed: u64,
    /// The label rows (indices of the CSV's data rows) that may be used,
    /// for calibration and for scoring it (`None`: all).
    pub allowed_rows: Option<Vec<usize>>,
    /// The label rows that score the fit (`None`: up to [`SCORE_TAPS`]
    /// allowed rows not chosen, drawn with the seed). Chosen rows are
    /// never scored.
    pub score_rows: Option<Vec<usize>>,
    /// Fit the simulator's label convention and mechanics to the chosen
    /// taps (`tactrace_sensor::fit_joint`) before the field correction:
    /// for a sensor unlike the shared one (`--fit-physics`).
    pub fit_physics: bool,
    /// Press each calibration tap to its labelled depth column and fit
    /// the field's gain instead of the depth law
    /// (`tactrace_sensor::DepthSearch::labelled_depth`, `--labelled-depth`).
    pub labelled_depth: bool,
    /// The sensor's render pin jitter: its own, given, or fitted to the
    /// calibration taps (`--pin-jitter`, [`PinJitter`]).
    pub pin_jitter: PinJitter,
}

/// A fitted sensor and what the calibration saw.
pub struct Calibrated {
    pub sensor: SensorFolder,
    /// Labelled taps given.
    pub taps: usize,
    /// Real frames rejected by the import (too few pins).
    pub rejected: usize,
    /// One held-out tap, to look at: its image name and its real,
    /// simulated and corrected fields (2P values, all x then all y).
    pub example: Option<ExampleTap>,
    /// What the user should know (the real frames' import warnings: a
    /// reference that looks pressed).
    pub warnings: Vec<String>,
    /// Both pin layouts' fits to the rest pins, and the one kept.
    pub layout: LayoutReport,
    /// The rest layout estimated here from the taps (no reference given).
    pub estimated: Option<EstimatedRest>,
    /// The label convention found from the calibration taps.
    pub convention: ConventionFit,
    /// The tap depth law and slide response found from them.
    pub depth: DepthFit,
}

/// A held-out tap's fields before and after calibration (the tap of
/// median misfit after calibration).
pub struct ExampleTap {
    pub image: String,
    pub real: Vec<f32>,
    pub simulated: Vec<f32>,
    pub corrected: Vec<f32>,
}

/// Held-out taps (at most) that score the fit: the rest of the given taps
/// are not imported, so calibration stays quick on large sets.
pub const SCORE_TAPS: usize = 400;

/// Calibrate `sensor` (the simulator's parameters) to the real taps of
/// `cfg` (pins found by its collection's blob detector): the calibration
/// taps are picked from
/// the labels alone (seeded rule spanning r and theta), then only they and
/// up to [`SCORE_TAPS`] other taps (seeded) are imported and replayed;
/// `progress` ticks once per frame imported and once per tap replayed.
pub fn calibrate_sensor(
    cfg: &CalibrateConfig,
    sensor: &TacTipConfig,
    progress: &(dyn Fn() + Sync),
) -> Result<Calibrated> {
    let c = &cfg.collection;
    let [r_column, theta_column] = c
        .spec()
        .edge_columns()
        .map_err(tactrace_store::StoreError::from)?;
    if let Some(got) = cfg.samples.filter(|&n| n < MIN_TAPS) {
        return Err(CalibError::TooFewTaps {
            got,
            needed: MIN_TAPS,
            recommended: RECOMMENDED_TAPS,
        }
        .into());
    }
    let (resolved, estimated) = resolve_reference(c.clone())?;
    let c = &resolved;
    let sight = sim_sight(c)?;
    let (fitted_layout, layout) = lay_out(sensor, &sight)?;
    let sensor = &fitted_layout;
    let rows = twin_rows(c)?;
    let labels: Vec<Label> = rows
        .iter()
        .map(|r| (f64::from(r.targets[0]), f64::from(r.targets[1])))
        .collect();
    check_labels(&labels)?;
    let pool: Vec<usize> = match &cfg.allowed_rows {
        Some(rows) => rows.iter().copied().filter(|&i| i < labels.len()).collect(),
        None => (0..labels.len()).collect(),
    };
    let pool_labels: Vec<Label> = pool.iter().map(|&i| labels[i]).collect();
    let chosen: Vec<usize> = match cfg.samples {
        Some(n) => select_taps(&pool_labels, n, cfg.seed)?
            .into_iter()
            .map(|k| pool[k])
            .collect(),
        None => pool.clone(),
    };
    let held = match &cfg.score_rows {
        Some(rows) => {
            let taken: HashSet<usize> = chosen.iter().copied().collect();
            let mut rows: Vec<usize> = rows
                .iter()
                .copied()
                .filter(|i| *i < labels.len() && !taken.contains(i))
                .collect();
            rows.sort_unstable();
            rows.dedup();
            rows
        }
        None => held_out_rows(&pool, &chosen, cfg.seed),
    };
    let keep: Vec<usize> = chosen.iter().chain(&held).copied().collect();
    let real = import_rows(c, Some(&keep), progress)?;
    let samples = fit_samples(&real, &rows, &chosen);
    let rest = &real.data.meta.reference_pins;
    let (convention, depth, physics) =
        fit_convention_and_depth(sensor, rest, &samples, cfg.labelled_depth)?;
    let physics = if cfg.fit_physics {
        fit_physics(&physics, rest, &samples)?
    } else {
        physics
    };
    let sensor = &physics;
    let twin = simulate_twin_rows(c, &sight, sensor, cfg.render_seed, (Some(&keep), progress))?;
    let chosen_names: HashSet<&str> = chosen.iter().map(|&i| rows[i].image.as_str()).collect();
    let pairs = paired(&real, &twin)?;
    let (fit_part, held_part) = pairs.split(|name| chosen_names.contains(name));
    let (sim, real_fields, fit_labels) = fit_part.fields()?;
    let plan = CalibrationPlan {
        samples: None,
        seed: cfg.seed,
        ..CalibrationPlan::default()
    };
    let fitted = calibrate(&sim, &real_fields, &fit_labels, &plan)?;
    let mut record = fitted.record;
    record.selection = Selection {
        seed: cfg.seed,
        samples: cfg.samples.unwrap_or(labels.len()),
        indices: chosen.clone(),
    };
    let mut example = None;
    if !held_part.labels.is_empty() {
        let (s, r, _) = held_part.fields()?;
        let corrected = fitted.correction.apply(&s)?;
        record.held_out_before = Some(field_stats(&s, &r)?);
        record.held_out_after = Some(field_stats(&corrected, &r)?);
        let k = median_tap(&corrected, &r);
        example = Some(ExampleTap {
            image: held_part.names[k].clone(),
            real: r.row(k),
            simulated: s.row(k),
            corrected: corrected.row(k),
        });
    }
    let (sensor, jitter) = with_jitter(cfg, (c, &sight, sensor), (&chosen, &real))?;
    record.pin_jitter = jitter;
    let sensor = &sensor;
    let reference = match c.reference() {
        Reference::Frame(path) => tactrace_sensor::read_frame(path)?,
        // No undeformed frame: the calibrated simulator's own rest frame.
        _ => {
            let rest = sight.rest().to_vec();
            let model = TacTipModel::with_rest_pins(sensor.clone(), rest)?;
            model.render(model.rest_pins(), None)
        }
    };
    let spec = SensorSpec {
        format: SENSOR_FORMAT.into(),
        format_version: SENSOR_FORMAT_VERSION,
        tactrace_version: crate::VERSION.into(),
        sensor: sensor.clone(),
        blob: c.blob().clone(),
        sight: c.sight().cloned(),
        labels: LabelColumnNames {
            image: c.spec().image_column().into(),
            r: r_column.into(),
            theta: theta_column.into(),
            dz: c.tap().depth.clone(),
            shear: c.tap().shear.clone(),
        },
        training: TrainingRecipe::default(),
        reference_pins: real.data.meta.reference_pins.clone(),
        calibration: record,
        convention: Some(convention.clone()),
        depth: Some(depth.clone()),
    };
    let sensor = SensorFolder {
        spec,
        reference,
        correction: fitted.correction,
        real_fields: fitted.real_taps.to_flat(),
        real_labels: fitted
            .labels
            .iter()
            .map(|l| [l.0 as f32, l.1 as f32])
            .collect(),
        source: PathBuf::new(),
    };
    Ok(Calibrated {
        sensor,
        taps: labels.len(),
        rejected: real.rejected.len(),
        example,
        warnings: real.warnings.clone(),
        layout,
        estimated,
        convention,
        depth,
    })
}

/// `sensor` with the render pin jitter `cfg` asks for, and the fit's
/// evidence when it was fitted to the `chosen` rows' real taps `real`
/// (after the field correction, which is fitted to noiseless renders as
/// before).
fn with_jitter(
    cfg: &CalibrateConfig,
    (c, sight, sensor): (&LabelledCollection, &SimSight, &TacTipConfig),
    (chosen, real): (&[usize], &Imported),
) -> Result<(TacTipConfig, Option<tactrace_calib::JitterFit>)> {
    let (px, fit) = match cfg.pin_jitter {
        PinJitter::Own => (sensor.nuisance.pin_jitter_px, None),
        PinJitter::Given(px) => (px, None),
        PinJitter::Fit => {
            let fit = fit_pin_jitter(c, sight, sensor, (chosen, real), cfg.render_seed)?;
            (fit.pin_jitter_px, Some(fit))
        }
    };
    Ok((with_pin_jitter(sensor, px)?, fit))
}

/// Nelder-Mead rounds and steps of the physics fit (`--fit-physics`).
const PHYSICS_FIT: (usize, usize) = (2, 150);

/// Settings of the label-convention search (`tactrace_sensor::fit_convention`).
fn convention_search() -> ConventionSearch {
    ConventionSearch {
        threads: rayon::current_num_threads(),
        ..ConventionSearch::default()
    }
}

/// The label convention of the calibration taps `samples` (pins in the
/// order of `rest`), from `sensor`'s.
fn fit_convention(
    sensor: &TacTipConfig,
    rest: &[[f64; 2]],
    samples: &[FitSample],
) -> Result<ConventionFit> {
    Ok(tactrace_sensor::fit_convention(
        sensor,
        rest,
        samples,
        &convention_search(),
    )?)
}

/// The label convention, then the tap depth law, slide response and rim
/// under it, then, when the depth changed, the convention again under
/// the fitted depth (the convention's offsets are found on fields of the
/// simulator's depth: a depth far from the sensor's leaves them weak) and
/// the depth again under it: the two fits, and `sensor` with both.
fn fit_convention_and_depth(
    sensor: &TacTipConfig,
    rest: &[[f64; 2]],
    samples: &[FitSample],
    labelled_depth: bool,
) -> Result<(ConventionFit, DepthFit, TacTipConfig)> {
    let convention = fit_convention(sensor, rest, samples)?;
    let with = convention.apply(sensor);
    let depth = fit_depth(&with, rest, samples, labelled_depth)?;
    if depth.kept_own {
        return Ok((convention, depth, with));
    }
    let deeper = depth.apply(sensor);
    let again = fit_convention(&deeper, rest, samples)?;
    let with = again.apply(&deeper);
    let mut depth2 = fit_depth(&with, rest, samples, labelled_depth)?;
    let physics = depth2.apply(&with);
    // Recorded against the given sensor: the scales of both passes, its
    // own values as the first pass scored them.
    depth2.chosen.slide_scale *= depth.chosen.slide_scale;
    depth2.chosen.rim_scale *= depth.chosen.rim_scale;
    if let (Some(g2), Some(g1)) = (&mut depth2.chosen.field_gain, depth.chosen.field_gain) {
        *g2 *= g1;
    }
    depth2.own = depth.own;
    depth2.kept_own = false;
    Ok((again, depth2, physics))
}

/// The tap depth law and slide response of the calibration taps
/// `samples` (pins in the order of `rest`), from `sensor`'s; with
/// `labelled_depth`, the field's gain under the labelled depth instead
/// of the depth law.
fn fit_depth(
    sensor: &TacTipConfig,
    rest: &[[f64; 2]],
    samples: &[FitSample],
    labelled_depth: bool,
) -> Result<DepthFit> {
    let search = DepthSearch {
        threads: rayon::current_num_threads(),
        labelled_depth,
        ..DepthSearch::default()
    };
    Ok(tactrace_sensor::fit_depth(sensor, rest, samples, &search)?)
}

/// The real fields of the `chosen` rows with their labelled taps, for the
/// fits against the simulator's pins.
fn fit_samples(real: &Imported, rows: &[LabelledRow], chosen: &[usize]) -> Vec<FitSample> {
    let data = &real.data;
    let p = data.dim() / 2;
    let of_image = data.image_rows();
    chosen
        .iter()
        .filter_map(|&i| {
            let k = *of_image.get(rows[i].image.as_str())?;
            let x = &data.inputs[k * 2 * p..(k + 1) * 2 * p];
            let disp = (0..p)
                .map(|j| Some([f64::from(x[j]), f64::from(x[p + j])]))
                .collect();
            Some(FitSample {
                tap: crate::twin::edge_tap(&rows[i]),
                disp,
            })
        })
        .collect()
}

/// `sensor` with its label convention and mechanics fitted to the real
/// fields `samples` (`tactrace_sensor::fit_joint`).
fn fit_physics(
    sensor: &TacTipConfig,
    rest: &[[f64; 2]],
    samples: &[FitSample],
) -> Result<TacTipConfig> {
    let (rounds, iterations) = PHYSICS_FIT;
    let threads = rayon::current_num_threads();
    let mut best: Option<tactrace_sensor::JointFit> = None;
    for start in discrete_conventions(sensor, samples) {
        let fit = tactrace_sensor::fit_joint(&start, rest, samples, (1, iterations, threads))?;
        if best.as_ref().is_none_or(|b| fit.rms_px < b.rms_px) {
            best = Some(fit);
        }
    }
    let Some(best) = best else {
        return Ok(sensor.clone());
    };
    let fit =
        tactrace_sensor::fit_joint(&best.config, rest, samples, (rounds, iterations, threads))?;
    Ok(fit.config)
}

/// The discrete label conventions `--fit-physics` tries, `sensor`'s own
/// first (so that a tie keeps it): the object on either side of the edge
/// (eq. L1; a local fit cannot turn the angle offset by 180 deg) and,
/// when some tap slid, either sign of the slide. Each is fitted one round
/// and the best fitted on.
fn discrete_conventions(
    sensor: &TacTipConfig,
    samples: &[tactrace_sensor::FitSample],
) -> Vec<TacTipConfig> {
    let slid = samples
        .iter()
        .any(|s| s.tap.shear.is_some_and(|m| m != Default::default()));
    let own = &sensor.calibration;
    let sides = [own.object_side, -own.object_side];
    let signs: &[f64] = if slid {
        &[own.shear_sign, -own.shear_sign]
    } else {
        &[own.shear_sign]
    };
    sides
        .iter()
        .flat_map(|&side| {
            signs.iter().map(move |&sign| {
                let mut c = sensor.clone();
                c.calibration.object_side = side;
                c.calibration.shear_sign = sign;
                c
            })
        })
        .collect()
}

/// Write the calibration into the sensor folder `dir` (refused when it
/// exists unless `force`), with a figure of the example tap's real field
/// beside the simulated one before and after calibration
/// (`figures/field_before.svg|png`, `figures/field_after.svg|png`).
pub fn write_calibrated(got: &Calibrated, dir: &std::path::Path, force: bool) -> Result<PathBuf> {
    let stage = got.sensor.stage(dir, force)?;
    if let Some(ex) = &got.example {
        let figs = stage.path().join("figures");
        std::fs::create_dir_all(&figs).map_err(tactrace_store::write_err(&figs))?;
        let pins = &got.sensor.spec.reference_pins;
        let vectors = |f: &[f32]| -> Vec<[f64; 2]> {
            let p = f.len() / 2;
            (0..p)
                .map(|i| [f64::from(f[i]), f64::from(f[p + i])])
                .collect()
        };
        let real = vectors(&ex.real);
        for (stem, field, what) in [
            ("field_before", &ex.simulated, "simulated, uncorrected"),
            ("field_after", &ex.corrected, "simulated, calibrated"),
        ] {
            let rms = field_rms(field, &ex.real);
            let titles = [
                format!("real {} (held out)", ex.image),
                format!("{what}: RMS {rms:.2} px from real"),
            ];
            tactrace_report::plot::quiver_pair(
                &figs.join(stem),
                [&titles[0], &titles[1]],
                pins,
                [&real, &vectors(field)],
                3.0,
            )
            .map_err(tactrace_report::ReportError::from)?;
        }
    }
    Ok(stage.commit()?)
}

/// The tap whose corrected field misfits the real one by the median RMS:
/// a typical tap to look at.
fn median_tap(corrected: &Fields, real: &Fields) -> usize {
    let mut by_rms: Vec<(f64, usize)> = (0..real.len())
        .map(|k| (field_rms(&corrected.row(k), &real.row(k)), k))
        .collect();
    by_rms.sort_by(|a, b| a.0.total_cmp(&b.0));
    by_rms[by_rms.len() / 2].1
}

/// Per-coordinate RMS difference of two fields, px.
fn field_rms(a: &[f32], b: &[f32]) -> f64 {
    let sum: f64 = a.iter().zip(b).map(|(x, y)| f64::from(x - y).powi(2)).sum();
    (sum / a.len().max(1) as f64).sqrt()
}

/// Up to [`SCORE_TAPS`] of the `pool` rows not `chosen`, drawn with `seed`.
fn held_out_rows(pool: &[usize], chosen: &[usize], seed: u64) -> Vec<usize> {
    use rand::seq::SliceRandom;
    use rand::SeedableRng;
    let taken: HashSet<usize> = chosen.iter().copied().collect();
    let mut rest: Vec<usize> = pool
        .iter()
        .copied()
        .filter(|i| !taken.contains(i))
        .collect();
    rest.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(
        seed ^ 0x5C02_E5C0,
    ));
    rest.truncate(SCORE_TAPS);
    rest.sort_unstable();
    rest
}

/// Twin and real fields of the same frames, joined on the image name.
pub(crate) struct Pairs {
    dim: usize,
    names: Vec<String>,
    sim: Vec<f32>,
    real: Vec<f32>,
    labels: Vec<Label>,
}

impl Pairs {
    /// (pairs whose image `first` accepts, the others).
    fn split(self, first: impl Fn(&str) -> bool) -> (Pairs, Pairs) {
        let d = self.dim;
        let empty = || Pairs {
            dim: d,
            names: Vec::new(),
            sim: Vec::new(),
            real: Vec::new(),
            labels: Vec::new(),
        };
        let (mut a, mut b) = (empty(), empty());
        for (k, name) in self.names.into_iter().enumerate() {
            let to = if first(&name) { &mut a } else { &mut b };
            to.sim.extend_from_slice(&self.sim[k * d..(k + 1) * d]);
            to.real.extend_from_slice(&self.real[k * d..(k + 1) * d]);
            to.labels.push(self.labels[k]);
            to.names.push(name);
        }
        (a, b)
    }

    pub(crate) fn fields(&self) -> Result<(Fields, Fields, Vec<Label>)> {
        Ok((
            Fields::from_flat(&self.sim, self.dim, "simulated taps")?,
            Fields::from_flat(&self.real, self.dim, "real taps")?,
            self.labels.clone(),
        ))
    }
}

/// The twin's and the real fields of the same frames (joined on the image
/// name), with their labels.
pub(crate) fn paired(real: &Imported, twin: &Imported) -> Result<Pairs> {
    let (r, s) = (&real.data, &twin.data);
    let row_of = s.image_rows();
    let d = r.dim();
    if d != s.dim() {
        return Err(LabError::Config(format!(
            "the real frames give {} pins a frame and the simulated taps {}",
            d / 2,
            s.dim() / 2
        )));
    }
    let mut pairs = Pairs {
        dim: d,
        names: Vec::new(),
        sim: Vec::new(),
        real: Vec::new(),
        labels: Vec::new(),
    };
    for (i, name) in r.meta.images.iter().enumerate() {
        let Some(&j) = row_of.get(name.as_str()) else {
            continue;
        };
        pairs.sim.extend_from_slice(&s.inputs[j * d..(j + 1) * d]);
        pairs.real.extend_from_slice(&r.inputs[i * d..(i + 1) * d]);
        pairs
            .labels
            .push((f64::from(r.targets[2 * i]), f64::from(r.targets[2 * i + 1])));
        pairs.names.push(name.clone());
    }
    Ok(pairs)
}
