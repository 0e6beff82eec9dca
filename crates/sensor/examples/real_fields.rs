//! Real displacement fields of the 127-pin edge set, tracked with the
//! vision crate's robust pin extractor (`PinExtractor`, preset `real256`),
//! written as a plain-text cache for `fit_mechanics`. Not part of the
//! product (docs/sensor-model.md, "Mechanics fit").
//!
//! Run: cargo run --release -p tactrace-sensor --example real_fields -- OUT
//! Line 1: `rest x0 y0 x1 y1 ...` (reference pins, detection order); then
//! per frame: name r theta dz move_1 move_2 move_6 matched dx0 dy0 ...
//! (pins in reference order; unmatched pins written as `nan nan`).
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use tactrace_sensor::read_frame;
use tactrace_vision::{BlobParams, PinExtractor};

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tactip127-edge2d")
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "/tmp/real_fields.txt".into());
    let dir = data_dir();
    let Ok(init) = read_frame(&dir.join("frames/init_0.png")) else {
        eprintln!("real data not found under {}; skipping", dir.display());
        return Ok(());
    };
    let mut ex = PinExtractor::from_reference_frame(&init, BlobParams::preset("real256")?)?;
    ex.min_matched_fraction = 0.0;
    let rest = ex.tracker.reference().to_vec();
    let mut text = String::from("rest");
    for p in &rest {
        write!(text, " {:.3} {:.3}", p[0], p[1])?;
    }
    text.push('\n');
    let csv = std::fs::read_to_string(dir.join("targets.csv"))?;
    let (mut frames, mut full) = (0usize, 0usize);
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |k: usize| f.get(k).and_then(|s| s.parse::<f64>().ok());
        let (Some(r), Some(th), Some(dz), Some(m1), Some(m2), Some(m6)) =
            (num(5), num(9), num(6), num(10), num(11), num(15))
        else {
            continue;
        };
        let Ok(img) = read_frame(&dir.join("frames").join(f[0])) else {
            continue;
        };
        let tracked = ex.extract(&img)?;
        let matched = tracked.matched_count();
        full += usize::from(matched == rest.len());
        frames += 1;
        write!(
            text,
            "{} {r:.4} {th:.4} {dz:.4} {m1:.4} {m2:.4} {m6:.4} {matched}",
            f[0]
        )?;
        for ((p, q), m) in tracked.pins.iter().zip(&rest).zip(&tracked.matched) {
            if *m {
                write!(text, " {:.3} {:.3}", p[0] - q[0], p[1] - q[1])?;
            } else {
                text.push_str(" nan nan");
            }
        }
        text.push('\n');
    }
    std::fs::write(&out, text)?;
    println!("{frames} frames, {full} with all pins matched -> {out}");
    Ok(())
}
