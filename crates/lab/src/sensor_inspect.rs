//! `tactrace sensor inspect`: an unknown TacTip's frames in, its sensor
//! settings out ([`SightFile`]: the preprocessing, the detector, the pin
//! count and layout kind) with a picture of what was found. The frames are
//! read here; the proposal is [`tactrace_vision::inspect`]'s.
use crate::error::{LabError, Result};
use image::RgbImage;
use std::path::{Path, PathBuf};
use tactrace_sensor::read_image;
use tactrace_store::{SensorSummary, SightFile};
use tactrace_vision::preprocess::grey_of;
use tactrace_vision::{draw_inspection, inspect, Frame, Inspection, PreprocessParams};

/// Frames inspected at most (spread evenly over those given).
pub const INSPECT_FRAMES: usize = 20;

/// What an inspection gives: the sensor file, the full inspection and
/// its picture.
pub struct Inspected {
    /// The settings to write.
    pub file: SightFile,
    /// Everything inspection found.
    pub inspection: Inspection,
    /// What it found drawn over one frame.
    pub picture: RgbImage,
    /// The frames inspected.
    pub frames: Vec<PathBuf>,
}

/// The image files named by `inputs` (files as given; folders: their PNG,
/// JPEG and BMP files, sorted by name), in order.
pub fn frame_files(inputs: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for input in inputs {
        if !input.is_dir() {
            out.push(input.clone());
            continue;
        }
        let entries = std::fs::read_dir(input).map_err(tactrace_store::read_err(input.clone()))?;
        let mut files: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && is_image_name(p))
            .collect();
        files.sort();
        if files.is_empty() {
            return Err(LabError::Format {
                path: input.clone(),
                reason: "no image files (.png, .jpg, .bmp) in this folder".into(),
            });
        }
        out.extend(files);
    }
    Ok(out)
}

fn is_image_name(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["png", "jpg", "jpeg", "bmp"].contains(&e.to_ascii_lowercase().as_str()))
}

/// Every `len / k`-th item, at most `k`.
fn spread<T: Clone>(items: &[T], k: usize) -> Vec<T> {
    let step = items.len().div_ceil(k.max(1)).max(1);
    items.iter().step_by(step).cloned().collect()
}

/// Inspects up to [`INSPECT_FRAMES`] of `files` (spread evenly; all the
/// same size, grey or colour), cropped to `crop` first when given.
pub fn inspect_frames(files: &[PathBuf], crop: Option<[u32; 4]>) -> Result<Inspected> {
    let chosen = spread(files, INSPECT_FRAMES);
    let mut frames: Vec<Frame> = Vec::with_capacity(chosen.len());
    let mut size = None;
    for path in &chosen {
        let image = read_image(path)?;
        let this = [image.width(), image.height()];
        if *size.get_or_insert(this) != this {
            let [w, h] = size.unwrap_or(this);
            return Err(LabError::Format {
                path: path.clone(),
                reason: format!(
                    "{} x {} px, unlike the first frame's {w} x {h}: inspect frames of one camera",
                    this[0], this[1]
                ),
            });
        }
        frames.push(grey_of(&image));
    }
    let [w, h] = size.ok_or_else(|| LabError::Config("no frames to inspect".into()))?;
    let what = chosen[0].parent().unwrap_or(Path::new(".")).to_path_buf();
    let found = inspect(&frames, crop).map_err(|e| LabError::Format {
        path: what,
        reason: format!("inspection found no pins to propose settings from: {e}"),
    })?;
    let shown = &frames[found.picture.frame.min(frames.len() - 1)];
    let cropped = PreprocessParams {
        crop,
        ..PreprocessParams::default()
    }
    .check()?
    .stage(w, h)?
    .apply_grey(shown)?;
    let picture = draw_inspection(&cropped, &found);
    let file = SightFile {
        sensor: SensorSummary {
            pins: found.pins,
            layout: found.layout.kind,
            spacing_px: round3(found.spacing),
            pin_pixels: round3(found.pin_pixels),
            frame_size: [w, h],
        },
        preprocess: found.preprocess.clone(),
        detect: found.detect.clone(),
    };
    Ok(Inspected {
        file,
        inspection: found,
        picture,
        frames: chosen,
    })
}

fn round3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}
