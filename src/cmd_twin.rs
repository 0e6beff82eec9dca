//! `twin`: a simulated twin of a real labelled data set (the simulator
//! judged against real frames, docs/results.md "Simulated to real"), and
//! `calibrate`: the simulator fitted to a user's own taps
//! (docs/calibration.md).
use crate::cmd_data::{blob_params, rig_config, LabelArgs};
use crate::progress::bar;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use tactrace_lab::calibrate::{calibrate_sensor, write_calibrated, CalibrateConfig};
use tactrace_lab::import::Imported;
use tactrace_lab::twin::{simulate_twin, simulate_twin_calibrated, TwinConfig};
use tactrace_lab::LabError;
use tactrace_store::{dataset, fsutil, SensorFolder};

/// The columns of a tap's depth and shear (`twin`, `calibrate`).
#[derive(Args)]
pub struct TapColumnArgs {
    /// Vertical offset of each tap, mm; `none`: all taps at the nominal depth.
    #[arg(long, default_value = "pose_3")]
    dz_column: String,
    /// Shear columns x,y (mm) and rotation (deg), comma-separated; `none`:
    /// taps without shear.
    #[arg(long, default_value = "move_1,move_2,move_6")]
    shear_columns: String,
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

/// `none` (any case) or empty means no column.
fn optional(name: &str) -> Option<String> {
    let name = name.trim();
    (!name.is_empty() && !name.eq_ignore_ascii_case("none")).then(|| name.to_string())
}

/// The twin configuration of labels, columns, row limit and seed.
fn twin_config(
    labels: LabelArgs,
    columns: &TapColumnArgs,
    limit: Option<usize>,
    seed: u64,
) -> Result<TwinConfig> {
    let shear_columns = match optional(&columns.shear_columns) {
        None => None,
        Some(list) => {
            let cols: Vec<String> = list.split(',').map(|c| c.trim().to_string()).collect();
            let n = cols.len();
            Some(<[String; 3]>::try_from(cols).map_err(|_| {
                LabError::Config(format!(
                    "--shear-columns wants three columns (x, y, rotation) or `none`, got {n}"
                ))
            })?)
        }
    };
    Ok(TwinConfig {
        targets: labels.targets,
        reference: labels.reference,
        image_column: labels.image_column,
        r_column: labels.r_column,
        theta_column: labels.theta_column,
        dz_column: optional(&columns.dz_column),
        shear_columns,
        limit,
        seed,
    })
}

pub fn twin(a: TwinArgs) -> Result<()> {
    let cfg = twin_config(a.labels, &a.columns, a.limit, a.seed)?;
    fsutil::check_output_dir(&a.out, a.force)?;
    let pb = bar(0, "twin");
    let tick = || pb.inc(1);
    let got = match &a.sensor {
        Some(dir) => {
            let sensor = SensorFolder::read(dir)?;
            simulate_twin_calibrated(&cfg, &sensor, !a.no_real_taps, &tick)
        }
        None => {
            let rig = rig_config(a.config.as_deref())?;
            let blob = blob_params(a.params.as_deref(), "real256")?;
            simulate_twin(&cfg, &rig.sensor, &blob, &tick)
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
    for (name, why) in got.rejected.iter().take(10) {
        eprintln!("  rejected {name}: {why}");
    }
}

#[derive(Args)]
pub struct CalibrateArgs {
    /// Folder of the real frames named in --targets.
    #[arg(long)]
    frames: PathBuf,
    #[command(flatten)]
    labels: LabelArgs,
    #[command(flatten)]
    columns: TapColumnArgs,
    /// Calibration taps to pick (by a seeded rule that spans r and theta,
    /// docs/calibration.md); the other given taps score the fit. 0: use
    /// every tap (nothing held out).
    #[arg(long, default_value_t = 100)]
    samples: usize,
    /// Seed of the tap selection and of the replayed taps' rendering noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Rig configuration TOML whose `sensor` table is the simulator to
    /// calibrate (default: the built-in model).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Blob detector parameters (TOML); default: the real256 preset.
    #[arg(long)]
    params: Option<PathBuf>,
    /// Use only the first N rows of --targets.
    #[arg(long)]
    limit: Option<usize>,
    /// Also fit the simulator's label convention (angle and edge offsets
    /// and scales, tap depth) and mechanics to the calibration taps before
    /// the field correction: for a sensor unlike the shared one (a few
    /// seconds more).
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
    let twin = twin_config(a.labels, &a.columns, a.limit, a.seed)?;
    let cfg = CalibrateConfig {
        frames: a.frames,
        twin,
        samples: (a.samples > 0).then_some(a.samples),
        seed: a.seed,
        allowed_rows: None,
        score_rows: None,
        fit_physics: a.fit_physics,
    };
    let rig = rig_config(a.config.as_deref())?;
    let blob = blob_params(a.params.as_deref(), "real256")?;
    fsutil::check_output_dir(&a.out, a.force)?;
    let t0 = std::time::Instant::now();
    let pb = bar(0, "calibrate");
    let tick = || pb.inc(1);
    let got = calibrate_sensor(&cfg, &rig.sensor, &blob, &tick);
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
    Ok(())
}
