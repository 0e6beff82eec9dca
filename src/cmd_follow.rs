//! Experiment commands: `follow` and `reproduce`.
use crate::progress::bar;
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use tactrace_geometry::ShapeSpec;
use tactrace_lab::follow::{run_follow, FollowRunConfig};
use tactrace_lab::hardware::{run_follow_hardware, HardwareConfig};
use tactrace_lab::report::{reproduce as run_reproduce, ReproduceConfig};
use tactrace_lab::{figures, fsutil, model_io, settings, shape_io, LabError};

#[derive(Args)]
pub struct FollowArgs {
    /// Model directory (from `tactrace train`).
    #[arg(long)]
    model: PathBuf,
    /// Built-in shape (disk, flower, trine, teardrop) or a CSV of x,y points
    /// (mm). With --hardware: optional, the object's true contour in the
    /// work frame, used only to score the run.
    #[arg(long, required_unless_present = "hardware")]
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
    #[arg(long)]
    seed: Option<u64>,
    /// Run directory.
    #[arg(long)]
    out: PathBuf,
}

fn follow_config(path: Option<&std::path::Path>) -> Result<FollowRunConfig> {
    let base = FollowRunConfig::simulated();
    let Some(path) = path else {
        return Ok(base);
    };
    let text = fsutil::read_text(path)?;
    let what = format!("{}: follow configuration", path.display());
    Ok(settings::overlay(&base, &text, &what)?)
}

pub fn follow(a: FollowArgs) -> Result<()> {
    if let Some(hw) = a.hardware.clone() {
        return follow_hardware(a, &hw);
    }
    let mut cfg = follow_config(a.config.as_deref())?;
    overrides(&a, &mut cfg.follow);
    let spec = ShapeSpec::parse(a.shape.as_deref().unwrap_or_default());
    let contour = shape_io::load_shape(&spec)?;
    let (model, pins) = start_run(&a, &toml::to_string(&cfg)?)?;
    let pb = bar(a.steps.unwrap_or(cfg.follow.max_steps) as u64, "follow");
    let res = run_follow(&cfg, (model, pins.as_deref()), &contour, &a.out, &mut |r| {
        pb.set_position(r.step as u64 + 1)
    })?;
    pb.finish_and_clear();
    let traj: Vec<(f64, f64)> = res.records.iter().map(|r| (r.pose.x, r.pose.y)).collect();
    figures::trajectory(&a.out.join("trajectory"), &spec.name(), &contour, &traj)?;
    figures::error_curve(&a.out.join("l2_error"), &spec.name(), &res.l2_curve)?;
    let m = &res.metrics;
    println!(
        "{}: {} steps, {:?}; mean L2 {:.3} mm, track error mean {:.3} / max {:.3} mm, coverage {:.0}%",
        spec.name(),
        m.steps,
        res.summary.ending,
        m.mean_l2_mm,
        m.mean_track_error_mm,
        m.max_track_error_mm,
        100.0 * m.coverage
    );
    eprintln!("{}", res.summary.message);
    Ok(())
}

#[derive(Args)]
pub struct ReproduceArgs {
    /// Output directory for data, models, runs, figures and the report.
    #[arg(long, default_value = "runs/reproduce")]
    out: PathBuf,
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
    /// Reproduce TOML overlaying the defaults (keys: seed, train_samples,
    /// val_samples, epochs, preset, report_steps, real, and the follow
    /// tables rig, controller, follow, start).
    #[arg(long)]
    config: Option<PathBuf>,
}

pub fn reproduce(a: ReproduceArgs) -> Result<()> {
    let mut cfg = match &a.config {
        Some(path) => {
            let text = fsutil::read_text(path)?;
            let what = format!("{}: reproduce configuration", path.display());
            settings::overlay(&ReproduceConfig::default(), &text, &what)?
        }
        None => ReproduceConfig::default(),
    };
    cfg.seed = a.seed.unwrap_or(cfg.seed);
    cfg.epochs = a.epochs.or(cfg.epochs);
    cfg.report_steps |= a.report_steps;
    cfg.real = a.real.or(cfg.real);
    let log = |msg: &str| eprintln!("[reproduce] {msg}");
    let r = run_reproduce(&cfg, &a.out, &log)?;
    let runs = [
        ("simulated", &r.networks),
        ("real", &r.real_networks),
        ("sim->real", &r.sim_to_real),
    ];
    for (data, rows) in runs {
        for n in rows.iter() {
            println!(
                "{:<16} {data:<9} angle {:.2} deg, position {:.3} mm",
                n.name, n.angle_mae_deg, n.position_mae_mm
            );
        }
    }
    for s in &r.shapes {
        println!(
            "{:<16} mean L2 {:.2} mm (report {:.2}), closed {}",
            s.shape, s.metrics.mean_l2_mm, s.report_l2_mm, s.metrics.closed
        );
    }
    println!("report: {}", a.out.join("report.html").display());
    Ok(())
}

#[derive(Args)]
pub struct BenchArgs {
    /// Number of simulated taps to time.
    #[arg(long, default_value_t = 2000)]
    taps: usize,
    /// A model directory: also time the control loop (frame -> command).
    #[arg(long)]
    model: Option<PathBuf>,
    /// A folder of real frames (Bristol layout, with init_0.png): also time
    /// the control loop on them (needs --model).
    #[arg(long)]
    real_frames: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

pub fn bench(a: BenchArgs) -> Result<()> {
    let model = a.model.as_deref().map(model_io::load_model).transpose()?;
    let rig = tactrace_lab::rig::RigConfig::simulated();
    let f = tactrace_lab::bench::bench(&rig, a.taps.max(1), model.as_ref())?;
    let real = match (&a.real_frames, &model) {
        (Some(dir), Some(m)) => {
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
        }
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(());
    }
    println!("simulate (pins + render): {:.1} us/tap", f.simulate_us);
    println!("extract (detect + order): {:.1} us/frame", f.extract_us);
    println!(
        "simulated taps per second (one core): {:.0}",
        f.taps_per_second
    );
    if let Some(l) = f.control_latency_us {
        let stat = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.1}"));
        println!(
            "control loop, frame -> command: mean {l:.1} us, median {} us, p95 {} us",
            stat(f.control_latency_median_us),
            stat(f.control_latency_p95_us)
        );
    }
    if let Some(r) = real {
        println!(
            "control loop on real frames, frame -> command: mean {:.1} us, median {:.1} us, p95 {:.1} us",
            r.mean_us, r.median_us, r.p95_us
        );
    }
    Ok(())
}

/// `--steps` and `--seed` over the configuration's follow settings.
fn overrides(a: &FollowArgs, follow: &mut tactrace_lab::servo::FollowConfig) {
    if a.steps.is_some() {
        follow.steps = a.steps;
    }
    if let Some(s) = a.seed {
        follow.seed = s;
    }
}

/// Load the model, create the run directory and record the resolved
/// configuration in it (before anything moves).
/// The model and its training data's reference pins (if saved).
type ModelAndPins = (tactrace_learn::PoseModel, Option<Vec<[f64; 2]>>);

fn start_run(a: &FollowArgs, config_toml: &str) -> Result<ModelAndPins> {
    let model = model_io::load_model(&a.model)?;
    let pins = model_io::load_reference_pins(&a.model)?;
    std::fs::create_dir_all(&a.out).with_context(|| a.out.display().to_string())?;
    fsutil::write_atomic(&a.out.join("config.toml"), config_toml.as_bytes())?;
    Ok((model, pins))
}

/// `follow --hardware`: the same loop on the real rig.
fn follow_hardware(a: FollowArgs, path: &std::path::Path) -> Result<()> {
    let text = fsutil::read_text(path)?;
    let mut cfg = HardwareConfig::from_toml(&text, &path.display().to_string())?;
    overrides(&a, &mut cfg.follow);
    cfg.validate()?;
    let shape = match &a.shape {
        Some(s) => {
            let spec = ShapeSpec::parse(s);
            Some((spec.name(), shape_io::load_shape(&spec)?))
        }
        None => None,
    };
    let (model, pins) = start_run(&a, &toml::to_string(&cfg)?)?;
    let pb = bar(a.steps.unwrap_or(cfg.follow.max_steps) as u64, "follow");
    let res = run_follow_hardware(
        &cfg,
        (model, pins.as_deref()),
        shape.as_ref().map(|s| &s.1),
        &a.out,
        &mut |r| pb.set_position(r.step as u64 + 1),
    )?;
    pb.finish_and_clear();
    if let (Some((name, contour)), Some((m, curve))) = (&shape, &res.metrics) {
        let traj: Vec<(f64, f64)> = res.records.iter().map(|r| (r.pose.x, r.pose.y)).collect();
        figures::trajectory(&a.out.join("trajectory"), name, contour, &traj)?;
        figures::error_curve(&a.out.join("l2_error"), name, curve)?;
        println!(
            "{name}: {} steps, {:?}; mean L2 {:.3} mm, track error mean {:.3} mm",
            m.steps, res.summary.ending, m.mean_l2_mm, m.mean_track_error_mm
        );
    } else {
        println!("{} steps, {:?}", res.summary.steps, res.summary.ending);
    }
    eprintln!("{}", res.summary.message);
    Ok(())
}
