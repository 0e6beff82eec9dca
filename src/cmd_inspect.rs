//! `tactrace sensor inspect FRAMES... --out SENSOR.toml [--picture PNG]`:
//! an unknown TacTip's frames in, its sensor settings file out; `tactrace
//! sensor preprocess FRAME --sensor SENSOR.toml --out PNG`: one frame as
//! the detector sees it.
use crate::inputs::Inputs;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;
use tactrace_lab::sensor_inspect::{frame_files, inspect_frames};
use tactrace_lab::LabError;
use tactrace_store::fsutil;
use tactrace_vision::{DetectorParams, LayoutKind};

#[derive(Args)]
pub struct InspectArgs {
    /// Frames of the sensor: image files, or folders of them (up to 20
    /// are used, spread evenly); taps or frames without contact alike.
    #[arg(required = true)]
    frames: Vec<PathBuf>,
    /// The sensor settings file to write (TOML).
    #[arg(long)]
    out: PathBuf,
    /// Also draw what was found (mask blue, rim yellow, pins green,
    /// clusters orange, left out red) into this PNG.
    #[arg(long)]
    picture: Option<PathBuf>,
    /// Crop the camera frames first: x0,y0,x1,y1 (px, end exclusive).
    #[arg(long, value_delimiter = ',', num_args = 4)]
    crop: Option<Vec<u32>>,
    /// Replace existing --out / --picture files.
    #[arg(long)]
    force: bool,
}

pub fn inspect(a: InspectArgs) -> Result<()> {
    let mut inputs = Inputs::new();
    for f in &a.frames {
        inputs = inputs.add("FRAMES", f);
    }
    inputs.check_outside("--out", &a.out)?;
    if let Some(p) = &a.picture {
        let mut inputs = Inputs::new();
        for f in &a.frames {
            inputs = inputs.add("FRAMES", f);
        }
        inputs.check_outside("--picture", p)?;
    }
    fsutil::check_output_file(&a.out, a.force, "--out")?;
    if let Some(p) = &a.picture {
        fsutil::check_output_file(p, a.force, "--picture")?;
    }
    let crop = match a.crop.as_deref() {
        None => None,
        Some(&[x0, y0, x1, y1]) => Some([x0, y0, x1, y1]),
        Some(_) => return Err(LabError::Config("--crop takes x0,y0,x1,y1".into()).into()),
    };
    let files = frame_files(&a.frames)?;
    let got = inspect_frames(&files, crop)?;
    let f = &got.file;
    let layout = match f.sensor.layout {
        LayoutKind::Hexagonal => "a hexagonal lattice".to_string(),
        LayoutKind::Rings => {
            let per_ring: Vec<String> = got
                .inspection
                .layout
                .rings
                .iter()
                .map(|n| n.to_string())
                .collect();
            format!(
                "concentric rings of {} pins (innermost first)",
                per_ring.join(", ")
            )
        }
    };
    let detector = match &f.detect {
        DetectorParams::Spots(_) => "the small-pin detector (spots)",
        DetectorParams::Blobs(_) => "the blob detector (blobs)",
    };
    eprintln!(
        "inspected {} frames ({} x {} px{}): {} pins on {layout}, spacing {:.2} px, pins of \
         {:.1} px; {detector}{}",
        got.frames.len(),
        f.sensor.frame_size[0],
        f.sensor.frame_size[1],
        if got.inspection.binary {
            ", binary"
        } else {
            ""
        },
        f.sensor.pins,
        f.sensor.spacing_px,
        f.sensor.pin_pixels,
        f.preprocess.mask.map_or(String::new(), |m| format!(
            ", dome mask r {:.1} px about ({:.1}, {:.1})",
            m.radius, m.centre[0], m.centre[1]
        )),
    );
    fsutil::write_output_file(&a.out, f.to_toml().as_bytes(), a.force, "--out")?;
    eprintln!("wrote {}", a.out.display());
    if let Some(p) = &a.picture {
        let img = image::DynamicImage::ImageRgb8(got.picture);
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| LabError::Config(format!("cannot encode the picture: {e}")))?;
        fsutil::write_output_file(p, &bytes, a.force, "--picture")?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

#[derive(Args)]
pub struct PreprocessArgs {
    /// The camera frame (grey or colour, the size the sensor file records).
    frame: PathBuf,
    /// The sensor file (`tactrace sensor inspect --out`).
    #[arg(long)]
    sensor: PathBuf,
    /// The preprocessed frame to write (PNG).
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing --out file.
    #[arg(long)]
    force: bool,
}

/// `sensor preprocess`: the frame through the sensor file's stage.
pub fn preprocess(a: PreprocessArgs) -> Result<()> {
    Inputs::new()
        .add("FRAME", &a.frame)
        .add("--sensor", &a.sensor)
        .check_outside("--out", &a.out)?;
    fsutil::check_output_file(&a.out, a.force, "--out")?;
    let sensor = tactrace_store::SightFile::read(&a.sensor)?;
    let image = tactrace_sensor::read_image(&a.frame).map_err(LabError::from)?;
    let [w, h] = sensor.sensor.frame_size;
    let stage = sensor
        .preprocess
        .check()
        .and_then(|p| p.stage(w, h))
        .map_err(LabError::from)?;
    let frame = stage.apply(&image).map_err(|e| LabError::Format {
        path: a.frame.clone(),
        reason: e.to_string(),
    })?;
    let png = tactrace_store::frame_file::png_bytes(&frame, "the preprocessed frame")?;
    fsutil::write_output_file(&a.out, &png, a.force, "--out")?;
    eprintln!(
        "wrote {} ({} x {} px)",
        a.out.display(),
        frame.width(),
        frame.height()
    );
    Ok(())
}
