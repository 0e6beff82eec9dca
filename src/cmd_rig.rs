//! Real-rig set-up commands: `rig check` (is everything ready before
//! anything moves?).
use crate::say;
use anyhow::{bail, Result};
use clap::{Args, Subcommand};
use std::path::PathBuf;
use tactrace_lab::hardware::{rig_check, HardwareConfig, RigCheck};
use tactrace_store::{fsutil, StoredModel};

#[derive(Subcommand)]
pub enum RigCommand {
    /// Say whether the arm, its safety state, the camera and the sensor
    /// reference are ready; nothing moves. Exit 0 ready, 1 not ready, 2 bad rig file.
    Check(CheckArgs),
}

#[derive(Args)]
pub struct CheckArgs {
    /// The rig file (docs/hardware.md).
    rig: PathBuf,
    /// A model directory: the reference frame's pins must be the model's,
    /// in its order.
    #[arg(long)]
    model: Option<PathBuf>,
}

pub fn rig(command: RigCommand) -> Result<()> {
    match command {
        RigCommand::Check(a) => check(a),
    }
}

fn check(a: CheckArgs) -> Result<()> {
    let text = fsutil::read_text(&a.rig)?;
    let cfg = HardwareConfig::from_toml(&text, &a.rig.display().to_string())?;
    let model = a.model.as_deref().map(StoredModel::load).transpose()?;
    let report = rig_check(&cfg, model.as_ref())?;
    print_check(&a.rig.display().to_string(), &report)?;
    if !report.ready() {
        let failed = report.items.iter().filter(|i| !i.ready).count();
        bail!(
            "the rig is not ready ({failed} of {} checks failed)",
            report.items.len()
        );
    }
    Ok(())
}

fn print_check(rig: &str, report: &RigCheck) -> Result<()> {
    say!("rig check of {rig} (nothing is moved)");
    for item in &report.items {
        let status = if item.ready { "ready" } else { "NOT READY" };
        say!("  {:<10} {:<10} {}", item.name, status, item.detail);
    }
    for note in &report.notes {
        say!("  note: {note}");
    }
    if report.ready() {
        say!("all ready");
    }
    Ok(())
}
