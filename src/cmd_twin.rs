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
use tactrace_lab::pin_jitter::{with_pin_jitter, PinJitter};
use tactrace_lab::twin::{
    fit_position_map, relabel_positions, renders_differ, simulate_twin_calibrated,
    simulate_twin_laid_out,
};
use tactrace_lab::LabError;
use tactrace_store::collection::{bristol, CollectionEdits, Reference};
use tactrace_store::{dataset, fsutil, LabelledCollection, SensorFolder, SightFile, StoredModel};

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
    /// detector, field correction and training recipe (several renders of
    /// every row, plus its real calibration taps); without --reference its
    /// own rest pins order the taps.
    #[arg(long, conflicts_with_all = ["config", "params"])]
    sensor: Option<PathBuf>,
    /// With --sensor: leave the sensor's real calibration taps out (a set
    /// of simulated taps only).
    #[arg(long, requires = "sensor")]
    no_real_taps: bool,
    /// With --sensor: relabel the simulated taps' edge positions by the
    /// position map this model (trained on the sensor's twin with
    /// --no-real-taps) gives the sensor's real calibration taps: the
    /// quadratic from the position it reads to the labelled one
    /// (docs/calibration.md, "The position map").
    #[arg(long, value_name = "MODEL", requires = "sensor")]
    position_map: Option<PathBuf>,
    /// With --sensor: move every rendered pin centre by N(0, PX^2) per
    /// axis (the sensor's `[sensor.nuisance] pin_jitter_px` for this twin),
    /// so that its renders differ as real frames of one tap would
    /// (docs/calibration.md, "Pin jitter in the twin"); default: the
    /// sensor's own (0 for a sensor `calibrate` writes: identical renders).
    #[arg(long, value_name = "PX", requires = "sensor")]
    pin_jitter: Option<f64>,
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
    /// Also keep every simulated tap's frame as an image for the image
    /// models (frames.npy, uint8 N x PX x PX, as `import --frames-size`
    /// writes a real collection's), so an image model trains on the twin.
    #[arg(long, value_name = "PX", value_parser = clap::value_parser!(u16).range(4..=1024))]
    frames_size: Option<u16>,
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
        .opt("--reference", a.labels.reference.as_deref())
        .opt("--sensor", a.sensor.as_deref())
        .opt("--position-map", a.position_map.as_deref())
        .opt("--config", a.config.as_deref())
        .opt("--params", a.params.as_deref())
        .check_apart("--out", &a.out)?;
    let blob = match &a.params {
        Some(p) => Some(blob_params(Some(p), bristol::BLOB_PRESET)?),
        None => None,
    };
    let given = blob.is_some();
    let reference = a.labels.reference.as_deref();
    // The twin reads no frames but the one that gives the frame size: its
    // collection's are the reference frame's folder, or those of the
    // dataset whose rest pins it takes.
    let (frames, recorded) = match (reference, &a.sensor) {
        (Some(dir), _) if dir.is_dir() => {
            let recorded = tactrace_lab::import::recorded(dir)?;
            let frames = recorded.frames.clone().unwrap_or_else(|| dir.to_path_buf());
            (frames, Some(recorded))
        }
        (Some(frame), _) => (frame.parent().unwrap_or(Path::new("")).to_path_buf(), None),
        (None, Some(sensor)) => (sensor.clone(), None),
        (None, None) => return Err(twin_needs_reference().into()),
    };
    let collection = a.columns.collection(&a.labels, &frames, (a.limit, blob))?;
    let collection = with_recorded(collection, recorded, None, given)?;
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let pb = bar(0, "twin");
    let tick = || pb.inc(1);
    let frames_size = a.frames_size.map(usize::from);
    let got = match &a.sensor {
        Some(dir) => {
            let mut sensor = SensorFolder::read(dir)?;
            if let Some(px) = a.pin_jitter {
                sensor.spec.sensor = with_pin_jitter(&sensor.spec.sensor, px)?;
            }
            if !renders_differ(&sensor.spec.sensor) && sensor.spec.training.renders > 1 {
                pb.suspend(|| eprintln!("{}", identical_renders_note(&sensor)));
            }
            let map = match &a.position_map {
                Some(m) => Some(fit_position_map(&sensor, &StoredModel::load(m)?)?),
                None => None,
            };
            let how = (!a.no_real_taps, frames_size);
            simulate_twin_calibrated(&collection, &sensor, a.seed, how, &tick).map(|mut got| {
                if let Some(map) = &map {
                    relabel_positions(&mut got, map);
                    pb.suspend(|| eprintln!("position map: {}", map.describe()));
                }
                got
            })
        }
        None => {
            let rig = rig_config(a.config.as_deref())?;
            let sensor = &rig.sensor;
            simulate_twin_laid_out(&collection, sensor, a.seed, frames_size, &tick).map(
                |(got, layout)| {
                    pb.suspend(|| eprintln!("{}", layout.describe()));
                    got
                },
            )
        }
    };
    pb.finish_and_clear();
    let got = got?;
    let images = got.images.as_ref();
    let dir = dataset::write_dataset_with(&a.out, &got.data, &[], images, a.force)?;
    summary("simulated", "labelled taps", &got, &dir);
    Ok(())
}

/// What `twin --sensor` says when the sensor's renders are copies of one
/// another (no pin jitter, no image noise).
fn identical_renders_note(sensor: &SensorFolder) -> String {
    format!(
        "note: the sensor's pin jitter and image noise are 0, so its {} renders of each \
         row are identical; --pin-jitter PX makes them differ",
        sensor.spec.training.renders
    )
}

/// The error of a twin given neither a reference nor a calibrated sensor.
fn twin_needs_reference() -> LabError {
    LabError::Config(
        "twin needs the sensor's rest pins: --reference FRAME (an undeformed frame), \
         --reference DATASET (an imported dataset's rest pins, e.g. estimated from its taps) \
         or --sensor SENSOR (a calibrated sensor folder)"
            .into(),
    )
}

/// `collection` read against a reference: the dataset `recorded` when
/// given (its rest pins, its sensor settings unless `sight` is given, its
/// blob detector unless `blob_given`), else as it is, with `sight` (a
/// sensor file's settings) when given; a reference still to be estimated
/// looks for the sensor file's pin count.
fn with_recorded(
    collection: LabelledCollection,
    recorded: Option<tactrace_lab::import::RecordedReference>,
    sight: Option<&SightFile>,
    blob_given: bool,
) -> Result<LabelledCollection> {
    let mut c = collection;
    let own = sight.map(SightFile::sight);
    if let Some(r) = recorded {
        c = c
            .with_reference(Reference::Estimated(r.rest))
            .with_sight(own.or(r.sight));
        if let (Some(blob), false) = (r.blob, blob_given) {
            c = c
                .with_blob(blob)
                .map_err(tactrace_store::StoreError::from)?;
        }
        return Ok(c);
    }
    if let (Reference::Estimate { .. }, Some(s)) = (c.reference(), sight) {
        let pins = Some(s.sensor.pins);
        c = c.with_reference(Reference::Estimate { pins });
    }
    Ok(match own {
        Some(own) => c.with_sight(Some(own)),
        None => c,
    })
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
    #[arg(long, conflicts_with = "sensor")]
    params: Option<PathBuf>,
    /// Sensor settings (`tactrace sensor inspect`): how to read the frames
    /// (grey, crop, dome mask, threshold; the detector, which also reads
    /// the simulated taps).
    #[arg(long)]
    sensor: Option<PathBuf>,
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
            .opt("--sensor", self.sensor.as_deref())
            .check_apart("--out", out)?;
        Ok(())
    }

    /// The labelled collection and the simulator to start from. Its
    /// reference: the undeformed frame `--reference FRAME`, the rest pins
    /// (and sensor settings, blob detector) of `--reference DATASET`, or,
    /// without --reference, a rest layout estimated from the taps.
    fn resolve(&self) -> Result<(LabelledCollection, tactrace_sensor::TacTipConfig)> {
        let blob = blob_params(self.params.as_deref(), bristol::BLOB_PRESET)?;
        let limits = (self.limit, Some(blob));
        let collection = self
            .columns
            .collection(&self.labels, &self.frames, limits)?;
        let sight = self.sensor.as_deref().map(SightFile::read).transpose()?;
        let recorded = match self.labels.reference.as_deref() {
            Some(dir) if dir.is_dir() => Some(tactrace_lab::import::recorded(dir)?),
            _ => None,
        };
        let given = self.params.is_some();
        let collection = with_recorded(collection, recorded, sight.as_ref(), given)?;
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
    /// Press each calibration tap to its labelled depth (the depth column
    /// read as the absolute depth, mm) and fit the field's gain instead
    /// of the depth law (docs/calibration.md, "The labelled depth").
    #[arg(long)]
    labelled_depth: bool,
    /// The sensor's render pin jitter, px per axis (`[sensor.nuisance]
    /// pin_jitter_px`; each render of `twin --sensor` then draws it):
    /// `fit` estimates it from the calibration taps' scatter about a
    /// smooth field against the simulator's at a grid of jitters and
    /// records the evidence (docs/calibration.md, "Pin jitter fitted from
    /// the taps"); a number sets it. Default: the simulator's own (0).
    #[arg(long, value_name = "fit|PX")]
    pin_jitter: Option<PinJitter>,
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
        labelled_depth: a.labelled_depth,
        pin_jitter: a.pin_jitter.unwrap_or_default(),
    };
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let t0 = std::time::Instant::now();
    let pb = bar(0, "calibrate");
    let tick = || pb.inc(1);
    let got = calibrate_sensor(&cfg, &sensor, &tick);
    pb.finish_and_clear();
    let got = got?;
    let dir = write_calibrated(&got, &a.out, a.force)?;
    if let Some(e) = &got.estimated {
        eprintln!(
            "no --reference: estimated the rest layout ({} pins) from {} taps, residual {:.3} px",
            e.pins.len(),
            e.frames,
            e.residual_px
        );
    }
    eprintln!("{}", got.layout.describe());
    eprintln!("{}", got.convention.describe());
    eprintln!("{}", got.depth.describe());
    if let Some(j) = &got.sensor.spec.calibration.pin_jitter {
        eprintln!("{}", j.describe());
    }
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
                      best: Option<&tactrace_lab::transfer_fit::Candidate>| {
        pb.inc(1);
        let show = |c: &tactrace_lab::transfer_fit::Candidate| match (c.mae, &c.failure) {
            (Some(m), _) => format!("{:.3} mm / {:.2} deg", m[0], m[1]),
            (None, Some(why)) => format!("failed ({why})"),
            (None, None) => "failed".into(),
        };
        let best = best.map_or("none yet".into(), show);
        let line = format!("generation {:>3}: {}   best {best}", c.generation, show(c));
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
    eprintln!("{}", fit.layout.describe());
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
