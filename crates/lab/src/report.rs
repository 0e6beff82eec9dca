//! `tactrace reproduce`: the whole report, end to end, in one directory.
//!
//! Collect on the disk (train and validation runs), train the three
//! networks and the backprop twin, validate them, follow the four shapes
//! with the PDenNN, and write report.md, report.html and metrics.json with
//! the report's numbers side by side.
use crate::collect::{collect, CollectConfig};
use crate::dataset::TapData;
use crate::error::{io_err, Result};
use crate::follow::{run_follow, FollowRunConfig};
use crate::train::{resolve_config, train, validate, Validation};
use crate::{figures, fsutil, model_io};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_geometry::{builtin_shape, BuiltinShape};
use tactrace_learn::{ModelKind, Preset};

/// The report's Table 4.1 errors (angle deg, position mm) and contour L2 (mm).
pub const REPORT_TABLE_4_1: [(&str, Option<f64>, Option<f64>); 3] = [
    ("DisDenNN", Some(6.55), Some(1.34)),
    ("PCADenNN", Some(5.89), Some(0.53)),
    ("PDenNN", Some(5.36), Some(0.38)),
];
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
    pub follow: FollowRunConfig,
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
            follow: FollowRunConfig::simulated(),
            real: None,
        }
    }
}

/// One row of the networks table.
#[derive(Debug, Clone, Serialize)]
pub struct NetRow {
    pub name: String,
    pub data: String,
    pub position_mae_mm: f64,
    pub angle_mae_deg: f64,
    pub train_seconds: f64,
}

/// One row of the contour table.
#[derive(Debug, Clone, Serialize)]
pub struct ShapeRow {
    pub shape: String,
    pub metrics: crate::metrics::FollowMetrics,
    pub ending: crate::servo::Ending,
    pub report_l2_mm: f64,
}

/// Everything `reproduce` measured.
#[derive(Debug, Clone, Serialize)]
pub struct ReproduceResults {
    pub networks: Vec<NetRow>,
    pub shapes: Vec<ShapeRow>,
    pub seconds: f64,
    pub seed: u64,
    pub tactrace_version: String,
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
    std::fs::create_dir_all(dir.join("figures")).map_err(io_err(dir))?;
    let mcfg = resolve_config(kind, cfg.preset, None, cfg.epochs)?;
    let t0 = std::time::Instant::now();
    let (model, history) = train(&mcfg, tr, &mut |_| {})?;
    let secs = t0.elapsed().as_secs_f64();
    let mdir = dir
        .join("models")
        .join(name.split(' ').next().unwrap_or(name).to_lowercase());
    model_io::save_model(&mdir, &model, &history, true)?;
    let v = validate(&model, va)?;
    figures::predicted_vs_true(
        &dir.join("figures").join(format!("fig4_4_{}", slug(name))),
        name,
        &v,
    )?;
    let row = NetRow {
        name: name.into(),
        data: tr.meta.source.clone(),
        position_mae_mm: v.position_mae_mm,
        angle_mae_deg: v.angle_mae_deg,
        train_seconds: secs,
    };
    Ok((row, v))
}

fn slug(s: &str) -> String {
    s.chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .collect::<String>()
        .to_lowercase()
}

/// Run everything into `out` (created; existing files are replaced).
pub fn reproduce(
    cfg: &ReproduceConfig,
    out: &Path,
    log: &(dyn Fn(&str) + Sync),
) -> Result<ReproduceResults> {
    let t0 = std::time::Instant::now();
    std::fs::create_dir_all(out.join("figures")).map_err(io_err(out))?;
    fsutil::write_atomic(
        &out.join("config.toml"),
        toml::to_string(cfg)
            .map_err(|e| crate::LabError::Config(e.to_string()))?
            .as_bytes(),
    )?;
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
    crate::dataset::write_dataset(&out.join("data/train"), &tr, &[], true)?;
    crate::dataset::write_dataset(&out.join("data/val"), &va, &[], true)?;
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
            let model = model_io::load_model(&out.join("models/pdennn"))?;
            let mut fcfg = cfg.follow.clone();
            if cfg.report_steps {
                fcfg.follow.steps = Some(*steps);
            }
            fcfg.follow.seed = cfg.seed;
            let contour = builtin_shape(*shape);
            let run = out.join("follow").join(shape.name());
            let res = run_follow(&fcfg, model, &contour, &run, &mut |_| {})?;
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
            Ok(ShapeRow {
                shape: shape.name().into(),
                metrics: res.metrics,
                ending: res.summary.ending,
                report_l2_mm: *report_l2,
            })
        })
        .collect();
    let shapes = shapes.into_iter().collect::<Result<Vec<_>>>()?;
    if let Some(real) = &cfg.real {
        log("importing real frames and training on them");
        networks.extend(real_rows(cfg, real, out)?);
    }
    let results = ReproduceResults {
        networks,
        shapes,
        seconds: t0.elapsed().as_secs_f64(),
        seed: cfg.seed,
        tactrace_version: crate::VERSION.into(),
    };
    write_report(out, &results)?;
    Ok(results)
}

/// Train the PDenNN and its backprop twin on real frames (80/20 split).
fn real_rows(cfg: &ReproduceConfig, dir: &Path, out: &Path) -> Result<Vec<NetRow>> {
    let icfg = crate::import::ImportConfig {
        frames: dir.join("frames"),
        targets: dir.join("targets.csv"),
        reference: dir.join("frames/init_0.png"),
        image_column: "image_name".into(),
        r_column: "pose_2".into(),
        theta_column: "pose_6".into(),
        limit: None,
    };
    let blob = tactrace_vision::BlobParams::preset("real256")?;
    let imported = crate::import::import(&icfg, &blob, &|| {})?;
    let (tr, va) = imported.data.split(0.8, cfg.seed);
    let rows: Vec<Result<NetRow>> = [
        (ModelKind::PDenNN, "PDenNN"),
        (ModelKind::Mlp, "MLP (backprop)"),
    ]
    .par_iter()
    .map(|(k, name)| {
        let (mut row, _) = train_and_score(
            *k,
            &format!("{name} real"),
            cfg,
            &tr,
            &va,
            &out.join("real"),
        )?;
        row.name = name.to_string();
        Ok(row)
    })
    .collect();
    rows.into_iter().collect()
}

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.2}")).unwrap_or_else(|| "-".into())
}

/// report.md, report.html and metrics.json.
fn write_report(out: &Path, r: &ReproduceResults) -> Result<()> {
    let mut md = String::from(
        "# tactrace reproduction of \"A Bio-Inspired System for Human-Like Contour Following\"\n\n",
    );
    md.push_str(&format!("tactrace {}, seed {}, {:.1} s in all. Simulated rig; the report used a real UR5 and TacTip.\n\n", r.tactrace_version, r.seed, r.seconds));
    md.push_str("## Table 4.1: validation errors\n\n| network | data | angle MAE (deg) | position MAE (mm) | report angle (deg) | report position (mm) | train time (s) |\n|---|---|---|---|---|---|---|\n");
    for n in &r.networks {
        let rep = REPORT_TABLE_4_1.iter().find(|(name, _, _)| *name == n.name);
        md.push_str(&format!(
            "| {} | {} | {:.2} | {:.3} | {} | {} | {:.1} |\n",
            n.name,
            n.data,
            n.angle_mae_deg,
            n.position_mae_mm,
            opt(rep.and_then(|x| x.1)),
            opt(rep.and_then(|x| x.2)),
            n.train_seconds
        ));
    }
    md.push_str("\n![Fig. 4.4 PDenNN](figures/fig4_4_pdennn.svg)\n\n![Fig. 4.5 PDenNN loss and energy](models/pdennn/loss_energy.svg)\n\n");
    md.push_str("## Contour following (Fig. 5.3, 5.4)\n\n| shape | mean L2 (mm) | report L2 (mm) | mean track error (mm) | p95 (mm) | max (mm) | coverage | closed | steps | ending |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for s in &r.shapes {
        let m = &s.metrics;
        md.push_str(&format!(
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0}% | {} | {} | {:?} |\n",
            s.shape,
            m.mean_l2_mm,
            s.report_l2_mm,
            m.mean_track_error_mm,
            m.p95_track_error_mm,
            m.max_track_error_mm,
            100.0 * m.coverage,
            m.closed,
            m.steps,
            s.ending
        ));
    }
    md.push('\n');
    for s in &r.shapes {
        md.push_str(&format!(
            "![Fig. 5.3 {0}](figures/fig5_3_{0}.svg) ![Fig. 5.4 {0}](figures/fig5_4_{0}.svg)\n\n",
            s.shape
        ));
    }
    fsutil::write_atomic(&out.join("report.md"), md.as_bytes())?;
    fsutil::write_atomic(
        &out.join("report.html"),
        crate::html::markdown_to_html(&md).as_bytes(),
    )?;
    let json = serde_json::to_string_pretty(r).expect("results serialise");
    fsutil::write_atomic(&out.join("metrics.json"), json.as_bytes())
}
