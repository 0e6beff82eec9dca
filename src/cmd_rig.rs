//! Real-rig set-up commands: `rig check` (is everything ready before
//! anything moves?), `camera list` and `camera grab` (which camera, what
//! does it see?).
use crate::say;
use anyhow::{bail, Result};
use clap::{Args, Subcommand};
use std::path::PathBuf;
use tactrace_lab::hardware::{
    grab_camera_frame, list_cameras, rig_check, HardwareConfig, RigCheck,
};
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
    /// Without --model: the number of pins the sensor has (127 on the
    /// Bristol TacTip); the reference frame must show exactly that many.
    #[arg(long, conflicts_with = "model")]
    pins: Option<usize>,
}

pub fn rig(command: RigCommand) -> Result<()> {
    match command {
        RigCommand::Check(a) => check(a),
    }
}

fn check(a: CheckArgs) -> Result<()> {
    let cfg = HardwareConfig::read(&a.rig)?;
    let model = a.model.as_deref().map(StoredModel::load).transpose()?;
    let report = rig_check(&cfg, model.as_ref(), a.pins)?;
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

#[derive(Subcommand)]
pub enum CameraCommand {
    /// List the V4L2 video capture devices and the pixel formats they offer.
    List,
    /// Grab one raw grey frame from a V4L2 camera into a PNG (to place the crop).
    Grab(GrabArgs),
}

#[derive(Args)]
pub struct GrabArgs {
    /// The camera device, e.g. /dev/video0.
    #[arg(long)]
    device: String,
    /// The PNG to write.
    #[arg(long)]
    out: PathBuf,
    /// Take size, format, exposure and warm-up from this rig file's
    /// `[camera.v4l2]` table (the device is still --device).
    #[arg(long)]
    rig: Option<PathBuf>,
    /// Replace an existing --out.
    #[arg(long)]
    force: bool,
}

pub fn camera(command: CameraCommand) -> Result<()> {
    match command {
        CameraCommand::List => list(),
        CameraCommand::Grab(a) => grab(a),
    }
}

fn list() -> Result<()> {
    let cameras = list_cameras()?;
    if cameras.is_empty() {
        say!("no video capture device found (no /dev/video* that can capture)");
    }
    for c in cameras {
        say!("{}  {}  formats: {}", c.path, c.card, c.formats.join(", "));
    }
    Ok(())
}

fn grab(a: GrabArgs) -> Result<()> {
    crate::inputs::Inputs::new()
        .opt("--rig", a.rig.as_deref())
        .check_outside("--out", &a.out)?;
    fsutil::check_output_file(&a.out, a.force, "--out")?;
    let rig = match &a.rig {
        Some(path) => Some(HardwareConfig::read(path)?),
        None => None,
    };
    let frame = grab_camera_frame(&a.device, rig.as_ref())?;
    let mut png = Vec::new();
    frame.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)?;
    fsutil::write_output_file(&a.out, &png, a.force, "--out")?;
    say!(
        "{} x {} frame from {} written to {}",
        frame.width(),
        frame.height(),
        a.device,
        a.out.display()
    );
    Ok(())
}
