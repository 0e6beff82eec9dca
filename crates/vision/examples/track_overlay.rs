//! Developer tool: draws the tracked pins of a frame over it for inspection.
//! `cargo run -p tactrace-vision --example track_overlay -- <init.png> <frame.png> <out.png>`
//! Grey: frame; blue: reference pins; green line: matched displacement;
//! red line: filled (missing) pin. Scaled 3x.

use image::{Rgb, RgbImage};
use tactrace_vision::{BlobParams, PinExtractor};

const SCALE: f64 = 3.0;

fn line(img: &mut RgbImage, a: [f64; 2], b: [f64; 2], colour: Rgb<u8>) {
    let steps = ((b[0] - a[0]).hypot(b[1] - a[1]) * SCALE).ceil().max(1.0) as usize;
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let x = (a[0] + t * (b[0] - a[0])) * SCALE;
        let y = (a[1] + t * (b[1] - a[1])) * SCALE;
        if x >= 0.0 && y >= 0.0 && (x as u32) < img.width() && (y as u32) < img.height() {
            img.put_pixel(x as u32, y as u32, colour);
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [init, frame, out] = args.as_slice() else {
        return Err("usage: track_overlay <init.png> <frame.png> <out.png>".into());
    };
    let params = BlobParams::preset("real256")?;
    let mut extractor = PinExtractor::from_reference_frame(&image::open(init)?.to_luma8(), params)?;
    extractor.min_matched_fraction = 0.0;
    let gray = image::open(frame)?.to_luma8();
    let tracked = extractor.extract(&gray)?;
    let (w, h) = (gray.width() * SCALE as u32, gray.height() * SCALE as u32);
    let mut img = RgbImage::from_fn(w, h, |x, y| {
        let v = gray.get_pixel(x / SCALE as u32, y / SCALE as u32)[0] / 3;
        Rgb([v, v, v])
    });
    let reference = extractor.tracker.reference();
    for ((r, p), m) in reference.iter().zip(&tracked.pins).zip(&tracked.matched) {
        let colour = if *m {
            Rgb([0, 255, 0])
        } else {
            Rgb([255, 0, 0])
        };
        line(&mut img, *r, *p, colour);
        line(
            &mut img,
            [r[0] - 0.4, r[1]],
            [r[0] + 0.4, r[1]],
            Rgb([80, 80, 255]),
        );
    }
    img.save(out)?;
    eprintln!("missing {} extra {}", tracked.missing, tracked.extra);
    Ok(())
}
