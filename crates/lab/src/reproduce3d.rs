//! `reproduce --3d`: the surface_3d section of the report. Collect taps
//! on the flat floor (training and validation from separate seeds),
//! train a PDenNN on the targets z, rx, ry, validate it, and follow the
//! saddle, the bowl and the wave with it (run folders under `follow-3d/`).
use crate::collect3d::{collect_3d, Collect3dConfig};
use crate::error::Result;
use crate::follow::task3d::{run_surface, PathConfig, Surface3dConfig};
use crate::follow::Run3dSettings;
use crate::reproduce::ReproduceConfig;
use crate::train::{resolve_config, save_model, train, validate_net};
use std::path::Path;
use tactrace_learn::ModelKind;
use tactrace_report::document3d::{Surface3dSection, SurfaceRow};
use tactrace_shape3d::ObjectConfig;
use tactrace_store::{write_dataset, StoredModel, TrainingRecord};

/// Taps the surface model is trained on, and validated on.
const SAMPLES: (usize, usize) = (2000, 500);

/// The objects followed.
pub const SURFACES: [&str; 3] = ["saddle", "bowl", "wave"];

/// Run the section into `out` (data/surface3d_*, models/surface3d,
/// follow-3d/OBJECT).
pub fn surface_section(
    cfg: &ReproduceConfig,
    out: &Path,
    log: &(dyn Fn(&str) + Sync),
) -> Result<Surface3dSection> {
    log("3D: collecting surface_3d taps on a flat floor and training a PDenNN on z, rx, ry");
    let rig = &cfg.follow.rig;
    let floor = ObjectConfig::named("plane").expect("built in").build()?;
    let draw = |samples, seed| Collect3dConfig {
        samples,
        seed,
        ..Collect3dConfig::default()
    };
    let tr = collect_3d(
        rig,
        &floor,
        &draw(SAMPLES.0, cfg.seed + 3000),
        "plane",
        |_| {},
    )?
    .data;
    let va = collect_3d(
        rig,
        &floor,
        &draw(SAMPLES.1, cfg.seed + 4000),
        "plane",
        |_| {},
    )?
    .data;
    write_dataset(&out.join("data/surface3d_train"), &tr, &[], true)?;
    write_dataset(&out.join("data/surface3d_val"), &va, &[], true)?;
    let mcfg = resolve_config(ModelKind::PDenNN, cfg.preset, None, cfg.epochs)?;
    let (net, history) = train(&mcfg, &tr, &mut |_| {})?;
    let model = StoredModel::new(net.clone(), tr.meta.reference_pins.clone())
        .with_training(TrainingRecord::all_rows(&tr, None));
    save_model(&out.join("models/surface3d"), &model, &history, true, &[])?;
    let v = validate_net(&net, &va)?;
    let validation_mae = v
        .per_target
        .iter()
        .map(|(name, s)| (name.clone(), s.mae, s.unit.as_str().to_string()))
        .collect();
    log("3D: following the saddle, the bowl and the wave");
    let mut rows = Vec::new();
    for name in SURFACES {
        let object = ObjectConfig::named(name).expect("built in").build()?;
        let run_cfg = Surface3dConfig {
            run: Run3dSettings {
                rig: rig.clone(),
                seed: cfg.seed,
                ..Run3dSettings::default()
            },
            path: PathConfig::for_object(name),
            ..Surface3dConfig::default()
        };
        let dir = out.join("follow-3d").join(name);
        let res = run_surface(&run_cfg, &object, name, &model, (&dir, true), &mut |_| {})?;
        let m = res.metrics;
        rows.push(SurfaceRow {
            object: name.into(),
            mean_distance_mm: m.mean_distance_mm,
            max_distance_mm: m.max_distance_mm,
            mean_normal_error_deg: m.mean_normal_error_deg,
            max_normal_error_deg: m.max_normal_error_deg,
            coverage: m.coverage,
            steps: m.steps,
            ending: res.summary.ending,
        });
    }
    Ok(Surface3dSection {
        model: "PDenNN".into(),
        train_samples: SAMPLES.0,
        val_samples: SAMPLES.1,
        validation_mae,
        rows,
    })
}
