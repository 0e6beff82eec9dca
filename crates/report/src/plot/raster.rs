//! Camera frames inside figures, for both backends.
//!
//! The PNG backend blits the frame's pixels, resized to the plot. The SVG
//! backend would write one `<rect>` per pixel, so there a filled rectangle
//! of a sentinel colour marks the frame's place and is afterwards replaced
//! by an `<image>` element holding the frame as an embedded PNG; the frame
//! thus stays a true raster, at the position plotters chose.

use super::render::draw_err;
use base64::Engine as _;
use image::codecs::png::PngEncoder;
use image::imageops::{resize, FilterType};
use image::{ExtendedColorType, GrayImage, ImageEncoder, ImageError};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// Which backend draws: how a figure draws camera frames on it (and
/// whether thick lines go as one path or as segments, `series.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Raster {
    /// Copy the pixels (bitmap backend).
    Blit,
    /// Draw a sentinel rectangle to be replaced by [`embed_rasters`] (SVG).
    Placeholder,
}

/// A colour no figure uses otherwise; marks where frames go in the SVG.
const SENTINEL: RGBColor = RGBColor(1, 2, 3);
const SENTINEL_SVG: &str = "fill=\"#010203\"";

/// A chart in image coordinates: x right, y down, pixels.
pub(crate) type ImageChart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws `frame` so that pixel (0, 0) sits at chart point (0, 0) and pixel
/// (w, h) at chart point (w, h).
pub(crate) fn draw_frame<DB: DrawingBackend>(
    chart: &mut ImageChart<'_, DB>,
    frame: &GrayImage,
    raster: Raster,
) -> Result<(), String> {
    let far = (f64::from(frame.width()), f64::from(frame.height()));
    let top_left = chart.backend_coord(&(0.0, 0.0));
    let bottom_right = chart.backend_coord(&far);
    let (w, h) = (bottom_right.0 - top_left.0, bottom_right.1 - top_left.1);
    if w <= 0 || h <= 0 || frame.width() == 0 || frame.height() == 0 {
        return Ok(());
    }
    match raster {
        Raster::Placeholder => {
            let rect = Rectangle::new([(0.0, 0.0), far], SENTINEL.filled());
            chart.draw_series(std::iter::once(rect)).map_err(draw_err)?;
        }
        Raster::Blit => {
            let scaled = resize(frame, w as u32, h as u32, FilterType::Nearest);
            let rgb: Vec<u8> = scaled.pixels().flat_map(|p| [p.0[0]; 3]).collect();
            let element = BitMapElement::with_owned_buffer((0.0, 0.0), (w as u32, h as u32), rgb)
                .ok_or_else(|| "frame buffer too small".to_owned())?;
            chart
                .draw_series(std::iter::once(element))
                .map_err(draw_err)?;
        }
    }
    Ok(())
}

/// Replaces every sentinel rectangle in `svg` by `frame` as an embedded PNG.
pub(crate) fn embed_rasters(svg: &str, frame: &GrayImage) -> Result<String, ImageError> {
    let mut png = Vec::new();
    PngEncoder::new(&mut png).write_image(
        frame.as_raw(),
        frame.width(),
        frame.height(),
        ExtendedColorType::L8,
    )?;
    let href = format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&png)
    );
    let mut out = String::with_capacity(svg.len() + 2 * href.len());
    let mut rest = svg;
    while let Some((before, rect, after)) = split_sentinel(rest) {
        out.push_str(before);
        out.push_str(&image_element(rect, &href));
        rest = after;
    }
    out.push_str(rest);
    Ok(out)
}

/// Splits `svg` round its first sentinel `<rect .../>`.
fn split_sentinel(svg: &str) -> Option<(&str, &str, &str)> {
    let mark = svg.find(SENTINEL_SVG)?;
    let start = svg[..mark].rfind("<rect")?;
    let end = mark + svg[mark..].find("/>")? + 2;
    Some((&svg[..start], &svg[start..end], &svg[end..]))
}

/// An `<image>` element covering the same box as the rectangle `rect`.
fn image_element(rect: &str, href: &str) -> String {
    let attr = |name: &str| attribute(rect, name).unwrap_or("0");
    format!(
        "<image x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" preserveAspectRatio=\"none\" \
         style=\"image-rendering:pixelated\" href=\"{href}\"/>",
        attr("x"),
        attr("y"),
        attr("width"),
        attr("height"),
    )
}

/// The value of attribute `name` in one SVG element.
fn attribute<'a>(element: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let start = element.find(&key)? + key.len();
    let len = element[start..].find('"')?;
    Some(&element[start..start + len])
}
