//! The 3D tasks on the command line: `collect --task
//! surface_3d|edge_5d|edge_3d --object NAME_OR_FILE` and `follow --task
//! surface_3d|edge_5d|edge_3d --object ...`.
use crate::inputs::Inputs;
use crate::progress::{bar, follow_bar};
use anyhow::Result;
use clap::{Args, ValueEnum};
use std::path::Path;
use tactrace_control::Task;
use tactrace_lab::collect3d::{collect_3d, Collect3dConfig};
use tactrace_lab::LabError;
use tactrace_servo::{LoopSummary, Step3d};
use tactrace_shape3d::{ObjectConfig, Surface, OBJECT_NAMES};
use tactrace_store::{dataset, fsutil, OutputLock, StoredModel};

/// The servo task (`--task`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TaskArg {
    /// An edge in the plane (r, theta): the report's task, on `--shape`.
    #[value(name = "edge_2d")]
    Edge2d,
    /// A surface in 3D (depth z; tilts rx, ry), on `--object`.
    #[value(name = "surface_3d")]
    Surface3d,
    /// An edge at a varying height (x, z; rz), on an edged `--object`.
    #[value(name = "edge_3d")]
    Edge3d,
    /// An edge in 3D (x, z; rx, ry, rz), on an edged `--object`.
    #[value(name = "edge_5d")]
    Edge5d,
}

impl From<TaskArg> for Task {
    fn from(t: TaskArg) -> Self {
        match t {
            TaskArg::Edge2d => Task::Edge2d,
            TaskArg::Surface3d => Task::Surface3d,
            TaskArg::Edge3d => Task::Edge3d,
            TaskArg::Edge5d => Task::Edge5d,
        }
    }
}

/// `--task` and `--object` of `collect`.
#[derive(Args)]
pub struct CollectTaskArgs {
    /// The task whose poses are collected: edge_2d (the report's, on
    /// --shape), surface_3d (depth 1-5 mm, tilts +-25 deg, on --object;
    /// targets z mm, rx deg, ry deg), edge_5d (also x +-5 mm across
    /// the edge and rz +-180 deg, circular; on an edged --object) or
    /// edge_3d (x, z, rz; level to the face).
    #[arg(long, value_enum, default_value = "edge_2d", conflicts_with_all = ["hardware", "sensor"])]
    task: TaskArg,
    /// The 3D object of a 3D task: plane, ramp, saddle, bowl, wave, foil,
    /// an extruded report shape (disk, ...), the held-out dome, cylinder,
    /// bowl-50, ramp-32, foil-65, an extruded square:S or star:R,A,K, or
    /// an .stl / .obj mesh (mm).
    #[arg(long, default_value = "plane")]
    object: String,
    /// The point tapped: the object's top over this X,Y (mm); edge_5d:
    /// the edge point nearest it.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,0",
        allow_hyphen_values = true
    )]
    at: Vec<f64>,
    /// Tilts rx, ry uniform in +-DEG (default 25, the anchors').
    #[arg(long, value_name = "DEG")]
    tilt_range: Option<f64>,
    /// Edge tasks: x across the edge uniform in +-MM (default 5).
    #[arg(long, value_name = "MM")]
    x_range: Option<f64>,
    /// Edge tasks: rz uniform in +-DEG (default 180, the anchors').
    #[arg(long, value_name = "DEG")]
    rz_range: Option<f64>,
    /// 3D tasks: an unlabelled shear, a slide ending at each tap's pose
    /// with dx, dy uniform in +-MM in the sensor's plane (default 0; the
    /// anchors' real taps: 5). Seeded; recorded in the dataset's meta.
    #[arg(long, value_name = "MM")]
    shear_mm: Option<f64>,
    /// 3D tasks: an unlabelled twist ending at each tap's pose, uniform
    /// in +-DEG (default 0; the anchors': 5).
    #[arg(long, value_name = "DEG")]
    shear_deg: Option<f64>,
    /// surface_3d: each tap on a curved patch of its own (a quadric level
    /// under the origin, principal curvatures uniform in +-K per mm, at
    /// most 0.05: convex, concave, saddle-shaped) instead of --object,
    /// which must be left the plane (default 0: the object).
    #[arg(long, value_name = "K")]
    patch_curvature: Option<f64>,
    /// Edge tasks: each tap at an edge point drawn uniformly along the
    /// whole edge (seeded) instead of the one nearest --at.
    #[arg(long)]
    along_edge: bool,
}

impl CollectTaskArgs {
    /// Whether a 3D task was asked for.
    pub fn is_3d(&self) -> bool {
        self.task != TaskArg::Edge2d
    }

    /// Refuse the flags only a 3D collection reads (bad input) when the
    /// task is the planar one, rather than ignore them.
    pub fn refuse_3d_flags(&self) -> Result<()> {
        let given = [
            ("--tilt-range", self.tilt_range),
            ("--x-range", self.x_range),
            ("--rz-range", self.rz_range),
            ("--shear-mm", self.shear_mm),
            ("--shear-deg", self.shear_deg),
            ("--patch-curvature", self.patch_curvature),
        ];
        if self.along_edge && !self.is_3d() {
            return Err(LabError::Config(
                "--along-edge is for a 3D edge collection (--task edge_3d or edge_5d)".into(),
            )
            .into());
        }
        match given.iter().find(|(_, v)| v.is_some()) {
            Some((flag, _)) if !self.is_3d() => Err(LabError::Config(format!(
                "{flag} is for a 3D collection (--task surface_3d, edge_3d or edge_5d)"
            ))
            .into()),
            _ => Ok(()),
        }
    }
}

/// The two numbers of an `X,Y` (or `X Y`) flag; bad input otherwise.
fn xy(values: &[f64], flag: &str) -> Result<[f64; 2]> {
    match values {
        [x, y] => Ok([*x, *y]),
        _ => Err(LabError::Config(format!("{flag} takes two numbers, X,Y (mm)")).into()),
    }
}

/// The object `arg` names, built (a mesh is read); bad input otherwise.
pub fn object(arg: &str) -> Result<Surface> {
    let cfg = ObjectConfig::from_arg(arg).ok_or_else(|| {
        LabError::Config(format!(
            "--object {arg}: not a built-in object ({OBJECT_NAMES}) nor an .stl / .obj file"
        ))
    })?;
    Ok(cfg.build().map_err(LabError::from)?)
}

/// `collect --task surface_3d`: (samples, seed, save_frames), the rig
/// configuration file, and the output folder with `--force`.
pub fn collect(
    a: &CollectTaskArgs,
    (samples, seed, save_frames): (usize, u64, bool),
    config: Option<&Path>,
    (out, force): (&Path, bool),
) -> Result<()> {
    Inputs::new()
        .opt("--config", config)
        .file_arg("--object", &a.object)
        .check_apart("--out", out)?;
    let rig = crate::cmd_data::rig_config(config)?;
    let base = Collect3dConfig::default();
    let cfg = Collect3dConfig {
        samples,
        seed,
        task: a.task.into(),
        at_mm: xy(&a.at, "--at")?,
        save_frames,
        tilt_range_deg: a.tilt_range.unwrap_or(base.tilt_range_deg),
        x_range_mm: a.x_range.unwrap_or(base.x_range_mm),
        rz_range_deg: a.rz_range.unwrap_or(base.rz_range_deg),
        shear_mm: a.shear_mm.unwrap_or(base.shear_mm),
        shear_deg: a.shear_deg.unwrap_or(base.shear_deg),
        curvature_per_mm: a.patch_curvature.unwrap_or(base.curvature_per_mm),
        along_edge: a.along_edge,
        ..base
    };
    cfg.validate()?;
    let on_plane = a.object.trim().eq_ignore_ascii_case("plane") && cfg.at_mm == [0.0, 0.0];
    if cfg.curvature_per_mm > 0.0 && !on_plane {
        return Err(LabError::Config(
            "--patch-curvature taps patches under the origin: leave --object plane and --at 0,0"
                .into(),
        )
        .into());
    }
    let surface = object(&a.object)?;
    let _out = fsutil::check_output_dir(out, force)?;
    let pb = bar(samples as u64, "collect");
    let got = collect_3d(&rig, &surface, &cfg, &a.object, |i| {
        pb.set_position(i as u64)
    });
    pb.finish_and_clear();
    let got = got?;
    let dir = dataset::write_dataset(out, &got.data, &got.frames, force)?;
    eprintln!(
        "collected {} {} taps on {} into {} ({} with missing pins)",
        got.data.len(),
        cfg.task,
        a.object,
        dir.display(),
        got.data.meta.frames_with_missing_pins
    );
    Ok(())
}

/// `--task`, `--object` and the path of `follow`.
#[derive(Args)]
pub struct FollowTaskArgs {
    /// The task: edge_2d (the report's, on --shape; the default),
    /// surface_3d (on --object, with a model of the targets z, rx, ry),
    /// edge_5d (round an edged --object: x, z, rx, ry, rz) or edge_3d
    /// (x, z, rz).
    #[arg(long, value_enum, conflicts_with_all = ["hardware", "sensor", "replay"])]
    task: Option<TaskArg>,
    /// The 3D object of a 3D task: plane, ramp, saddle, bowl, wave, foil,
    /// an extruded report shape, the held-out dome, cylinder, bowl-50,
    /// ramp-32, foil-65, an extruded square:S or star:R,A,K, or an .stl /
    /// .obj mesh (mm).
    #[arg(long, requires = "task")]
    object: Option<String>,
    /// The path's start: the surface point over X,Y (mm); default: the
    /// object's (-40,0; the saddle -40,10; plane and ramps -20,0; the
    /// held-out dome, cylinder and bowl-50 their own, docs/3d.md). Edge
    /// tasks: the edge point nearest X,Y (default the edge's first).
    #[arg(
        long,
        value_delimiter = ',',
        requires = "task",
        allow_hyphen_values = true
    )]
    start: Option<Vec<f64>>,
    /// The path's heading in the xy plane, deg from +x (default 0;
    /// surface_3d only).
    #[arg(long, requires = "task", allow_negative_numbers = true)]
    heading: Option<f64>,
    /// Hold this direction of travel, deg from +x (surface_3d only): the
    /// controller turns the sensor about its axis onto it, with its rz
    /// gains (default: none, the start's heading is kept as it comes).
    #[arg(long, requires = "task", allow_negative_numbers = true)]
    steer: Option<f64>,
    /// The path's length, mm (default 80; plane and ramp 40; surface_3d
    /// only).
    #[arg(long, requires = "task")]
    length: Option<f64>,
    /// surface_3d in the real-frame world: every tap over --object
    /// answered by the row of this dataset (imported from a real surface
    /// collection, e.g. its held-out part with `import --like`) whose
    /// labels (depth, rx, ry) are nearest the tool's true pose.
    #[arg(long, value_name = "DATASET", requires = "task")]
    replay_data: Option<std::path::PathBuf>,
}

impl FollowTaskArgs {
    /// Whether a 3D task was asked for.
    pub fn is_3d(&self) -> bool {
        self.task.is_some_and(|t| t != TaskArg::Edge2d)
    }
}

/// `follow --task surface_3d`: the model, the run configuration file, the
/// seed, and the run folder with `--force`.
pub fn follow(
    a: &FollowTaskArgs,
    model: &Path,
    config: Option<&Path>,
    seed: Option<u64>,
    (out, force): (&Path, bool),
) -> Result<()> {
    use tactrace_lab::follow::task3d::{run_surface, PathConfig, Surface3dConfig};
    if a.task != Some(TaskArg::Surface3d) {
        return follow_edge(a, model, config, seed, (out, force));
    }
    let name = a.object.as_deref().unwrap_or("plane");
    let inputs = Inputs::new().opt("--replay-data", a.replay_data.as_deref());
    keep_apart(inputs, (model, config, name), out)?;
    let mut cfg: Surface3dConfig =
        tactrace_store::load_config(config, "surface follow configuration")?;
    if config.is_none() {
        cfg.path = PathConfig::for_object(name);
    }
    if let Some(s) = &a.start {
        cfg.path.start_mm = xy(s, "--start")?;
    }
    cfg.path.heading_deg = a.heading.unwrap_or(cfg.path.heading_deg);
    cfg.path.length_mm = a.length.unwrap_or(cfg.path.length_mm);
    if a.steer.is_some() {
        cfg.controller.heading_deg = a.steer;
    }
    cfg.run.seed = seed.unwrap_or(cfg.run.seed);
    cfg.validate()?;
    let surface = object(name)?;
    let (_out, model) = claim_and_load(model, (out, force))?;
    let res = follow_bar(cfg.steps(), |pb| -> Result<_> {
        let mut progress = |s: &Step3d| pb.set_position(s.step as u64 + 1);
        let Some(dir) = &a.replay_data else {
            return Ok(run_surface(
                &cfg,
                &surface,
                name,
                &model,
                (out, force),
                &mut progress,
            )?);
        };
        use tactrace_lab::follow::surface_replay::run_surface_replay;
        let data = tactrace_store::dataset::read_dataset(dir)?;
        let seen = model.training().map(|t| t.rows_seen(&data));
        let bank =
            tactrace_lab::world::SurfaceBank::from_dataset(&data)?.with_rows_seen_in_training(seen);
        if let Some(k) = seen.filter(|&k| k > 0) {
            eprintln!(
                "warning: {k} of the bank's {} rows were in the model's training data: \
                 this run's figures are not held-out ones",
                bank.len()
            );
        }
        let (outcome, stats) = run_surface_replay(
            &cfg,
            (&surface, name),
            &bank,
            &model,
            (out, force),
            &mut progress,
        )?;
        eprintln!(
            "real-frame world: {} taps answered by {} of the {} rows, label distance \
             mean {:.3} / max {:.3}",
            stats.taps,
            stats.distinct_rows,
            stats.bank_rows,
            stats.mean_label_distance,
            stats.max_label_distance
        );
        Ok(outcome)
    })?;
    let m = &res.metrics;
    say_run(
        &format!("{name}:"),
        (m.steps, &res.summary),
        ("depth error", m.mean_distance_mm, m.max_distance_mm),
        (m.mean_normal_error_deg, m.max_normal_error_deg),
        m.coverage,
    )?;
    run_ended(&res.summary, &res.dir)
}

/// How a 3D run ended: its message and folder, and a failed run (lost
/// contact, a refused move, the step cap of an edge run) as an error.
fn run_ended(summary: &LoopSummary, dir: &Path) -> Result<()> {
    if !summary.ending.succeeded() {
        eprintln!("the run and its trajectory so far are in {}", dir.display());
        return Err(LabError::RunFailed {
            ending: summary.ending,
            message: summary.message.clone(),
        }
        .into());
    }
    eprintln!("{} (run folder {})", summary.message, dir.display());
    Ok(())
}

/// `follow --task edge_5d|edge_3d`: round the edge of `--object`.
fn follow_edge(
    a: &FollowTaskArgs,
    model: &Path,
    config: Option<&Path>,
    seed: Option<u64>,
    (out, force): (&Path, bool),
) -> Result<()> {
    use tactrace_control::Se3Config;
    use tactrace_lab::follow::edge3d::{edge_of, run_edge, Edge3dConfig};
    let task: Task = a.task.unwrap_or(TaskArg::Edge5d).into();
    if a.heading.is_some() || a.length.is_some() || a.steer.is_some() || a.replay_data.is_some() {
        return Err(LabError::Config(format!(
            "--heading, --steer, --length and --replay-data are surface_3d's: {task} follows the edge round"
        ))
        .into());
    }
    let name = a.object.as_deref().unwrap_or("foil");
    keep_apart(Inputs::new(), (model, config, name), out)?;
    let mut cfg: Edge3dConfig = tactrace_store::load_config(config, "edge follow configuration")?;
    if config.is_none() {
        cfg.controller = Se3Config::for_task(task);
    }
    if cfg.controller.task != task {
        return Err(LabError::Config(format!(
            "--task {task} but the configuration's controller.task is {}",
            cfg.controller.task
        ))
        .into());
    }
    if let Some(s) = &a.start {
        cfg.start_mm = Some(xy(s, "--start")?);
    }
    cfg.run.seed = seed.unwrap_or(cfg.run.seed);
    cfg.validate()?;
    let surface = object(name)?;
    let edge = edge_of(&surface, name)?;
    let (_out, model) = claim_and_load(model, (out, force))?;
    let res = follow_bar(cfg.steps(&edge), |pb| {
        let mut progress = |s: &Step3d| pb.set_position(s.step as u64 + 1);
        run_edge(&cfg, &surface, name, &model, (out, force), &mut progress)
    })?;
    let m = &res.metrics;
    say_run(
        &format!("{name}: {task},"),
        (m.steps, &res.summary),
        (
            "distance from the edge",
            m.mean_distance_mm,
            m.max_distance_mm,
        ),
        (m.mean_normal_error_deg, m.max_normal_error_deg),
        m.coverage,
    )?;
    run_ended(&res.summary, &res.dir)
}

/// The inputs of a 3D follow run kept apart from its folder `out`: the
/// task's own (`inputs`), then the model, the configuration file and the
/// `--object` when it names a mesh file.
fn keep_apart(
    inputs: Inputs,
    (model, config, object): (&Path, Option<&Path>, &str),
    out: &Path,
) -> Result<()> {
    inputs
        .add("--model", model)
        .opt("--config", config)
        .file_arg("--object", object)
        .check_apart("--out", out)?;
    Ok(())
}

/// The last checks before a 3D run starts, once its settings and object
/// are good: the run folder free (its lock held until the returned guard
/// drops), then the model loaded.
fn claim_and_load(model: &Path, (out, force): (&Path, bool)) -> Result<(OutputLock, StoredModel)> {
    let lock = fsutil::check_output_dir(out, force)?;
    Ok((lock, StoredModel::load(model)?))
}

/// A finished 3D run's line: `head` (the object, the task), its steps and
/// ending, `distance` (what is measured, mean and max, mm), the normal
/// error (mean and max, deg) and the coverage (a fraction, shown in %).
fn say_run(
    head: &str,
    (steps, summary): (usize, &LoopSummary),
    (distance, mean_mm, max_mm): (&str, f64, f64),
    (mean_deg, max_deg): (f64, f64),
    coverage: f64,
) -> Result<()> {
    crate::say!(
        "{head} {steps} steps, {}; {distance} mean {mean_mm:.3} / max {max_mm:.3} mm, normal \
         error mean {mean_deg:.2} / max {max_deg:.2} deg, coverage {:.0}%",
        summary.ending,
        100.0 * coverage
    );
    Ok(())
}
