//! `tactrace ensemble`: pin models trained apart on the same rows joined
//! into one model folder whose prediction averages theirs
//! (`tactrace_lab::join_models`; docs/learning.md, "Joining models trained
//! apart").
use crate::inputs::Inputs;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use tactrace_lab::join_models::{join_models, save_joined};
use tactrace_store::check_output_dir;

#[derive(Args)]
pub struct EnsembleArgs {
    /// A pin model folder to join (repeat it): models trained on the same rows, with nets of the same shape and rates (other seeds, or one run's snapshots continued by `train --init`)
    #[arg(long = "member", required = true)]
    members: Vec<PathBuf>,
    /// Output model directory: an ensemble of the members, their predictions averaged (a circular target's sine and cosine before its atan2)
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing model directory.
    #[arg(long)]
    force: bool,
}

pub fn ensemble(a: EnsembleArgs) -> Result<()> {
    Inputs::new()
        .all("--member", &a.members)
        .check_apart("--out", &a.out)?;
    let _out = check_output_dir(&a.out, a.force)?;
    let (model, record) = join_models(&a.members)?;
    let dir = save_joined(&a.out, &model, &record, a.force)?;
    eprintln!(
        "joined {} models into one ensemble; saved model to {}",
        a.members.len(),
        dir.display()
    );
    Ok(())
}
