//! `twin`: a simulated twin of a real labelled data set (the simulator
//! judged against real frames, docs/results.md "Simulated to real").
use crate::cmd_data::{blob_params, rig_config, LabelArgs};
use crate::progress::bar;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use tactrace_lab::twin::{simulate_twin, TwinConfig};
use tactrace_lab::LabError;
use tactrace_store::{dataset, fsutil};

#[derive(Args)]
pub struct TwinArgs {
    #[command(flatten)]
    labels: LabelArgs,
    /// Vertical offset of each tap, mm; `none`: all taps at the nominal depth.
    #[arg(long, default_value = "pose_3")]
    dz_column: String,
    /// Shear columns x,y (mm) and rotation (deg), comma-separated; `none`:
    /// taps without shear.
    #[arg(long, default_value = "move_1,move_2,move_6")]
    shear_columns: String,
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

pub fn twin(a: TwinArgs) -> Result<()> {
    let shear_columns = match optional(&a.shear_columns) {
        None => None,
        Some(list) => {
            let cols: Vec<String> = list.split(',').map(|c| c.trim().to_string()).collect();
            match <[String; 3]>::try_from(cols) {
                Ok(cols) => Some(cols),
                Err(cols) => {
                    let why = format!(
                        "--shear-columns wants three columns (x, y, rotation) or `none`, got {}",
                        cols.len()
                    );
                    return Err(LabError::Config(why).into());
                }
            }
        }
    };
    let cfg = TwinConfig {
        targets: a.labels.targets,
        reference: a.labels.reference,
        image_column: a.labels.image_column,
        r_column: a.labels.r_column,
        theta_column: a.labels.theta_column,
        dz_column: optional(&a.dz_column),
        shear_columns,
        limit: a.limit,
        seed: a.seed,
    };
    let rig = rig_config(a.config.as_deref())?;
    let blob = blob_params(a.params.as_deref(), "real256")?;
    fsutil::check_output_dir(&a.out, a.force)?;
    let pb = bar(0, "twin");
    let tick = || pb.inc(1);
    let got = simulate_twin(&cfg, &rig.sensor, &blob, &tick)?;
    pb.finish_and_clear();
    let dir = dataset::write_dataset(&a.out, &got.data, &[], a.force)?;
    let n = got.data.len();
    eprintln!(
        "simulated {n} labelled taps into {}: all pins matched on {}, {} with missing pins, {} rejected (too few pins)",
        dir.display(),
        n - got.frames_with_missing_pins,
        got.frames_with_missing_pins,
        got.rejected.len()
    );
    for (name, why) in got.rejected.iter().take(10) {
        eprintln!("  rejected {name}: {why}");
    }
    Ok(())
}
