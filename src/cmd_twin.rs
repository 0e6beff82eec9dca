//! `twin`: a simulated twin of a real labelled data set (the simulator
//! judged against real frames, docs/results.md "Simulated to real"), and
//! `calibrate`: the simulator fitted to a user's own taps
//! (docs/calibration.md).
use crate::cmd_data::{blob_params, rig_config, LabelArgs};
use crate::inputs::Inputs;
use crate::progress::bar;
use anyhow::Result;
use clap::Args;
use std::path::{Path, PathBuf};
use tactrace_lab::calibrate::{calibrate_sensor, write_calibrated, CalibrateConfig};
use tactrace_lab::import::Imported;
use tactrace_lab::twin::{simulate_twin, simulate_twin_calibrated};
use tactrace_lab::LabError;
use tactrace_store::collection::{bristol, CollectionEdits};
use tactrace_store::{dataset, fsutil, LabelledCollection, SensorFolder};

/// The columns of a tap's depth and shear (`twin`, `calibrate`, `sim-fit`).
#[derive(Args)]
pub struct TapColumnArgs {
    /// Vertical offset of each tap, mm; `none`: all taps at the nominal depth.
    #[arg(long, default_value = bristol::DEPTH_COLUMN)]
    dz_column: String,
    /// Shear columns x,y (mm) and rotation (deg), comma-separated; `none`:
    /// taps without shear.
    #[arg(long, default_value_t = bristol::SHEAR_COLUMNS.join(","))]
    shear_columns: String,
}

impl TapColumnArgs {
    /// The collection of `labels` (its frames in `frames`) with these tap
    /// columns, the first `limit` rows and the blob detector `blob`
    /// (default: the Bristol preset).
    fn collection(
        &self,
        labels: &LabelArgs,
        frames: &Path,
        (limit, blob): (Option<usize>, Option<tactrace_vision::BlobParams>),
    ) -> Result<LabelledCollection> {
        let edits = CollectionEdits {
            depth_column: Some(self.dz_column.clone()),
            shear_columns: Some(self.shear_columns.clone()),
            limit,
            blob,
            ..CollectionEdits::default()
        };
        labels.collection(frames, edits)
    }
}

#[derive(Args)]
pub struct TwinArgs {
    #[command(flatten)]
    labels: LabelArgs,
    #[command(flatten)]
    columns: TapColumnArgs,
    /// A calibrated sensor folder (`tactrace calibrate`): its parameters,
    /// field correction and training recipe (several renders of every row,
    /// plus its real calibration taps).
    #[arg(long, conflicts_with_all = ["config", "params"])]
    sensor: Option<PathBuf>,
    /// With --sensor: leave the sensor's real calibration taps out (a set
    /// of simulated taps only).
    #[arg(long, requires = "sensor")]
    no_real_taps: bool,
    /// Rig configuration TOML whose `sensor` table is the simulated TacTip
    /// (default: the model calibrated on the real edge frames).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Blob detector parameters (TOML); default: the real256 preset, as `import`.
    #[arg(long)]
    params: Option<PathBuf>,
    /// Seed of the pin jitter and image noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Simulate only the first N rows.
    #[arg(long)]
    limit: Option<usize>,
    /// Output dataset directory.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing non-empty `--out`.
    #[arg(long)]
    force: bool,
}

pub fn twin(a: TwinArgs) -> Result<()> {
    Inputs::new()
        .add("--targets", &a.labels.targets)
        .add("--reference", a.labels.reference_frame()?)
        .opt("--sensor", a.sensor.as_deref())
        .opt("--config", a.config.as_deref())
        .opt("--params", a.params.as_deref())
        .check_apart("--out", &a.out)?;
    // The twin reads no frames: its collection's are the reference's folder.
    let frames = a
        .labels
        .reference_frame()?
        .parent()
        .unwrap_or(Path::new(""));
    let blob = match &a.params {
        Some(p) => Some(blob_params(Some(p), bristol::BLOB_PRESET)?),
        None => None,
    };
    let collection = a.columns.collection(&a.labels, frames, (a.limit, blob))?;
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let pb = bar(0, "twin");
    let tick = || pb.inc(1);
    let got = match &a.sensor {
        Some(dir) => {
            let sensor = SensorFolder::read(dir)?;
            simulate_twin_calibrated(&collection, &sensor, a.seed, !a.no_real_taps, &tick)
        }
        None => {
            let rig = rig_config(a.config.as_deref())?;
            simulate_twin(&collection, &rig.sensor, a.seed, &tick)
        }
    };
    pb.finish_and_clear();
    let got = got?;
    let dir = dataset::write_dataset(&a.out, &got.data, &[], a.force)?;
    summary("simulated", "labelled taps", &got, &dir);
    Ok(())
}

fn summary(verb: &str, what: &str, got: &Imported, dir: &std::path::Path) {
    let n = got.data.len();
    eprintln!(
        "{verb} {n} {what} into {}: all pins matched on {}, {} with missing pins, {} rejected (too few pins)",
        dir.display(),
        n - got.frames_with_missing_pins,
        got.frames_with_missing_pins,
        got.rejected.len()
    );
    if let Some(c) = &got.composition {
        eprintln!("  {}", composition_text(c));
    }
    for (name, why) in got.rejected.iter().take(10) {
        eprintln!("  rejected {name}: {why}");
    }
}

/// Where a calibrated sensor's twin taps come from, in words: the count
/// `twin --sensor` prints is more than the labelled rows.
fn composition_text(c: &tactrace_lab::import::TwinComposition) -> String {
    let rendered = c.rows * c.renders;
    let mut text = format!(
        "from {} labelled rows: {} render(s) of each ({rendered} taps, the sensor's training \
         recipe)",
        c.rows, c.renders
    );
    if c.real_tap_repeats > 0 {
        text.push_str(&format!(
            ", then its {} real calibration taps {} time(s) ({} taps; --no-real-taps leaves \
             them out)",
            c.real_taps,
            c.real_tap_repeats,
            c.real_taps * c.real_tap_repeats
        ));
    }
    text
}

/// Real labelled taps and the simulator to fit to them (`calibrate`,
/// `sim-fit`).
#[derive(Args)]
pub struct RealTapArgs {
    /// Folder of the real frames named in --targets.
    #[arg(long)]
    frames: PathBuf,
    #[command(flatten)]
    labels: LabelArgs,
    #[command(flatten)]
    columns: TapColumnArgs,
    /// Rig configuration TOML whose `sensor` table is the simulator to
    /// start from (default: the built-in model).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Blob detector parameters (TOML); default: the real256 preset.
    #[arg(long)]
    params: Option<PathBuf>,
    /// Use only the first N rows of --targets.
    #[arg(long)]
    limit: Option<usize>,
}

impl RealTapArgs {
    /// Refuse an output folder `out` in or around these inputs.
    fn check_apart(&self, out: &std::path::Path) -> Result<()> {
        Inputs::new()
            .add("--frames", &self.frames)
            .add("--targets", &self.labels.targets)
            .opt("--reference", self.labels.reference.as_deref())
            .opt("--config", self.config.as_deref())
            .opt("--params", self.params.as_deref())
            .check_apart("--out", out)?;
        Ok(())
    }

    /// The labelled collection and the simulator to start from.
    fn resolve(&self) -> Result<(LabelledCollection, tactrace_sensor::TacTipConfig)> {
        let blob = blob_params(self.params.as_deref(), bristol::BLOB_PRESET)?;
        let limits = (self.limit, Some(blob));
        let collection = self
            .columns
            .collection(&self.labels, &self.frames, limits)?;
        let rig = rig_config(self.config.as_deref())?;
        Ok((collection, rig.sensor))
    }
}

#[derive(Args)]
pub struct CalibrateArgs {
    #[command(flatten)]
    taps: RealTapArgs,
    /// Calibration taps to pick (by a seeded rule that spans r and theta,
    /// docs/calibration.md); the other given taps score the fit. 0: use
    /// every tap (nothing held out).
    #[arg(long, default_value_t = 100)]
    samples: usize,
    /// Seed of the tap selection and of the replayed taps' rendering noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also fit the simulator's label convention (the object's side of
    /// the edge and the slide's sign, tried both ways; angle and edge
    /// offsets and scales, tap depth) and mechanics to the calibration
    /// taps before the field correction: for a sensor unlike the shared
    /// one (up to a minute more).
    #[arg(long)]
    fit_physics: bool,
    /// The sensor folder to write.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing sensor folder.
    #[arg(long)]
    force: bool,
}

pub fn calibrate(a: CalibrateArgs) -> Result<()> {
    a.taps.check_apart(&a.out)?;
    let (collection, sensor) = a.taps.resolve()?;
    let cfg = CalibrateConfig {
        collection,
        render_seed: a.seed,
        samples: (a.samples > 0).then_some(a.samples),
        seed: a.seed,
        allowed_rows: None,
        score_rows: None,
        fit_physics: a.fit_physics,
    };
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let t0 = std::time::Instant::now();
    let pb = bar(0, "calibrate");
    let tick = || pb.inc(1);
    let got = calibrate_sensor(&cfg, &sensor, &tick);
    pb.finish_and_clear();
    let got = got?;
    let dir = write_calibrated(&got, &a.out, a.force)?;
    let c = &got.sensor.spec.calibration;
    eprintln!(
        "calibrated on {} of {} labelled taps ({} frames rejected) in {:.1} s into {}",
        c.selection.indices.len(),
        got.taps,
        got.rejected,
        t0.elapsed().as_secs_f64(),
        dir.display()
    );
    if let (Some(b), Some(f)) = (&c.held_out_before, &c.held_out_after) {
        crate::say!(
            "held-out taps ({}): field RMS {:.3} -> {:.3} px, mean cosine {:.3} -> {:.3}",
            f.taps,
            b.rms_px,
            f.rms_px,
            b.mean_cosine,
            f.mean_cosine
        );
    }
    for w in &got.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}

#[derive(Args)]
pub struct SimFitArgs {
    #[command(flatten)]
    taps: RealTapArgs,
    /// CMA-ES generations (each candidate trains one PDenNN per render,
    /// about 2 s per 2000 taps on two cores).
    #[arg(long, default_value_t = 14)]
    generations: usize,
    /// Candidates per generation (default: CMA-ES's 4 + 3 ln n = 12).
    #[arg(long)]
    population: Option<usize>,
    /// First step of the search, in units of each parameter's scale.
    #[arg(long, default_value_t = 0.5)]
    sigma: f64,
    /// Seed of the search.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Degrees of angle error that cost as much as 1 mm of position error.
    #[arg(long, default_value_t = 5.0)]
    deg_per_mm: f64,
    /// Twins per candidate (rendering seeds 1, 2, ...); the cost is their
    /// mean.
    #[arg(long, default_value_t = 2)]
    renders: usize,
    /// Output folder: sensor.toml (a rig file for --config), search.csv,
    /// summary.json.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing output folder.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    executor: crate::cmd_search::ExecutorArgs,
}

/// `sim-fit`: the simulator's physical parameters fitted by what a PDenNN
/// trained on its twin makes of the real frames (docs/sensor-model.md,
/// "Transfer fit").
pub fn sim_fit(a: SimFitArgs) -> Result<()> {
    use tactrace_lab::transfer_fit::{fit_transfer, write_transfer_fit, TransferFitConfig};
    if a.generations == 0 {
        return Err(LabError::Config("--generations must be at least 1".into()).into());
    }
    if !(a.sigma.is_finite() && a.sigma > 0.0) {
        return Err(LabError::Config(format!("--sigma {} must be positive", a.sigma)).into());
    }
    if !(a.deg_per_mm.is_finite() && a.deg_per_mm > 0.0) {
        return Err(
            LabError::Config(format!("--deg-per-mm {} must be positive", a.deg_per_mm)).into(),
        );
    }
    if a.renders == 0 {
        return Err(LabError::Config("--renders must be at least 1".into()).into());
    }
    a.taps.check_apart(&a.out)?;
    let (collection, sensor) = a.taps.resolve()?;
    let cfg = TransferFitConfig {
        renders: a.renders,
        deg_per_mm: a.deg_per_mm,
        collection,
        render_seed: 1,
        generations: a.generations,
        population: a.population,
        sigma: a.sigma,
        seed: a.seed,
        val_fraction: 0.15,
    };
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let t0 = std::time::Instant::now();
    let pb = bar(0, "sim-fit");
    let mut report = |c: &tactrace_lab::transfer_fit::Candidate,
                      best: &tactrace_lab::transfer_fit::Candidate| {
        pb.inc(1);
        let show = |c: &tactrace_lab::transfer_fit::Candidate| {
            c.mae.map_or("invalid sensor".into(), |m| {
                format!("{:.3} mm / {:.2} deg", m[0], m[1])
            })
        };
        let line = format!(
            "generation {:>3}: {}   best {}",
            c.generation,
            show(c),
            show(best)
        );
        if pb.is_hidden() {
            eprintln!("{line}");
        } else {
            pb.println(line);
        }
    };
    let executor = a.executor.executor()?;
    let fit = fit_transfer(&cfg, &sensor, &executor, &mut report);
    pb.finish_and_clear();
    let fit = fit?;
    for w in &fit.warnings {
        eprintln!("warning: {w}");
    }
    let dir = write_transfer_fit(&fit, &cfg, &a.out, a.force)?;
    let show = |c: &tactrace_lab::transfer_fit::Candidate| {
        c.mae
            .map_or("-".into(), |m| format!("{:.3} mm / {:.2} deg", m[0], m[1]))
    };
    eprintln!(
        "{} candidates in {:.0} s; on the {} real frames: start {}, best {} -> {}",
        fit.candidates.len(),
        t0.elapsed().as_secs_f64(),
        fit.real_frames,
        show(&fit.start),
        show(&fit.best),
        dir.join("sensor.toml").display()
    );
    Ok(())
}
