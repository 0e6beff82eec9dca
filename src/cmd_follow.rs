//! Experiment commands: `follow` and `reproduce`.
use crate::inputs::Inputs;
use crate::progress::follow_bar;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use tactrace_geometry::Contour;
use tactrace_geometry::ShapeSpec;
use tactrace_lab::follow::{FollowOutcome, RunHooks, SimFollowConfig};
use tactrace_lab::hardware::{HardwareConfig, StopFlag};
use tactrace_lab::reproduce::{reproduce as run_reproduce, ReproduceConfig};
use tactrace_lab::world::{OpenWorld, ReplayBank, World};
use tactrace_lab::LabError;
use tactrace_servo::{LoopConfig, StepRecord};
use tactrace_store::collection::{bristol, CollectionEdits};
use tactrace_store::{fsutil, load_config, load_shape, LoadedModel, StoredModel};

#[derive(Args)]
pub struct FollowArgs {
    /// Model directory (from `tactrace train`).
    #[arg(long)]
    model: PathBuf,
    /// Built-in shape (disk, flower, trine, teardrop), a parametric one
    /// (square:S, rect:W,H, star:R,A,K for r = R + A cos(K phi), each with an
    /// optional last value: rotation, deg) or a CSV of x,y points (mm). With --hardware: optional, the object's true contour in the
    /// work frame, used only to score the run.
    #[arg(long, required_unless_present_any = ["hardware", "task"])]
    shape: Option<String>,
    /// Run on a real rig (UR5 + TacTip camera) described by this TOML
    /// (docs/hardware.md) instead of the simulated world.
    #[arg(long, conflicts_with = "config")]
    hardware: Option<PathBuf>,
    /// Run exactly N steps (default: until the loop closes, capped).
    #[arg(long)]
    steps: Option<usize>,
    /// Follow-run TOML (tables rig, controller, follow, start).
    #[arg(long)]
    config: Option<PathBuf>,
    /// A calibrated sensor folder (`tactrace calibrate`): the simulated
    /// world is that sensor, and the model predicts labels in its
    /// convention (a model trained on its real frames, or on `twin
    /// --sensor` / `collect --sensor` data of it).
    #[arg(long, conflicts_with = "hardware")]
    sensor: Option<PathBuf>,
    /// Seed of the tap-depth variation and the simulated world's noise
    /// (default: the configuration's, 1).
    #[arg(long)]
    seed: Option<u64>,
    /// Run directory: written as OUT.partial and renamed to OUT when
    /// the run is over.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing run directory.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    views: crate::views::ViewsFlag,
    #[command(flatten)]
    replay: ReplayArgs,
    #[command(flatten)]
    task3d: crate::cmd_task3d::FollowTaskArgs,
}

/// The real-frame world (`follow --replay`).
#[derive(Args)]
pub struct ReplayArgs {
    /// Follow in the real-frame world: a simulated arm whose every tap is
    /// answered by the frame of this real labelled collection on a straight
    /// edge (Bristol layout: targets.csv, frames/ with init_0.png) whose
    /// labels are nearest the sensor's true pose
    /// (docs/real-frame-world.md). The model must be trained on this
    /// collection.
    #[arg(long, conflicts_with = "hardware")]
    replay: Option<PathBuf>,
    /// Answer only with the frames whose number N (frame_N_0.png) has
    /// N % M == K, e.g. `N%5==0`: frames the model never trained on.
    #[arg(long, requires = "replay")]
    replay_keep: Option<String>,
    /// The collection's labels CSV (default: DIR/targets.csv), e.g. one
    /// part of a split.
    #[arg(long, requires = "replay")]
    targets: Option<PathBuf>,
    /// The collection's undeformed frame (default: DIR/frames/init_0.png).
    #[arg(long, requires = "replay")]
    reference: Option<PathBuf>,
    /// Column of the labels naming each row's frame file.
    #[arg(long, requires = "replay", default_value = bristol::IMAGE_COLUMN)]
    image_column: String,
    /// Column of the labels with the edge position r, mm.
    #[arg(long, requires = "replay", default_value = bristol::R_COLUMN)]
    r_column: String,
    /// Column of the labels with the edge angle theta, degrees.
    #[arg(long, requires = "replay", default_value = bristol::THETA_COLUMN)]
    theta_column: String,
    /// Column of the labels with the tap's vertical offset, mm; `none`:
    /// depth does not count in choosing a frame.
    #[arg(long, requires = "replay", default_value = bristol::DEPTH_COLUMN)]
    dz_column: String,
    /// Blob detector parameters (TOML) for the real frames; default: the
    /// real256 preset, as `import`.
    #[arg(long, requires = "replay")]
    params: Option<PathBuf>,
}

impl ReplayArgs {
    /// The bank these flags describe: the collection in `dir` with them.
    fn bank(&self, dir: &std::path::Path) -> Result<ReplayBank> {
        let edits = CollectionEdits {
            targets: self.targets.clone(),
            reference: self.reference.clone(),
            image_column: Some(self.image_column.clone()),
            r_column: Some(self.r_column.clone()),
            theta_column: Some(self.theta_column.clone()),
            depth_column: Some(self.dz_column.clone()),
            keep: self.replay_keep.clone(),
            blob: Some(crate::cmd_data::blob_params(
                self.params.as_deref(),
                bristol::BLOB_PRESET,
            )?),
            ..CollectionEdits::default()
        };
        Ok(ReplayBank::from_dir(dir, &edits)?)
    }
}

pub fn follow(a: FollowArgs) -> Result<()> {
    if let Some(hw) = a.hardware.clone() {
        return follow_hardware(a, &hw);
    }
    if a.task3d.is_3d() {
        if a.views.given() {
            return Err(LabError::Config(
                "--views is the edge follow's (and validate's, predict's): the 3D tasks \
                 take a model's turned views as its file says"
                    .into(),
            )
            .into());
        }
        let out = (a.out.as_path(), a.force);
        return crate::cmd_task3d::follow(&a.task3d, &a.model, a.config.as_deref(), a.seed, out);
    }
    let mut cfg: SimFollowConfig = load_config(a.config.as_deref(), "follow configuration")?;
    overrides(&a, &mut cfg.follow);
    if a.sensor.is_some() {
        cfg.calibrated_sensor = a.sensor.clone();
    }
    if let Some(dir) = &a.replay.replay {
        cfg.replay = Some(a.replay.bank(dir)?);
    }
    let bank = cfg.replay.as_ref().map(ReplayBank::collection);
    Inputs::new()
        .add("--model", &a.model)
        .file_arg("--shape", a.shape.as_deref().unwrap_or_default())
        .opt("--config", a.config.as_deref())
        .opt("--sensor", cfg.calibrated_sensor.as_deref())
        .opt("--replay", a.replay.replay.as_deref())
        .opt("--replay", bank.map(|c| c.frames()))
        .opt("--targets", bank.map(|c| c.targets()))
        .opt("--reference", bank.and_then(|c| c.reference().frame()))
        .opt("--params", a.replay.params.as_deref())
        .check_apart("--out", &a.out)?;
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let world = cfg.world().open()?;
    let spec =
        ShapeSpec::parse_checked(a.shape.as_deref().unwrap_or_default()).map_err(LabError::from)?;
    let shape = (spec.name(), load_shape(&spec)?);
    let mut model = LoadedModel::load(&a.model)?;
    a.views.apply(&mut model)?;
    follow_in(world, &model, Some(&shape), (&a.out, a.force), None)
}

/// Run `world` with `model` on `shape` into `out` with a progress bar,
/// then print the run's summary ([`report_run`]); `stop` stops a real rig.
fn follow_in(
    world: OpenWorld,
    model: &LoadedModel,
    shape: Option<&(String, Contour)>,
    out: (&std::path::Path, bool),
    stop: Option<&StopFlag>,
) -> Result<()> {
    let named = shape.map(|(n, c)| (n.as_str(), c));
    let steps = world.settings().follow().step_limit();
    let res = follow_bar(steps, |pb| {
        let mut progress = |r: &StepRecord| pb.set_position(r.step as u64 + 1);
        let mut warn = |w: &str| pb.suspend(|| eprintln!("warning: {w}"));
        let hooks = RunHooks {
            progress: Some(&mut progress),
            warn: Some(&mut warn),
            stop,
        };
        tactrace_lab::follow::run_model(world, model, named, out, hooks)
    })?;
    if let Some(stats) = &res.replay {
        crate::say!("{}", stats.summary());
        if let Some(w) = stats.warning() {
            eprintln!("warning: {w}");
        }
    }
    report_run(named.map_or("rig", |s| s.0), &res)
}

/// Print a finished run's summary; a run that did not do what was asked
/// (lost contact, refused move, fault, step cap) is an error (exit code 1)
/// after its outputs are kept.
fn report_run(name: &str, res: &FollowOutcome) -> Result<()> {
    match &res.metrics {
        Some(m) => crate::say!(
            "{name}: {} steps, {}; mean L2 {:.3} mm, track error mean {:.3} / max {:.3} mm, coverage {:.0}%",
            m.steps,
            res.summary.ending,
            m.mean_l2_mm,
            m.mean_track_error_mm,
            m.max_track_error_mm,
            100.0 * m.coverage
        ),
        None => crate::say!("{} steps, {}", res.summary.steps, res.summary.ending),
    }
    if res.summary.ending.succeeded() {
        eprintln!("{} (run folder {})", res.summary.message, res.dir.display());
        if let Some(m) = &res.metrics {
            tactrace_lab::numbers::require_finite_run(name, m)?;
        }
    } else {
        eprintln!(
            "the run and its trajectory so far are in {}",
            res.dir.display()
        );
        return Err(LabError::RunFailed {
            ending: res.summary.ending,
            message: res.summary.message.clone(),
        }
        .into());
    }
    Ok(())
}

#[derive(Args)]
pub struct ReproduceArgs {
    /// Output directory for data, models, runs, figures and the report
    /// (appears only when complete).
    #[arg(long, default_value = "runs/reproduce")]
    out: PathBuf,
    /// Replace an existing output directory.
    #[arg(long)]
    force: bool,
    /// Seed of every random choice (default 1, or the config's).
    #[arg(long)]
    seed: Option<u64>,
    /// Epochs for every network (default: the preset's).
    #[arg(long)]
    epochs: Option<usize>,
    /// Use the report's fixed step counts (266, 272, 222, 260).
    #[arg(long)]
    report_steps: bool,
    /// Add results on real frames from this folder (Bristol layout).
    #[arg(long)]
    real: Option<PathBuf>,
    /// With --real: also train the image model conv-dennn on the real
    /// frames (64 px; --epochs applies, default 40: minutes) and follow
    /// the four shapes with it in the real-frame world.
    #[arg(long)]
    image_model: bool,
    /// A calibrated sensor folder (`tactrace calibrate`): the whole report
    /// in that sensor's simulated world (collection in its label
    /// convention, training, following).
    #[arg(long)]
    sensor: Option<PathBuf>,
    /// Add surface following in 3D: a surface_3d model trained on
    /// simulated taps, following the saddle, bowl and wave (a section of
    /// report.html, run folders under follow-3d/).
    #[arg(long = "3d")]
    three_d: bool,
    /// Reproduce TOML overlaying the defaults (keys: seed, train_samples,
    /// val_samples, epochs, preset, report_steps, real, image_model, and the follow
    /// tables rig, controller, follow, start).
    #[arg(long)]
    config: Option<PathBuf>,
}

pub fn reproduce(a: ReproduceArgs) -> Result<()> {
    let mut cfg: ReproduceConfig = load_config(a.config.as_deref(), "reproduce configuration")?;
    cfg.seed = a.seed.unwrap_or(cfg.seed);
    cfg.epochs = a.epochs.or(cfg.epochs);
    cfg.report_steps |= a.report_steps;
    cfg.three_d |= a.three_d;
    cfg.real = a.real.or(cfg.real);
    cfg.image_model |= a.image_model;
    if a.sensor.is_some() {
        cfg.follow.calibrated_sensor = a.sensor.clone();
    }
    let log = |msg: &str| eprintln!("[reproduce] {msg}");
    Inputs::new()
        .opt("--real", cfg.real.as_deref())
        .opt("--sensor", cfg.follow.calibrated_sensor.as_deref())
        .opt("--config", a.config.as_deref())
        .check_apart("--out", &a.out)?;
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let r = run_reproduce(&cfg, (&a.out, a.force), &log)?;
    let runs = [
        ("simulated", &r.networks),
        ("real", &r.real_networks),
        ("sim->real", &r.sim_to_real),
    ];
    for (data, rows) in runs {
        for n in rows.iter() {
            crate::say!(
                "{:<16} {data:<9} angle {:.2} deg, position {:.3} mm",
                n.name,
                n.angle_mae_deg,
                n.position_mae_mm
            );
        }
    }
    for c in &r.calibration {
        crate::say!(
            "calibrated, {} taps from the {}: angle {:.2} deg, position {:.3} mm on the {}",
            c.taps.map_or("all".into(), |n| n.to_string()),
            c.pool,
            c.angle_mae_deg,
            c.position_mae_mm,
            c.scored_on
        );
    }
    for s in &r.shapes {
        crate::say!(
            "{:<16} mean L2 {:.2} mm (report {:.2}), closed {}",
            s.shape,
            s.metrics.mean_l2_mm,
            s.report_l2_mm,
            s.metrics.closed
        );
    }
    for s in &r.real_model_shapes {
        crate::say!(
            "{:<16} mean L2 {:.2} mm (report {:.2}), closed {}: the PDenNN trained on real frames, in the calibrated simulator",
            s.shape,
            s.metrics.mean_l2_mm,
            s.report_l2_mm,
            s.metrics.closed
        );
    }
    let real_runs = r.real_shapes.iter().map(|s| ("", s));
    let image_runs = r.real_image_shapes.iter().map(|s| (", conv-dennn", s));
    for (with, s) in real_runs.chain(image_runs) {
        crate::say!(
            "{:<16} real-frame world{with}: mean L2 {:.2} mm (report {:.2}), closed {}, label distance mean {:.2} / p95 {:.2}",
            s.shape,
            s.metrics.mean_l2_mm,
            s.report_l2_mm,
            s.metrics.closed,
            s.label_distance_mean,
            s.label_distance_p95
        );
    }
    crate::say!("report: {}", a.out.join("report.html").display());
    let runs = r.shapes.iter().chain(&r.real_model_shapes);
    for s in runs {
        tactrace_lab::numbers::require_finite_run(&s.shape, &s.metrics)?;
    }
    for s in r.real_shapes.iter().chain(&r.real_image_shapes) {
        tactrace_lab::numbers::require_finite_run(&s.shape, &s.metrics)?;
    }
    Ok(())
}

#[derive(Args)]
pub struct BenchArgs {
    /// Number of simulated taps to time (at most 20000).
    #[arg(long, default_value_t = 2000)]
    taps: usize,
    /// A model directory: also time the control loop (frame -> command).
    #[arg(long)]
    model: Option<PathBuf>,
    /// A folder of real frames (Bristol layout, with init_0.png): also time
    /// the control loop on them (needs --model).
    #[arg(long)]
    real_frames: Option<PathBuf>,
    /// A sensor file (`tactrace sensor inspect --out`) the real frames are
    /// read with (its preprocessing and detector, against the model's
    /// reference pins; no init_0.png needed), as `import` read them.
    #[arg(long, requires = "real_frames")]
    real_sensor: Option<PathBuf>,
    /// A calibrated sensor folder (`tactrace calibrate`): time its taps
    /// (with its field correction) instead of the default sensor's.
    #[arg(long)]
    sensor: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// The most taps `bench` times: it keeps every tap's frame (64 KB at 256
/// x 256 px), so 1e11 aborted on allocation.
const MAX_BENCH_TAPS: usize = 20_000;

pub fn bench(a: BenchArgs) -> Result<()> {
    if a.real_frames.is_some() && a.model.is_none() {
        return Err(LabError::Config(
            "--real-frames times the control loop on real frames, which needs --model".into(),
        )
        .into());
    }
    if a.taps > MAX_BENCH_TAPS {
        return Err(LabError::Config(format!(
            "--taps {}: at most {MAX_BENCH_TAPS} (every tap's frame is kept in memory)",
            a.taps
        ))
        .into());
    }
    let stored = a.model.as_deref().map(StoredModel::load).transpose()?;
    let model_pins = stored.as_ref().map(|m| m.reference_pins().to_vec());
    let model = stored.map(|m| {
        let pins = m.reference_pins().to_vec();
        m.into_model_for(&pins, std::path::Path::new("bench"))
    });
    let model = model.transpose().map_err(LabError::from)?;
    let rig = tactrace_servo::RigConfig::default();
    let taps = a.taps.max(1);
    // A model of another sensor's real frames is timed on them only.
    let sim_model = model.as_ref().filter(|_| a.real_sensor.is_none());
    let f = match &a.sensor {
        Some(dir) => {
            let folder = tactrace_store::SensorFolder::read(dir)?;
            tactrace_lab::bench::bench_calibrated(&folder, &rig, taps, sim_model)?
        }
        None => tactrace_lab::bench::bench(&rig, taps, sim_model)?,
    };
    let real = match (&a.real_frames, &model, &a.real_sensor) {
        (Some(dir), Some(m), Some(file)) => {
            let sight = tactrace_store::SightFile::read(file)?.sight();
            let rest = model_pins.unwrap_or_default();
            Some(tactrace_lab::bench::real_control_latency_sight(
                dir, sight, rest, m, a.taps,
            )?)
        }
        (Some(dir), Some(m), None) => {
            let blob = tactrace_vision::BlobParams::preset("real256").map_err(LabError::from)?;
            Some(tactrace_lab::bench::real_control_latency_stats(
                dir, &blob, m, a.taps,
            )?)
        }
        _ => None,
    };
    if a.json {
        let mut doc = serde_json::to_value(&f)?;
        if let (Some(r), Some(obj)) = (&real, doc.as_object_mut()) {
            obj.insert("real_control_latency_us".into(), r.mean_us.into());
            obj.insert("real_control_latency_median_us".into(), r.median_us.into());
            obj.insert("real_control_latency_p95_us".into(), r.p95_us.into());
            obj.insert("real_detect_median_us".into(), r.detect_median_us.into());
            obj.insert("real_predict_median_us".into(), r.predict_median_us.into());
            obj.insert("real_cpu_median_us".into(), r.cpu_median_us.into());
            obj.insert("real_cpu_p95_us".into(), r.cpu_p95_us.into());
        }
        crate::say!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(());
    }
    crate::say!("simulate (pins + render): {:.1} us/tap", f.simulate_us);
    crate::say!("extract (detect + order): {:.1} us/frame", f.extract_us);
    crate::say!(
        "simulated taps per second (one core): {:.0}",
        f.taps_per_second
    );
    if let Some(l) = f.control_latency_us {
        let stat = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1}"));
        crate::say!(
            "control loop, frame -> command: mean {l:.1} us, median {} us, p95 {} us",
            stat(f.control_latency_median_us),
            stat(f.control_latency_p95_us)
        );
    }
    if let Some(p) = &f.prediction {
        crate::say!(
            "predict (both nets): {:.2} us a sample one at a time, {:.2} us in a batch; \
             {} + {} multiply-adds (f64 + f32), {:.2} us at the measured peak (batch {:.1}x that)",
            p.one_us,
            p.batch_us,
            p.multiply_adds_f64,
            p.multiply_adds_f32,
            p.fma_bound_us,
            p.batch_us / p.fma_bound_us
        );
    }
    if let Some(r) = real {
        crate::say!(
            "control loop on real frames, frame -> command: mean {:.1} us, median {:.1} us, p95 {:.1} us \
             (medians of the parts: detect {:.1} us, predict {:.1} us)",
            r.mean_us, r.median_us, r.p95_us, r.detect_median_us, r.predict_median_us
        );
        crate::say!(
            "the same, thread CPU time a frame: median {:.1} us, p95 {:.1} us",
            r.cpu_median_us,
            r.cpu_p95_us
        );
    }
    Ok(())
}

/// `--steps` and `--seed` over the configuration's follow settings.
fn overrides(a: &FollowArgs, follow: &mut LoopConfig) {
    if a.steps.is_some() {
        follow.steps = a.steps;
    }
    if let Some(s) = a.seed {
        follow.seed = s;
    }
}

/// `follow --hardware`: the same loop on the real rig.
fn follow_hardware(a: FollowArgs, path: &std::path::Path) -> Result<()> {
    Inputs::new()
        .add("--hardware", path)
        .add("--model", &a.model)
        .file_arg("--shape", a.shape.as_deref().unwrap_or_default())
        .check_apart("--out", &a.out)?;
    let mut cfg = HardwareConfig::read(path)?;
    overrides(&a, &mut cfg.follow);
    let world = World::Hardware(cfg).open()?;
    let shape = match &a.shape {
        Some(s) => {
            let spec = ShapeSpec::parse(s);
            Some((spec.name(), load_shape(&spec)?))
        }
        None => None,
    };
    let mut model = LoadedModel::load(&a.model)?;
    a.views.apply(&mut model)?;
    // From here on SIGINT / SIGTERM stop the arm (stopl) instead of the
    // process; the run keeps its steps and exits 130 / 143.
    let stop = StopFlag::on_signals().map_err(LabError::from)?;
    follow_in(
        world,
        &model,
        shape.as_ref(),
        (&a.out, a.force),
        Some(&stop),
    )
}
