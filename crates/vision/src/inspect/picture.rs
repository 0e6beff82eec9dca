//! The inspection as a picture (pure: returns the image, writes nothing):
//! the frame dimmed and enlarged, the mask circle in blue, the rim in
//! yellow, each pin kept as a green cross, clusters of touching pins in
//! orange, components left out in red.

use image::{Rgb, RgbImage};

use super::Inspection;
use crate::blob::Frame;
use crate::preprocess::MaskCircle;

const BLUE: Rgb<u8> = Rgb([70, 130, 255]);
const YELLOW: Rgb<u8> = Rgb([240, 200, 40]);
const GREEN: Rgb<u8> = Rgb([40, 220, 80]);
const ORANGE: Rgb<u8> = Rgb([255, 140, 0]);
const RED: Rgb<u8> = Rgb([230, 40, 40]);

/// `frame` (the inspected frame `inspection.picture.frame`, after the
/// crop) with what the inspection found drawn over it, enlarged to at
/// least 512 px on its longer side (a whole factor).
pub fn draw_inspection(frame: &Frame, inspection: &Inspection) -> RgbImage {
    let longer = frame.width().max(frame.height()).max(1);
    let scale = 512u32.div_ceil(longer).max(1);
    let s = f64::from(scale);
    let mut img = RgbImage::from_fn(frame.width() * scale, frame.height() * scale, |x, y| {
        let v = frame.get_pixel(x / scale, y / scale)[0] / 2;
        Rgb([v, v, v])
    });
    let to_picture = |p: [f64; 2]| [(p[0] + 0.5) * s, (p[1] + 0.5) * s];
    if let Some(mask) = inspection.preprocess.mask {
        circle(&mut img, mask, s, BLUE);
    }
    if let Some(rim) = inspection.rim {
        circle(&mut img, rim, s, YELLOW);
    }
    let arm = (0.4 * s).max(2.0);
    let picture = &inspection.picture;
    for &p in &picture.rejected {
        cross(&mut img, to_picture(p), arm, true, RED);
    }
    for &p in &picture.clusters {
        cross(&mut img, to_picture(p), arm * 1.5, false, ORANGE);
    }
    for &p in &picture.pins {
        cross(&mut img, to_picture(p), arm, false, GREEN);
    }
    img
}

fn put(img: &mut RgbImage, x: f64, y: f64, colour: Rgb<u8>) {
    if x >= 0.0 && y >= 0.0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, colour);
    }
}

/// A circle given in frame pixels, drawn at `scale`.
fn circle(img: &mut RgbImage, c: MaskCircle, scale: f64, colour: Rgb<u8>) {
    let r = c.radius * scale;
    let steps = (std::f64::consts::TAU * r).ceil().max(8.0) as usize;
    for k in 0..steps {
        let t = std::f64::consts::TAU * k as f64 / steps as f64;
        let x = (c.centre[0] + 0.5) * scale + r * t.cos();
        let y = (c.centre[1] + 0.5) * scale + r * t.sin();
        put(img, x, y, colour);
    }
}

/// A `+` (or an `x` when `diagonal`) of half-width `arm` at `p`.
fn cross(img: &mut RgbImage, p: [f64; 2], arm: f64, diagonal: bool, colour: Rgb<u8>) {
    let n = arm.ceil() as i32;
    for k in -n..=n {
        let k = f64::from(k);
        if diagonal {
            put(img, p[0] + k, p[1] + k, colour);
            put(img, p[0] + k, p[1] - k, colour);
        } else {
            put(img, p[0] + k, p[1], colour);
            put(img, p[0], p[1] + k, colour);
        }
    }
}
