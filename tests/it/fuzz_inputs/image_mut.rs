//! PNG-aware mutations: decode, change pixels, size or colour type, encode
//! again, so the input passes the decoder and reaches the blob detector.
use image::{DynamicImage, GrayImage, Luma, Rgb, RgbImage};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// One pixel-level mutation of a PNG, re-encoded; None if it does not decode.
pub fn mutate_png(data: &[u8], rng: &mut ChaCha8Rng) -> Option<(Vec<u8>, &'static str)> {
    let img = image::load_from_memory(data).ok()?.to_luma8();
    let (out, name) = match rng.random_range(0..8) {
        0 => (DynamicImage::ImageLuma8(noise(&img, rng)), "pixel noise"),
        1 => (DynamicImage::ImageLuma8(flat(&img, rng)), "flat image"),
        2 => (DynamicImage::ImageLuma8(speckle(&img, rng)), "speckles"),
        3 => (DynamicImage::ImageLuma8(resize(&img, rng)), "odd size"),
        4 => (DynamicImage::ImageRgb8(to_rgb(&img)), "colour image"),
        5 => (
            DynamicImage::ImageLuma16(DynamicImage::ImageLuma8(img).to_luma16()),
            "16-bit",
        ),
        6 => (DynamicImage::ImageLuma8(invert(&img)), "inverted"),
        _ => (DynamicImage::ImageLuma8(stripes(&img, rng)), "stripes"),
    };
    let mut bytes = std::io::Cursor::new(Vec::new());
    out.write_to(&mut bytes, image::ImageFormat::Png).ok()?;
    Some((bytes.into_inner(), name))
}

fn noise(img: &GrayImage, rng: &mut ChaCha8Rng) -> GrayImage {
    let mut out = img.clone();
    let p = rng.random_range(0.001..0.5);
    for px in out.pixels_mut() {
        if rng.random_bool(p) {
            px.0[0] = rng.random();
        }
    }
    out
}

fn flat(img: &GrayImage, rng: &mut ChaCha8Rng) -> GrayImage {
    let v = [0u8, 255, 128][rng.random_range(0..3)];
    GrayImage::from_pixel(img.width(), img.height(), Luma([v]))
}

/// Many small bright and dark dots, some touching the border.
fn speckle(img: &GrayImage, rng: &mut ChaCha8Rng) -> GrayImage {
    let mut out = img.clone();
    let (w, h) = out.dimensions();
    for _ in 0..rng.random_range(1..3000) {
        let (x, y) = (rng.random_range(0..w), rng.random_range(0..h));
        let v = if rng.random_bool(0.5) { 255 } else { 0 };
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            if x + dx < w && y + dy < h {
                out.put_pixel(x + dx, y + dy, Luma([v]));
            }
        }
    }
    out
}

/// A crop or tiling to an unusual size (1 px wide, tiny, large).
fn resize(img: &GrayImage, rng: &mut ChaCha8Rng) -> GrayImage {
    let sizes = [
        (1, 1),
        (1, 256),
        (256, 1),
        (3, 3),
        (17, 256),
        (512, 64),
        (1024, 1024),
    ];
    let (w, h) = sizes[rng.random_range(0..sizes.len())];
    GrayImage::from_fn(w, h, |x, y| {
        *img.get_pixel(x % img.width(), y % img.height())
    })
}

fn to_rgb(img: &GrayImage) -> RgbImage {
    RgbImage::from_fn(img.width(), img.height(), |x, y| {
        let v = img.get_pixel(x, y).0[0];
        Rgb([v, v / 2, 255 - v])
    })
}

fn invert(img: &GrayImage) -> GrayImage {
    GrayImage::from_fn(img.width(), img.height(), |x, y| {
        Luma([255 - img.get_pixel(x, y).0[0]])
    })
}

/// Bright horizontal or vertical lines across the frame.
fn stripes(img: &GrayImage, rng: &mut ChaCha8Rng) -> GrayImage {
    let mut out = img.clone();
    let period = rng.random_range(2..40);
    let vertical = rng.random_bool(0.5);
    for (x, y, px) in out.enumerate_pixels_mut() {
        let k = if vertical { x } else { y };
        if k % period == 0 {
            px.0[0] = 255;
        }
    }
    out
}
