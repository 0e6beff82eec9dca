//! Renders one figure twice, to SVG text and to a PNG, and writes both.
//!
//! plotters backends are different types, so a figure is a [`Figure`]
//! value drawn by a generic method; this file owns the backends, the file
//! names (`<stem>.svg`, `<stem>.png`) and the mapping of every failure to a
//! [`PlotError`] that names the file.

use super::font::ensure_font;
use super::raster::{embed_rasters, Raster};
use super::PlotError;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, GrayImage, ImageEncoder};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// Smallest and largest accepted figure side, in pixels.
const SIDE_LIMITS: (u32, u32) = (64, 8192);

/// A picture that can draw itself on any plotters backend.
pub(crate) trait Figure {
    /// Draws the whole figure on `root` (already filled white); frames are
    /// drawn as pixels or as SVG placeholders according to `raster`.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        raster: Raster,
    ) -> Result<(), String>;

    /// The camera frame that SVG placeholders stand for, if any.
    fn frame(&self) -> Option<&GrayImage> {
        None
    }
}

/// Converts any plotters error into the message stored in [`PlotError::Draw`].
pub(crate) fn draw_err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// `<stem>.<ext>`, keeping any dots already in the stem.
pub(crate) fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut name = OsString::from(stem.as_os_str());
    name.push(".");
    name.push(ext);
    PathBuf::from(name)
}

/// Rejects figure sizes outside [`SIDE_LIMITS`].
pub(crate) fn check_size(stem: &Path, size: (u32, u32)) -> Result<(), PlotError> {
    let ok = |side: u32| (SIDE_LIMITS.0..=SIDE_LIMITS.1).contains(&side);
    if ok(size.0) && ok(size.1) {
        return Ok(());
    }
    Err(PlotError::InvalidSize {
        path: stem.to_path_buf(),
        width: size.0,
        height: size.1,
    })
}

/// Writes `figure` as `<stem>.svg` and `<stem>.png`; returns both paths.
pub(crate) fn write_both<F: Figure>(
    stem: &Path,
    size: (u32, u32),
    figure: &F,
) -> Result<Vec<PathBuf>, PlotError> {
    check_size(stem, size)?;
    if !ensure_font() {
        return Err(PlotError::Font {
            path: stem.to_path_buf(),
        });
    }
    let svg_path = with_suffix(stem, "svg");
    let svg = render_svg(&svg_path, size, figure)?;
    write_file(&svg_path, svg.as_bytes())?;
    let png_path = with_suffix(stem, "png");
    let png = render_png(&png_path, size, figure)?;
    write_file(&png_path, &png)?;
    Ok(vec![svg_path, png_path])
}

fn render_svg<F: Figure>(path: &Path, size: (u32, u32), figure: &F) -> Result<String, PlotError> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw_root(&root, figure, Raster::Placeholder).map_err(|message| PlotError::Draw {
            path: path.to_path_buf(),
            message,
        })?;
    }
    match figure.frame() {
        Some(frame) => embed_rasters(&text, frame).map_err(|source| PlotError::Encode {
            path: path.to_path_buf(),
            source,
        }),
        None => Ok(text),
    }
}

fn render_png<F: Figure>(path: &Path, size: (u32, u32), figure: &F) -> Result<Vec<u8>, PlotError> {
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_root(&root, figure, Raster::Blit).map_err(|message| PlotError::Draw {
            path: path.to_path_buf(),
            message,
        })?;
    }
    let mut png = Vec::new();
    PngEncoder::new(&mut png)
        .write_image(&rgb, size.0, size.1, ExtendedColorType::Rgb8)
        .map_err(|source| PlotError::Encode {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(png)
}

fn draw_root<DB: DrawingBackend, F: Figure>(
    root: &DrawingArea<DB, Shift>,
    figure: &F,
    raster: Raster,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(draw_err)?;
    figure.draw(root, raster)?;
    root.present().map_err(draw_err)
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), PlotError> {
    std::fs::write(path, bytes).map_err(|source| PlotError::Write {
        path: path.to_path_buf(),
        source,
    })
}
