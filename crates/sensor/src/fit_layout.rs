//! The simulated TacTip's layout fitted to a user's undeformed frame
//! (`tactrace calibrate`, docs/calibration.md "Any TacTip"): the ring count
//! from the pin count, the frame size, the pin spacing that keeps the
//! lattice's extent on the dome, and the camera (centre, focal length,
//! rotation, mirror) that projects the lattice onto the measured pins.
use crate::layout::{hex_lattice, pin_count, Projection};
use crate::nelder_mead::minimise;
use crate::{SensorError, TacTipConfig, TacTipModel};

/// Hexagonal rings a TacTip may have (1 + 3n(n+1) pins).
const MAX_RINGS: usize = 20;

/// `base` with the layout of the frame whose pins (px, any order) are
/// `rest_px` and whose size is `frame` (width, height px). When `base`
/// already fits those pins (same count, every pin within half a spacing of
/// a model pin) only the frame size changes; otherwise the ring count, the
/// spacing (the lattice keeps `base`'s extent on the dome, pins scaled with
/// it) and the camera are fitted. The sensor frame's orientation is fixed
/// up to the lattice's 60-degree symmetry by taking the rotation nearest
/// `base`'s.
pub fn fit_layout(
    base: &TacTipConfig,
    rest_px: &[[f64; 2]],
    frame: (u32, u32),
) -> Result<TacTipConfig, SensorError> {
    let rings = rings_for(rest_px.len())?;
    let mut cfg = base.clone();
    cfg.camera.width = frame.0;
    cfg.camera.height = frame.1;
    if rings == base.geometry.rings
        && TacTipModel::with_rest_pins(cfg.clone(), rest_px.to_vec()).is_ok()
    {
        return Ok(cfg);
    }
    let scale = base.geometry.rings as f64 / rings as f64;
    cfg.geometry.rings = rings;
    cfg.geometry.pin_spacing_mm = base.geometry.pin_spacing_mm * scale;
    cfg.geometry.pin_radius_mm = base.geometry.pin_radius_mm * scale;
    let mut best: Option<(f64, TacTipConfig)> = None;
    for mirror in [base.camera.mirror, !base.camera.mirror] {
        let mut trial = cfg.clone();
        trial.camera.mirror = mirror;
        let start = initial_camera(&trial, rest_px);
        let (fitted, cost) = fit_camera(&trial, rest_px, start);
        if best.as_ref().is_none_or(|(c, _)| cost < *c) {
            best = Some((cost, fitted));
        }
    }
    let (_, fitted) = best.expect("two mirror choices tried");
    TacTipModel::with_rest_pins(fitted.clone(), rest_px.to_vec())?;
    Ok(fitted)
}

/// The ring count of a hexagonal lattice of `pins` pins.
fn rings_for(pins: usize) -> Result<usize, SensorError> {
    if let Some(n) = (1..=MAX_RINGS).find(|&n| pin_count(n) == pins) {
        return Ok(n);
    }
    let nearest = (1..=MAX_RINGS)
        .map(pin_count)
        .min_by_key(|&c| c.abs_diff(pins))
        .unwrap_or(127);
    let counts: Vec<String> = (2..=10).map(|n| pin_count(n).to_string()).collect();
    Err(SensorError::RestPins {
        expected: nearest,
        got: pins,
        reason: format!(
            "the simulated TacTip is a hexagonal lattice of 1 + 3n(n + 1) pins ({}, ...); \
             check that the reference frame shows every pin once (blob parameters, --params)",
            counts.join(", ")
        ),
    })
}

/// (centre x, centre y, focal px, rotation deg): centre at the pin nearest
/// the pins' centroid, focal from the median nearest-neighbour distance
/// there, rotation from the direction to the nearest neighbour against the
/// lattice's own first-neighbour direction (mirrored with the camera),
/// taken nearest `cfg`'s rotation modulo 60 degrees.
fn initial_camera(cfg: &TacTipConfig, rest_px: &[[f64; 2]]) -> [f64; 4] {
    let n = rest_px.len() as f64;
    let mean = rest_px
        .iter()
        .fold([0.0, 0.0], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let centre = *rest_px
        .iter()
        .min_by(|a, b| dist(**a, mean).total_cmp(&dist(**b, mean)))
        .expect("at least one pin");
    let neighbour = *rest_px
        .iter()
        .filter(|p| dist(**p, centre) > 1e-9)
        .min_by(|a, b| dist(**a, centre).total_cmp(&dist(**b, centre)))
        .unwrap_or(&centre);
    let spacing_px = dist(neighbour, centre).max(1.0);
    let g = &cfg.geometry;
    let focal = spacing_px * cfg.camera.height_mm / g.pin_spacing_mm;
    let seen = (neighbour[1] - centre[1])
        .atan2(neighbour[0] - centre[0])
        .to_degrees();
    let first = hex_lattice(1, 1.0)[1];
    let own = first[1].atan2(first[0]).to_degrees();
    let own = if cfg.camera.mirror { -own } else { own };
    let base = cfg.camera.rotation_deg;
    let rotation = base + (seen - own - base + 30.0).rem_euclid(60.0) - 30.0;
    [centre[0], centre[1], focal, rotation]
}

/// Fit the camera from `start` by Nelder-Mead on the mean squared distance
/// from each measured pin to the nearest projected lattice pin and back.
fn fit_camera(cfg: &TacTipConfig, rest_px: &[[f64; 2]], start: [f64; 4]) -> (TacTipConfig, f64) {
    let lattice = hex_lattice(cfg.geometry.rings, cfg.geometry.pin_spacing_mm);
    let with = |x: &[f64]| {
        let mut c = cfg.clone();
        c.camera.centre_px = [x[0], x[1]];
        c.camera.focal_px = x[2];
        c.camera.rotation_deg = x[3];
        c
    };
    let cost = |x: &[f64]| {
        if x[2] <= 0.0 {
            return f64::INFINITY;
        }
        let c = with(x);
        let proj = Projection::new(&c.geometry, &c.camera);
        let model: Vec<[f64; 2]> = lattice.iter().map(|g| proj.project(*g)).collect();
        chamfer(rest_px, &model)
    };
    let step = [2.0, 2.0, 0.05 * start[2], 3.0];
    let (x, _) = minimise(&cost, &start, &step, 400);
    let (x, value) = minimise(&cost, &x, &[0.5, 0.5, 0.01 * start[2], 0.5], 400);
    (with(&x), value)
}

/// Symmetric mean squared nearest-neighbour distance between two point
/// sets, px^2.
fn chamfer(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    let one_way = |from: &[[f64; 2]], to: &[[f64; 2]]| {
        from.iter()
            .map(|p| {
                to.iter()
                    .map(|q| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2))
                    .fold(f64::INFINITY, f64::min)
            })
            .sum::<f64>()
            / from.len().max(1) as f64
    };
    one_way(a, b) + one_way(b, a)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rest pins of a sensor with `rings` rings seen by another camera.
    fn other_sensor(rings: usize) -> (TacTipConfig, Vec<[f64; 2]>) {
        let base = TacTipConfig::default();
        let mut cfg = base.clone();
        let scale = base.geometry.rings as f64 / rings as f64;
        cfg.geometry.rings = rings;
        cfg.geometry.pin_spacing_mm *= scale;
        cfg.geometry.pin_radius_mm *= scale;
        cfg.camera.width = 320;
        cfg.camera.height = 240;
        cfg.camera.centre_px = [163.0, 118.5];
        cfg.camera.focal_px = 70.0;
        cfg.camera.rotation_deg = 160.0;
        let model = TacTipModel::new(cfg.clone()).unwrap();
        (cfg, model.rest_pins().to_vec())
    }

    #[test]
    fn the_shared_sensor_keeps_its_camera() {
        let base = TacTipConfig::default();
        let model = TacTipModel::new(base.clone()).unwrap();
        let got = fit_layout(&base, model.rest_pins(), (256, 256)).unwrap();
        assert_eq!(got, base);
    }

    #[test]
    fn another_pin_count_and_frame_size_are_fitted() {
        for rings in [4, 8] {
            let (truth, pins) = other_sensor(rings);
            let got = fit_layout(&TacTipConfig::default(), &pins, (320, 240)).unwrap();
            let (c, t) = (&got.camera, &truth.camera);
            assert_eq!(got.geometry.rings, rings);
            assert_eq!((c.width, c.height), (320, 240));
            assert!((c.centre_px[0] - t.centre_px[0]).abs() < 0.5, "{c:?}");
            assert!((c.centre_px[1] - t.centre_px[1]).abs() < 0.5, "{c:?}");
            assert!((c.focal_px / t.focal_px - 1.0).abs() < 0.01, "{c:?}");
            let turn = (c.rotation_deg - t.rotation_deg).rem_euclid(60.0);
            assert!(turn.min(60.0 - turn) < 0.5, "{c:?}");
            // The fitted model takes the pins as its rest layout.
            TacTipModel::with_rest_pins(got, pins).unwrap();
        }
    }

    #[test]
    fn a_pin_count_off_the_lattice_is_refused_with_the_counts_that_fit() {
        let (_, mut pins) = other_sensor(6);
        pins.pop();
        let err = fit_layout(&TacTipConfig::default(), &pins, (256, 256)).unwrap_err();
        let text = err.to_string();
        assert!(text.contains("127") && text.contains("hexagonal"), "{text}");
    }
}
