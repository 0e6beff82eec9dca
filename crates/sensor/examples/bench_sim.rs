//! Timing of the simulated tap (pins, then render) on the built-in disk,
//! with the same poses as `tactrace bench`; prints us per tap for each part
//! and a checksum of the pins (to confirm optimisations keep results).
//!
//! Run: cargo run --release -p tactrace-sensor --example bench_sim [taps]
use std::time::Instant;

/// This thread's time on a CPU so far, s (Linux schedstat), so the figure
/// is not inflated when other processes share the cores.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}
use tactrace_geometry::{builtin_shape, BuiltinShape, Pose};
use tactrace_sensor::{TacTipConfig, TacTipModel};

/// The previous renderer's disc loop (whole bounding box, one square root
/// per pixel), kept here only to time the span-based one against it.
fn old_disc(frame: &mut image::GrayImage, c: [f64; 2], r: f64) {
    let (w, h) = frame.dimensions();
    let x0 = (c[0] - r - 1.0).floor().max(0.0) as i64;
    let y0 = (c[1] - r - 1.0).floor().max(0.0) as i64;
    let x1 = ((c[0] + r + 1.0).ceil() as i64).min(w as i64 - 1);
    let y1 = ((c[1] + r + 1.0).ceil() as i64).min(h as i64 - 1);
    let width = w as usize;
    let buf: &mut [u8] = frame;
    for y in y0..=y1 {
        let dy = y as f64 - c[1];
        for x in x0..=x1 {
            let dx = x as f64 - c[0];
            let cover = (r + 0.5 - (dx * dx + dy * dy).sqrt()).clamp(0.0, 1.0);
            if cover > 0.0 {
                let v = (255.0 * cover + 0.5) as u8;
                let px = &mut buf[y as usize * width + x as usize];
                *px = (*px).max(v);
            }
        }
    }
}

fn main() {
    let taps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(2000);
    let model = TacTipModel::new(TacTipConfig::default()).expect("default config");
    let disk = builtin_shape(BuiltinShape::Disk);
    let (edge, normal) = disk.at_arc_length(0.0);
    let yaw = normal.y.atan2(normal.x).to_degrees();
    let poses: Vec<Pose> = (0..taps)
        .map(|i| {
            let u = i as f64 / taps.max(1) as f64;
            let p = edge + normal * (-5.0 + 10.0 * u);
            Pose::planar(p.x, p.y, -3.0, yaw - 45.0 + 90.0 * ((u * 7.0) % 1.0))
        })
        .collect();
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let pins: Vec<Vec<[f64; 2]>> = poses.iter().map(|p| model.pins(&disk, *p, None)).collect();
    let t_pins = t0.elapsed().as_secs_f64();
    let (t1, c1) = (Instant::now(), cpu_seconds());
    let frames: Vec<_> = pins.iter().map(|p| model.render(p, None)).collect();
    let t_render = t1.elapsed().as_secs_f64();
    let c2 = cpu_seconds();
    let sum: f64 = pins.iter().flatten().map(|p| p[0] + 2.0 * p[1]).sum();
    let pix: u64 = frames
        .iter()
        .flat_map(|f| f.iter())
        .map(|&v| v as u64)
        .sum();
    let n = taps.max(1) as f64;
    println!(
        "wall: pins {:.1} us/tap, render {:.1} us/frame, total {:.1} us/tap",
        t_pins * 1e6 / n,
        t_render * 1e6 / n,
        (t_pins + t_render) * 1e6 / n
    );
    println!(
        "cpu:  pins {:.1} us/tap, render {:.1} us/frame, total {:.1} us/tap",
        (c1 - c0) * 1e6 / n,
        (c2 - c1) * 1e6 / n,
        (c2 - c0) * 1e6 / n
    );
    println!("checksum: pins {sum:.6} pixels {pix}");
    // The same renders with each frame dropped at once: no fresh memory
    // to fault in, which `tactrace bench` pays by keeping every frame.
    let c3 = cpu_seconds();
    let mut same = true;
    for (p, f) in pins.iter().zip(&frames) {
        same &= model.render(p, None) == *f;
    }
    let c4 = cpu_seconds();
    let (w, h) = model.image_size();
    let mut old_same = true;
    for (p, f) in pins.iter().zip(&frames) {
        let mut g = image::GrayImage::new(w, h);
        for (c, r) in p.iter().zip(model.pin_radii()) {
            old_disc(&mut g, *c, *r);
        }
        old_same &= g == *f;
    }
    let c5 = cpu_seconds();
    println!(
        "cpu:  frames dropped (+ compare): render {:.1} us/frame, previous renderer {:.1} us/frame; identical frames: {old_same} (repeat {same})",
        (c4 - c3) * 1e6 / n,
        (c5 - c4) * 1e6 / n
    );
}
