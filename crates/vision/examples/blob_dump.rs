//! Developer tool for cross-checking the blob detector against OpenCV:
//! `cargo run -p tactrace-vision --example blob_dump -- <preset|file.toml> <png>...`
//! prints one line per keypoint: `<file> <x> <y> <size>`, then the mean
//! detection time per frame on stderr.

use std::time::Instant;

use tactrace_vision::{detect_blobs, BlobParams};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let which = args
        .next()
        .ok_or("usage: blob_dump <preset|file.toml> <png>...")?;
    let params = if which.ends_with(".toml") {
        BlobParams::from_toml(&std::fs::read_to_string(&which)?)?
    } else {
        BlobParams::preset(&which)?
    };
    let mut elapsed = 0.0;
    let mut frames = 0;
    for path in args {
        let frame = image::open(&path)?.to_luma8();
        let start = Instant::now();
        let keypoints = detect_blobs(&frame, &params);
        elapsed += start.elapsed().as_secs_f64();
        frames += 1;
        for k in keypoints {
            println!("{path} {:.6} {:.6} {:.6}", k.x, k.y, k.size);
        }
    }
    if frames > 0 {
        eprintln!(
            "mean detect time {:.1} us over {frames} frames",
            1e6 * elapsed / f64::from(frames)
        );
    }
    Ok(())
}
