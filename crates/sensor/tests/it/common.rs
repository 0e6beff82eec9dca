//! Helpers shared by the sensor's integration tests.
#![allow(dead_code)]
use tactrace_geometry::{Contour, Pose, Vec2};
use tactrace_sensor::{Frame, TacTipConfig, TacTipModel};

/// A model whose camera is unrotated and unmirrored, so sensor-frame
/// symmetries map directly onto image symmetries.
pub fn plain_model() -> TacTipModel {
    let mut cfg = TacTipConfig::default();
    cfg.camera.rotation_deg = 0.0;
    cfg.camera.mirror = false;
    TacTipModel::new(cfg).expect("default config is valid")
}

/// Image displacement of each pin from rest, px.
pub fn displacement(model: &TacTipModel, pins: &[[f64; 2]]) -> Vec<[f64; 2]> {
    model
        .rest_pins()
        .iter()
        .zip(pins)
        .map(|(r, p)| [p[0] - r[0], p[1] - r[1]])
        .collect()
}

pub fn mean_magnitude(d: &[[f64; 2]]) -> f64 {
    d.iter().map(|v| v[0].hypot(v[1])).sum::<f64>() / d.len() as f64
}

/// Index of the pin whose rest position (relative to the centre pin) is
/// `map` of pin i's, within 1e-6 px.
pub fn partner(rest: &[[f64; 2]], i: usize, map: impl Fn([f64; 2]) -> [f64; 2]) -> usize {
    let c = rest[0];
    let r = map([rest[i][0] - c[0], rest[i][1] - c[1]]);
    let target = [c[0] + r[0], c[1] + r[1]];
    rest.iter()
        .position(|p| (p[0] - target[0]).hypot(p[1] - target[1]) < 1e-6)
        .expect("lattice is symmetric under this map")
}

pub fn rotate(v: [f64; 2], deg: f64) -> [f64; 2] {
    let (s, c) = deg.to_radians().sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1]]
}

/// A square of half-width `half` mm centred on `centre`.
pub fn square(centre: [f64; 2], half: f64) -> Contour {
    let v = |x: f64, y: f64| Vec2::new(centre[0] + x, centre[1] + y);
    Contour::new(vec![
        v(-half, -half),
        v(half, -half),
        v(half, half),
        v(-half, half),
    ])
    .expect("square is a valid contour")
}

/// Sensor tip at (x, y) pressed `depth` mm with yaw `rz` degrees.
pub fn tap(x: f64, y: f64, depth: f64, rz: f64) -> Pose {
    Pose::planar(x, y, -depth, rz)
}

/// Intensity-weighted and thresholded centroids of 8-connected bright
/// components (pixel (x, y) centred at (x, y)).
pub fn centroids(frame: &Frame) -> Vec<([f64; 2], [f64; 2])> {
    let (w, h) = frame.dimensions();
    let (w, h) = (w as i64, h as i64);
    let val = |x: i64, y: i64| frame.get_pixel(x as u32, y as u32)[0] as f64;
    let mut seen = vec![false; (w * h) as usize];
    let mut out = Vec::new();
    for y0 in 0..h {
        for x0 in 0..w {
            if seen[(y0 * w + x0) as usize] || val(x0, y0) == 0.0 {
                continue;
            }
            seen[(y0 * w + x0) as usize] = true;
            let mut stack = vec![(x0, y0)];
            let mut acc = [0.0; 6];
            while let Some((x, y)) = stack.pop() {
                let v = val(x, y);
                acc[0] += v * x as f64;
                acc[1] += v * y as f64;
                acc[2] += v;
                if v >= 128.0 {
                    acc[3] += x as f64;
                    acc[4] += y as f64;
                    acc[5] += 1.0;
                }
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (nx, ny) = (x + dx, y + dy);
                        if nx < 0 || ny < 0 || nx >= w || ny >= h {
                            continue;
                        }
                        let j = (ny * w + nx) as usize;
                        if !seen[j] && val(nx, ny) > 0.0 {
                            seen[j] = true;
                            stack.push((nx, ny));
                        }
                    }
                }
            }
            out.push((
                [acc[0] / acc[2], acc[1] / acc[2]],
                [acc[3] / acc[5], acc[4] / acc[5]],
            ));
        }
    }
    out
}

/// The calibration sample `model` gives for `tap`: the label and every
/// pin's displacement from `rest`, px.
pub fn fit_sample(
    model: &TacTipModel,
    rest: &[[f64; 2]],
    tap: tactrace_sensor::EdgeTap,
) -> tactrace_sensor::FitSample {
    let disp = model
        .edge_tap_pins(&tap)
        .iter()
        .zip(rest)
        .map(|(p, r)| Some([p[0] - r[0], p[1] - r[1]]))
        .collect();
    tactrace_sensor::FitSample { tap, disp }
}

/// `n` taps of `truth` with their fields against its rest pins: r in
/// [-3, 3] mm, dz in [3, 5], slides of up to `slide` mm and deg, the
/// angle of tap `k` from `theta(k)`; each label spread over its range by
/// [`spread`] with its own stride.
pub fn depth_taps(
    truth: &TacTipConfig,
    n: usize,
    slide: f64,
    theta: impl Fn(usize) -> f64,
) -> (Vec<[f64; 2]>, Vec<tactrace_sensor::FitSample>) {
    let model = TacTipModel::new(truth.clone()).unwrap();
    let rest = model.rest_pins().to_vec();
    let samples = (0..n)
        .map(|k| {
            let span = |m: usize| -slide + 2.0 * slide * spread(k, m, n);
            let tap = tactrace_sensor::EdgeTap {
                r_mm: -3.0 + 6.0 * spread(k, 7, n),
                theta_deg: theta(k),
                dz_mm: 3.0 + 2.0 * spread(k, 13, n),
                shear: Some(tactrace_sensor::Shear {
                    dx_mm: span(17),
                    dy_mm: span(19),
                    drz_deg: span(23),
                }),
            };
            fit_sample(&model, &rest, tap)
        })
        .collect();
    (rest, samples)
}

/// Tap `k` of `n`'s place in [0, 1] with stride `m` (coprime to `n`,
/// so the taps cover the range evenly and the labels do not move together).
pub fn spread(k: usize, m: usize, n: usize) -> f64 {
    ((k * m) % n) as f64 / (n - 1) as f64
}
