//! `tactrace reproduce`: the whole report, end to end, in one directory.
//!
//! Collect on the disk (train and validation runs), train the three
//! networks and the backprop twin, validate them, follow the four shapes
//! with the PDenNN, and write report.md, report.html and metrics.json with
//! the report's numbers side by side.
use crate::collect::{collect, CollectConfig};
use crate::error::Result;
use crate::follow::{follow_simulated, SimFollowConfig};
use crate::train::{resolve_config, save_model, train, validate_net, Validation};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_geometry::{builtin_shape, BuiltinShape, Contour};
use tactrace_learn::{ModelKind, Preset};
use tactrace_report::figures::{self, Predicted};
use tactrace_report::results::slug;
use tactrace_report::{NetRow, ReproduceResults, ShapeRow};
use tactrace_servo::pose_at_edge;
use tactrace_store::{write_atomic, write_dataset, StagedDir, StoredModel, TapData};
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
        }
    }
}

const NETS: [(ModelKind, &str); 4] = [
    (ModelKind::DisDenNN, "DisDenNN"),
    (ModelKind::PcaDenNN, "PCADenNN"),
    (ModelKind::PDenNN, "PDenNN"),
    (ModelKind::Mlp, "MLP (backprop)"),
];

fn train_and_score(
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
    save_model(&mdir, &model, &tr.meta.reference_pins, &history, true, &[])?;
    let v = validate_net(&model, va)?;
    let predicted = Predicted {
        truth: &v.truth,
        predictions: &v.predictions,
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
    let (tr, va) = rayon::join(
        || collect(rig, &disk, &tcfg, "disk", |_| {}),
        || collect(rig, &disk, &vcfg, "disk", |_| {}),
    );
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
    let shapes: Vec<Result<ShapeRow>> = REPORT_L2
        .par_iter()
        .map(|(shape, report_l2, steps)| {
            let model = StoredModel::load(&out.join("models/pdennn"))?;
            let mut fcfg = cfg.follow.clone();
            if cfg.report_steps {
                fcfg.follow.steps = Some(*steps);
            }
            fcfg.follow.seed = cfg.seed;
            let contour = builtin_shape(*shape);
            let run = out.join("follow").join(shape.name());
            let named = (shape.name(), &contour);
            let res = follow_simulated(&fcfg, &model, named, (&run, true), &mut |_| {})?;
            let traj: Vec<(f64, f64)> = res.records.iter().map(|r| (r.pose.x, r.pose.y)).collect();
            let figs = out.join("figures");
            figures::trajectory(
                &figs.join(format!("fig5_3_{}", shape.name())),
                shape.name(),
                &contour,
                &traj,
            )?;
            figures::error_curve(
                &figs.join(format!("fig5_4_{}", shape.name())),
                shape.name(),
                &res.l2_curve,
            )?;
            let metrics = res.metrics.expect("scored against the known contour");
            Ok(ShapeRow {
                shape: shape.name().into(),
                metrics,
                ending: res.summary.ending,
                report_l2_mm: *report_l2,
            })
        })
        .collect();
    let shapes = shapes.into_iter().collect::<Result<Vec<_>>>()?;
    let (real_networks, sim_to_real) = match &cfg.real {
        Some(real) => {
            log("importing real frames and training on them, and on their simulated twin");
            real_rows(cfg, real, out)?
        }
        None => (Vec::new(), Vec::new()),
    };
    let results = ReproduceResults {
        networks,
        real_networks,
        sim_to_real,
        shapes,
        seconds: t0.elapsed().as_secs_f64(),
        seed: cfg.seed,
        tactrace_version: crate::VERSION.into(),
    };
    tactrace_report::document::write_report(out, &results)?;
    Ok(results)
}

/// Train every network on real frames (seeded 80/20 split) and validate on
/// the 20 %; then train the PDenNN and the MLP on the simulated twin of the
/// real set (its own 80 %) and validate them on the same real 20 %.
fn real_rows(cfg: &ReproduceConfig, dir: &Path, out: &Path) -> Result<(Vec<NetRow>, Vec<NetRow>)> {
    let icfg = crate::import::ImportConfig::bristol(dir);
    let blob = tactrace_vision::BlobParams::preset("real256")?;
    fig_4_1_real(dir, &blob, &out.join("figures/fig4_1_real"))?;
    let imported = crate::import::import(&icfg, &blob, &|| {})?;
    let (tr, va) = imported.data.split(0.8, cfg.seed);
    let real = train_rows(cfg, &NETS, "real", &tr, &va, &out.join("real"))?;
    let twin_cfg = crate::twin::TwinConfig::bristol(dir, cfg.seed);
    let twin = crate::twin::simulate_twin(&twin_cfg, &cfg.follow.rig.sensor, &blob, &|| {})?;
    let twin_tr = rows_not_in(&twin.data, &va);
    let nets = [NETS[2], NETS[3]];
    let mut transfer = train_rows(cfg, &nets, "twin", &twin_tr, &va, &out.join("twin"))?;
    transfer.push(calibrated_row(cfg, dir, (&tr, &va), &twin_cfg, out)?);
    Ok((real, transfer))
}

/// The PDenNN trained on the twin of a sensor calibrated with 100 taps of
/// the real training part (`tactrace calibrate`, `twin --sensor`),
/// validated on the same held-out real frames. The sensor folder is kept
/// under `sensor/`.
fn calibrated_row(
    cfg: &ReproduceConfig,
    dir: &Path,
    (tr, va): (&TapData, &TapData),
    twin_cfg: &crate::twin::TwinConfig,
    out: &Path,
) -> Result<NetRow> {
    let training: std::collections::HashSet<&str> =
        tr.meta.images.iter().map(String::as_str).collect();
    let rows = crate::twin::twin_rows(twin_cfg)?;
    let allowed = (0..rows.len())
        .filter(|&i| training.contains(rows[i].image.as_str()))
        .collect();
    let ccfg = crate::calibrate::CalibrateConfig {
        frames: dir.join("frames"),
        twin: twin_cfg.clone(),
        samples: Some(100),
        seed: cfg.seed,
        allowed_rows: Some(allowed),
    };
    let blob = tactrace_vision::BlobParams::preset("real256")?;
    let got = crate::calibrate::calibrate_sensor(&ccfg, &cfg.follow.rig.sensor, &blob, &|| {})?;
    crate::calibrate::write_calibrated(&got, &out.join("sensor"), true)?;
    let twin = crate::twin::simulate_twin_calibrated(twin_cfg, &got.sensor, true, &|| {})?;
    let twin_tr = rows_not_in(&twin.data, va);
    let name = "PDenNN (calibrated sensor, 100 taps)";
    let (row, _) = train_and_score(
        ModelKind::PDenNN,
        name,
        cfg,
        &twin_tr,
        va,
        &out.join("calibrated"),
    )?;
    Ok(row)
}

/// The rows of `data` whose image is not among `held_out`'s: the twin's
/// training part, joined with the real split on the image name (import and
/// twin may each drop frames, so row indices need not correspond).
fn rows_not_in(data: &TapData, held_out: &TapData) -> TapData {
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

/// Fig. 4.1 on a real frame of the Bristol set in `dir`.
fn fig_4_1_real(dir: &Path, blob: &tactrace_vision::BlobParams, stem: &Path) -> Result<()> {
    let reference = tactrace_sensor::read_frame(&dir.join("frames/init_0.png"))?;
    let frame = tactrace_sensor::read_frame(&dir.join("frames/frame_0_0.png"))?;
    let extractor = PinExtractor::from_reference_frame(&reference, blob.clone())?;
    figures::frame_pins_displacements(stem, &frame, &extractor, 3.0)?;
    Ok(())
}
