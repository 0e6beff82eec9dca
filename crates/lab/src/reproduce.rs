//! `tactrace reproduce`: the whole report, end to end, in one directory.
//!
//! Collect on the disk (train and validation runs), train the three
//! networks and the backprop twin, validate them, follow the four shapes
//! with the PDenNN, and write report.md, report.html and metrics.json with
//! the report's numbers side by side. With real frames (`--real`), the
//! networks on real frames and the simulator's twin, and the four shapes
//! in the real-frame world ([`crate::world::ReplayWorld`]): the PDenNN
//! trained on the real 80 %, every tap answered by the held-out 20 %.
use crate::collect::{collect, CollectConfig};
use crate::error::{LabError, Result};
use crate::follow::{FollowOutcome, RunHooks, SimFollowConfig};
use crate::train::{resolve_config, save_model, train, validate_net, Validation};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_geometry::{builtin_shape, BuiltinShape, Contour};
use tactrace_learn::{ModelKind, Preset};
use tactrace_report::figures::{self, Predicted};
use tactrace_report::results::slug;
use tactrace_report::{NetRow, ReplayShapeRow, ReproduceResults, ShapeRow};
use tactrace_servo::pose_at_edge;
use tactrace_store::collection::CollectionEdits;
use tactrace_store::{
    write_atomic, write_dataset, LabelledCollection, LoadedModel, SensorFolder, StagedDir,
    StoredModel, TapData, TrainingRecord,
};
use tactrace_vision::PinExtractor;
/// The report's contour-following mean L2 errors, mm (ch. 5.3).
pub const REPORT_L2: [(BuiltinShape, f64, usize); 4] = [
    (BuiltinShape::Disk, 0.75, 266),
    (BuiltinShape::Flower, 1.01, 272),
    (BuiltinShape::Trine, 0.89, 222),
    (BuiltinShape::Teardrop, 1.16, 260),
];

/// What `reproduce` runs.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReproduceConfig {
    pub seed: u64,
    pub train_samples: usize,
    pub val_samples: usize,
    /// Epochs for every network (report: 200).
    pub epochs: Option<usize>,
    pub preset: Preset,
    /// Use the report's fixed step counts instead of running to closure.
    pub report_steps: bool,
    /// The follow settings: the report's ([`SimFollowConfig::report`]).
    pub follow: SimFollowConfig,
    /// Folder of real frames (Bristol layout) to add the real-data results.
    pub real: Option<PathBuf>,
    /// Add surface following in 3D (`--3d`: [`crate::reproduce3d`]).
    #[serde(default, rename = "3d", skip_serializing_if = "std::ops::Not::not")]
    pub three_d: bool,
    /// With `real`: also train the image model `conv-dennn` on the real
    /// frames and follow the four shapes with it in the real-frame world.
    #[serde(default)]
    pub image_model: bool,
}

impl Default for ReproduceConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            train_samples: 1000,
            val_samples: 500,
            epochs: None,
            preset: Preset::Default,
            report_steps: false,
            follow: SimFollowConfig::report(),
            real: None,
            three_d: false,
            image_model: false,
        }
    }
}

const NETS: [(ModelKind, &str); 4] = [
    (ModelKind::DisDenNN, "DisDenNN"),
    (ModelKind::PcaDenNN, "PCADenNN"),
    (ModelKind::PDenNN, "PDenNN"),
    (ModelKind::Mlp, "MLP (backprop)"),
];

pub(crate) fn train_and_score(
    kind: ModelKind,
    name: &str,
    cfg: &ReproduceConfig,
    tr: &TapData,
    va: &TapData,
    dir: &Path,
) -> Result<(NetRow, Validation)> {
    let figs = dir.join("figures");
    std::fs::create_dir_all(&figs).map_err(tactrace_store::write_err(&figs))?;
    let mcfg = resolve_config(kind, cfg.preset, None, cfg.epochs)?;
    let t0 = std::time::Instant::now();
    let (model, history) = train(&mcfg, tr, &mut |_| {})?;
    let secs = t0.elapsed().as_secs_f64();
    let mdir = dir
        .join("models")
        .join(name.split(' ').next().unwrap_or(name).to_lowercase());
    let stored = StoredModel::new(model.clone(), tr.meta.reference_pins.clone())
        .with_training(TrainingRecord::all_rows(tr, None));
    save_model(&mdir, &stored, &history, true, &[])?;
    let v = validate_net(&model, va)?;
    let predicted = Predicted {
        truth: &v.truth,
        predictions: &v.predictions,
        mae: [v.position_mae_mm, v.angle_mae_deg],
    };
    figures::predicted_vs_true(
        &dir.join("figures").join(format!("fig4_4_{}", slug(name))),
        name,
        &predicted,
    )?;
    let row = NetRow {
        name: name.into(),
        data: tr.meta.source.clone(),
        position_mae_mm: v.position_mae_mm,
        angle_mae_deg: v.angle_mae_deg,
        train_seconds: secs,
        lr_halvings: history.lr_halvings,
    };
    Ok((row, v))
}

/// Run everything into `out`, which appears only when complete; an
/// existing `out` is refused unless `force` (then replaced at the end).
pub fn reproduce(
    cfg: &ReproduceConfig,
    (out, force): (&Path, bool),
    log: &(dyn Fn(&str) + Sync),
) -> Result<ReproduceResults> {
    if cfg.follow.replay.is_some() {
        return Err(LabError::Config(
            "reproduce runs the simulated world, and with --real the real-frame world on its \
             own held-out frames: leave [follow.replay] out"
                .into(),
        ));
    }
    if cfg.image_model && cfg.real.is_none() {
        return Err(LabError::Config(
            "the image model is trained and followed on real frames: give --real DIR".into(),
        ));
    }
    let stage = StagedDir::new(out, force)?;
    let results = reproduce_into(cfg, stage.path(), log)?;
    stage.commit()?;
    Ok(results)
}

fn reproduce_into(
    cfg: &ReproduceConfig,
    out: &Path,
    log: &(dyn Fn(&str) + Sync),
) -> Result<ReproduceResults> {
    let t0 = std::time::Instant::now();
    let figs = out.join("figures");
    std::fs::create_dir_all(&figs).map_err(tactrace_store::write_err(&figs))?;
    let text = tactrace_store::resolved_config_toml(crate::VERSION, cfg)?;
    write_atomic(&out.join("config.toml"), text.as_bytes())?;
    let disk = builtin_shape(BuiltinShape::Disk);
    let rig = &cfg.follow.rig;
    log("collecting training and validation taps on the disk");
    let tcfg = CollectConfig {
        samples: cfg.train_samples,
        seed: cfg.seed,
        ..CollectConfig::default()
    };
    let vcfg = CollectConfig {
        samples: cfg.val_samples,
        seed: cfg.seed + 1000,
        ..CollectConfig::default()
    };
    let calibrated = cfg
        .follow
        .calibrated_sensor
        .as_deref()
        .map(SensorFolder::read)
        .transpose()?;
    let collect_on_disk = |c: &CollectConfig| match &calibrated {
        Some(s) => crate::collect::collect_calibrated(rig, s, &disk, c, "disk", |_| {}),
        None => collect(rig, &disk, c, "disk", |_| {}),
    };
    let (tr, va) = rayon::join(|| collect_on_disk(&tcfg), || collect_on_disk(&vcfg));
    let (tr, va) = (tr?.data, va?.data);
    write_dataset(&out.join("data/train"), &tr, &[], true)?;
    write_dataset(&out.join("data/val"), &va, &[], true)?;
    fig_4_1_simulated(rig, &disk, &out.join("figures/fig4_1_simulated"))?;
    log("training DisDenNN, PCADenNN, PDenNN and the backprop twin");
    let trained: Vec<Result<(NetRow, Validation)>> = NETS
        .par_iter()
        .map(|(k, name)| train_and_score(*k, name, cfg, &tr, &va, out))
        .collect();
    let mut networks = Vec::new();
    for r in trained {
        networks.push(r?.0);
    }
    log("following the four shapes with the PDenNN");
    let shapes = follow_report_shapes(
        cfg,
        &cfg.follow,
        &out.join("models/pdennn"),
        (&out.join("follow"), &out.join("figures"), ""),
    )?;
    let (real_rows, real_shapes, real_image_shapes) = match &cfg.real {
        Some(real) => {
            log("importing real frames and training on them, on their simulated twin, and on the calibrated twin");
            let rows = real_rows(cfg, real, out, log)?;
            log("following the four shapes in the real-frame world");
            let dir = out.join("real");
            let (model, runs) = (dir.join("models/pdennn"), dir.join("follow"));
            let shapes = match &rows.held_out {
                Some(va) => real_world_shapes(cfg, real, va, (&model, &runs))?,
                None => Vec::new(),
            };
            let image = match (&rows.held_out, cfg.image_model) {
                (Some(va), true) => {
                    log("training the image model (conv-dennn) on the real frames and following the four shapes with it");
                    crate::reproduce_image::image_world_shapes(cfg, real, va, &dir)?
                }
                _ => Vec::new(),
            };
            (rows, shapes, image)
        }
        None => (RealRows::default(), Vec::new(), Vec::new()),
    };
    let surface_3d = if cfg.three_d {
        Some(crate::reproduce3d::surface_section(cfg, out, log)?)
    } else {
        None
    };
    let results = ReproduceResults {
        networks,
        real_networks: real_rows.real,
        sim_to_real: real_rows.sim_to_real,
        calibration: real_rows.calibration,
        real_model_shapes: real_rows.real_model_shapes,
        calibrated_sensor: cfg
            .follow
            .calibrated_sensor
            .as_ref()
            .map(|p| p.display().to_string()),
        shapes,
        real_shapes,
        surface_3d,
        real_image_shapes,
        seconds: t0.elapsed().as_secs_f64(),
        seed: cfg.seed,
        tactrace_version: crate::VERSION.into(),
    };
    tactrace_report::document::write_report(out, &results)?;
    Ok(results)
}

/// The report's four shapes followed with the model in `model_dir` in the
/// simulated world of `fcfg`: run folders under `runs`, figures
/// `fig5_3_{tag}{shape}` and `fig5_4_{tag}{shape}` under `figs`.
fn follow_report_shapes(
    cfg: &ReproduceConfig,
    fcfg: &SimFollowConfig,
    model_dir: &Path,
    (runs, figs, tag): (&Path, &Path, &str),
) -> Result<Vec<ShapeRow>> {
    let shapes: Vec<Result<ShapeRow>> = REPORT_L2
        .par_iter()
        .map(|(shape, report_l2, steps)| {
            let model = StoredModel::load(model_dir)?;
            let mut fcfg = fcfg.clone();
            if cfg.report_steps {
                fcfg.follow.steps = Some(*steps);
            }
            fcfg.follow.seed = cfg.seed;
            let contour = builtin_shape(*shape);
            let run = runs.join(shape.name());
            let named = (shape.name(), &contour);
            let res = follow_quietly(&fcfg, &model, named, &run)?;
            let traj: Vec<(f64, f64)> = res.records.iter().map(|r| (r.pose.x, r.pose.y)).collect();
            let name = shape.name();
            figures::trajectory(
                &figs.join(format!("fig5_3_{tag}{name}")),
                name,
                &contour,
                &traj,
            )?;
            figures::error_curve(
                &figs.join(format!("fig5_4_{tag}{name}")),
                name,
                &contour,
                &res.l2_curve,
            )?;
            let metrics = res.metrics.expect("scored against the known contour");
            Ok(ShapeRow {
                shape: name.into(),
                metrics,
                ending: res.summary.ending,
                report_l2_mm: *report_l2,
            })
        })
        .collect();
    shapes.into_iter().collect()
}

/// Follow `shape` in the world of `fcfg` with `model` into `run`
/// (replaced), telling no one.
fn follow_quietly(
    fcfg: &SimFollowConfig,
    model: &StoredModel,
    shape: (&str, &Contour),
    run: &Path,
) -> Result<FollowOutcome> {
    let hooks = RunHooks::default();
    crate::follow::run(fcfg.world().open()?, model, Some(shape), (run, true), hooks)
}

/// [`follow_quietly`] with any model (pin or image).
fn follow_any_quietly(
    fcfg: &SimFollowConfig,
    model: &LoadedModel,
    shape: (&str, &Contour),
    run: &Path,
) -> Result<FollowOutcome> {
    let hooks = RunHooks::default();
    crate::follow::run_model(fcfg.world().open()?, model, Some(shape), (run, true), hooks)
}

/// What `--real` adds to the report.
#[derive(Default)]
struct RealRows {
    real: Vec<NetRow>,
    sim_to_real: Vec<NetRow>,
    calibration: Vec<tactrace_report::CalibrationRow>,
    /// The PDenNN trained on real frames following the four shapes in the
    /// simulator calibrated with 100 of its training taps.
    real_model_shapes: Vec<ShapeRow>,
    /// The real frames held out of training (the real-frame world's bank).
    held_out: Option<TapData>,
}

/// Train every network on real frames (seeded 80/20 split) and validate on
/// the 20 %; then train the PDenNN and the MLP on the simulated twin of the
/// real set (its own 80 %) and validate them on the same real 20 %; then
/// the calibrated simulator's rows ([`crate::calibration_sweep`]).
fn real_rows(
    cfg: &ReproduceConfig,
    dir: &Path,
    out: &Path,
    log: &(dyn Fn(&str) + Sync),
) -> Result<RealRows> {
    let collection = LabelledCollection::bristol(dir);
    fig_4_1_real(&collection, &out.join("figures/fig4_1_real"))?;
    let imported = crate::import::import(&collection, &|| {})?;
    for w in &imported.warnings {
        log(&format!("warning: {w}"));
    }
    let (tr, va) = imported.data.split(0.8, cfg.seed);
    let real = train_rows(cfg, &NETS, "real", &tr, &va, &out.join("real"))?;
    let sensor = &cfg.follow.rig.sensor;
    let twin = crate::twin::simulate_twin(&collection, sensor, cfg.seed, &|| {})?;
    let twin_tr = rows_not_in(&twin.data, &va);
    let nets = [NETS[2], NETS[3]];
    let mut transfer = train_rows(cfg, &nets, "twin", &twin_tr, &va, &out.join("twin"))?;
    let split = crate::calibration_sweep::Split {
        collection: &collection,
        render_seed: cfg.seed,
        training: &tr,
        validation: &va,
    };
    let (calibration, headline) = crate::calibration_sweep::calibration_rows(cfg, &split, out)?;
    transfer.push(headline);
    let fcfg = SimFollowConfig {
        calibrated_sensor: Some(out.join("sensor")),
        ..cfg.follow.clone()
    };
    let real_model_shapes = follow_report_shapes(
        cfg,
        &fcfg,
        &out.join("real/models/pdennn"),
        (
            &out.join("follow-calibrated"),
            &out.join("figures"),
            "calibrated_",
        ),
    )?;
    Ok(RealRows {
        real,
        sim_to_real: transfer,
        calibration,
        real_model_shapes,
        held_out: Some(va),
    })
}

/// The rows of `data` whose image is not among `held_out`'s: the twin's
/// training part, joined with the real split on the image name (import and
/// twin may each drop frames, so row indices need not correspond).
pub(crate) fn rows_not_in(data: &TapData, held_out: &TapData) -> TapData {
    let held: std::collections::HashSet<&str> =
        held_out.meta.images.iter().map(String::as_str).collect();
    let keep: Vec<usize> = (0..data.len())
        .filter(|&i| {
            data.meta
                .images
                .get(i)
                .is_some_and(|name| !held.contains(name.as_str()))
        })
        .collect();
    data.subset(&keep)
}

/// Train `nets` in parallel on `tr`, validate on `va`; rows named plainly,
/// files under `dir` with the `tag` in the figure names.
fn train_rows(
    cfg: &ReproduceConfig,
    nets: &[(ModelKind, &str)],
    tag: &str,
    tr: &TapData,
    va: &TapData,
    dir: &Path,
) -> Result<Vec<NetRow>> {
    let rows: Vec<Result<NetRow>> = nets
        .par_iter()
        .map(|(k, name)| {
            let (mut row, _) = train_and_score(*k, &format!("{name} {tag}"), cfg, tr, va, dir)?;
            row.name = name.to_string();
            Ok(row)
        })
        .collect();
    rows.into_iter().collect()
}

/// Fig. 4.1 on a simulated tap: 2 mm onto the disk edge, 10 deg, nominal depth.
fn fig_4_1_simulated(rig: &tactrace_servo::RigConfig, disk: &Contour, stem: &Path) -> Result<()> {
    let model = tactrace_sensor::TacTipModel::new(rig.sensor.clone())?;
    let reference = model.render(model.rest_pins(), None);
    let extractor = PinExtractor::from_reference_frame(&reference, rig.blob.clone())?;
    let (edge, normal) = disk.at_arc_length(0.0);
    let depth = rig.tap.nominal_indentation_mm();
    let pose = pose_at_edge(edge, normal, 2.0, 10.0, -depth);
    let frame = model.render(&model.pins(disk, pose, None), None);
    figures::frame_pins_displacements(stem, &frame, &extractor, 3.0)?;
    Ok(())
}

/// Fig. 4.1 on a real frame of the Bristol set `collection`.
fn fig_4_1_real(collection: &LabelledCollection, stem: &Path) -> Result<()> {
    let reference = tactrace_sensor::read_frame(collection.reference().path()?)?;
    let frame = tactrace_sensor::read_frame(&collection.frames().join("frame_0_0.png"))?;
    let extractor = PinExtractor::from_reference_frame(&reference, collection.blob().clone())?;
    figures::frame_pins_displacements(stem, &frame, &extractor, 3.0)?;
    Ok(())
}

/// The report's four shapes in the real-frame world (`follow --replay`):
/// the model in `model_dir` (the PDenNN, or the image model, trained on
/// the real 80 %), every tap answered by a frame of the held-out 20 %
/// (`held_out`, written as `bank.csv` beside `runs`), runs in
/// `runs/SHAPE`.
pub(crate) fn real_world_shapes(
    cfg: &ReproduceConfig,
    real: &Path,
    held_out: &TapData,
    (model_dir, runs): (&Path, &Path),
) -> Result<Vec<ReplayShapeRow>> {
    let bank = crate::world::ReplayBank::from_dir(real, &CollectionEdits::default())?;
    let dir = runs.parent().unwrap_or(runs);
    let part = bank
        .collection()
        .with_images(&held_out.meta.images, &dir.join("bank.csv"))?;
    let bank = bank.with_collection(part)?;
    let rows: Vec<Result<ReplayShapeRow>> = REPORT_L2
        .par_iter()
        .map(|(shape, report_l2, steps)| {
            let model = LoadedModel::load(model_dir)?;
            let mut fcfg = cfg.follow.clone();
            if cfg.report_steps {
                fcfg.follow.steps = Some(*steps);
            }
            fcfg.follow.seed = cfg.seed;
            let contour = builtin_shape(*shape);
            let run = runs.join(shape.name());
            fcfg.replay = Some(bank.clone());
            let named = (shape.name(), &contour);
            let res = follow_any_quietly(&fcfg, &model, named, &run)?;
            let metrics = res.metrics.expect("scored against the known contour");
            let stats = res.replay.expect("the real-frame world's statistics");
            Ok(ReplayShapeRow {
                shape: shape.name().into(),
                metrics,
                ending: res.summary.ending,
                report_l2_mm: *report_l2,
                bank_frames: stats.bank_frames,
                label_distance_mean: stats.distance_mean,
                label_distance_p95: stats.distance_p95,
                label_distance_max: stats.distance_max,
            })
        })
        .collect();
    rows.into_iter().collect()
}
