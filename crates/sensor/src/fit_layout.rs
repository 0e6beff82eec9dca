//! The simulated TacTip's layout fitted to a user's rest pins (`tactrace
//! calibrate`, docs/calibration.md "Any TacTip"): the ring count from the
//! pin count, the frame size, the pin spacing that keeps the layout's
//! extent on the dome, then both kinds of layout fitted and the better one
//! chosen: a hexagonal lattice (eq. S1) with the camera's centre, focal
//! length, rotation and mirror, and concentric rings (eq. S1r) with the
//! camera's centre, focal length and height and each ring's phase
//! (`fit_rings.rs`).
use crate::config::PinLayout;
use crate::fit_rings::fit_rings_camera;
use crate::layout::{hex_lattice, pin_count, skin_pins, Projection};
use crate::model::match_rest_pins;
use crate::nelder_mead::minimise;
use crate::{SensorError, TacTipConfig};

/// Rings a TacTip may have (1 + 3n(n+1) pins).
const MAX_RINGS: usize = 20;

/// Both layouts fitted to one set of rest pins, and the better one.
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutFit {
    /// The configuration of the better-fitting layout.
    pub config: TacTipConfig,
    /// The hexagonal lattice's fit.
    pub hex: KindFit,
    /// The concentric rings' fit.
    pub rings: KindFit,
}

/// One kind of layout fitted to the rest pins.
#[derive(Debug, Clone, PartialEq)]
pub struct KindFit {
    /// The fitted configuration.
    pub config: TacTipConfig,
    /// Root mean square distance from each measured pin to the nearest
    /// model pin and from each model pin to the nearest measured one
    /// (both ways), px.
    pub residual_px: f64,
    /// Whether every measured pin pairs with its own model pin within
    /// half a spacing (what [`crate::TacTipModel::with_rest_pins`] asks).
    pub matched: bool,
    /// Whether the base configuration already fitted and was kept as it
    /// was (frame size apart).
    pub kept: bool,
}

impl LayoutFit {
    /// The kind chosen (the layout of [`Self::config`]).
    pub fn layout(&self) -> PinLayout {
        self.config.geometry.layout
    }

    /// The fit of `kind`.
    pub fn of(&self, kind: PinLayout) -> &KindFit {
        match kind {
            PinLayout::Hex => &self.hex,
            PinLayout::Rings => &self.rings,
        }
    }
}

/// `base` with the layout of the frame whose pins (px, any order) are
/// `rest_px` and whose size is `frame` (width, height px): the better of
/// the two kinds of layout ([`fit_layouts`]).
pub fn fit_layout(
    base: &TacTipConfig,
    rest_px: &[[f64; 2]],
    frame: (u32, u32),
) -> Result<TacTipConfig, SensorError> {
    fit_layouts(base, rest_px, frame).map(|fit| fit.config)
}

/// Both kinds of layout fitted to the rest pins `rest_px` (px, any order)
/// of a frame of size `frame` (width, height px), and the better chosen:
/// of the kinds whose every measured pin pairs with a model pin, the one
/// with the smaller residual. For each kind: when `base` is of that kind
/// and already fits those pins (same count, every pin within half a
/// spacing of a model pin) only the frame size changes; otherwise the
/// ring count comes from the pin count, the spacing keeps `base`'s extent
/// on the dome (pins scaled with it), and the camera is fitted. A lattice
/// keeps its orientation nearest `base`'s up to its 60-degree symmetry;
/// rings keep `base`'s rotation and mirror and fit each ring's phase.
pub fn fit_layouts(
    base: &TacTipConfig,
    rest_px: &[[f64; 2]],
    frame: (u32, u32),
) -> Result<LayoutFit, SensorError> {
    let rings = rings_for(rest_px.len())?;
    let mut cfg = base.clone();
    cfg.camera.width = frame.0;
    cfg.camera.height = frame.1;
    let hex = fit_kind(base, &cfg, PinLayout::Hex, rings, rest_px);
    let circles = fit_kind(base, &cfg, PinLayout::Rings, rings, rest_px);
    let better = match (hex.matched, circles.matched) {
        (true, true) if circles.residual_px < hex.residual_px => &circles,
        (true, _) => &hex,
        (false, true) => &circles,
        (false, false) => {
            let closer = if circles.residual_px < hex.residual_px {
                &circles
            } else {
                &hex
            };
            let source =
                check(&closer.config, rest_px)
                    .err()
                    .unwrap_or_else(|| SensorError::RestPins {
                        expected: rest_px.len(),
                        got: rest_px.len(),
                        reason: "the fitted layout is not a valid sensor".into(),
                    });
            return Err(SensorError::NoLayoutFits {
                pins: rest_px.len(),
                hex_px: hex.residual_px,
                rings_px: circles.residual_px,
                source: Box::new(source),
            });
        }
    };
    Ok(LayoutFit {
        config: better.config.clone(),
        hex,
        rings: circles,
    })
}

/// `cfg` (`base` with the frame size) laid out as `kind` with `rings`
/// rings and fitted to `rest_px`.
fn fit_kind(
    base: &TacTipConfig,
    cfg: &TacTipConfig,
    kind: PinLayout,
    rings: usize,
    rest_px: &[[f64; 2]],
) -> KindFit {
    let g = &base.geometry;
    if g.layout == kind && g.rings == rings && check(cfg, rest_px).is_ok() {
        return KindFit {
            residual_px: residual(cfg, rest_px),
            config: cfg.clone(),
            matched: true,
            kept: true,
        };
    }
    let mut start = cfg.clone();
    let scale = g.rings as f64 / rings as f64;
    start.geometry.layout = kind;
    start.geometry.ring_phase_deg.clear();
    start.geometry.rings = rings;
    start.geometry.pin_spacing_mm = g.pin_spacing_mm * scale;
    start.geometry.pin_radius_mm = g.pin_radius_mm * scale;
    let config = match kind {
        PinLayout::Hex => fit_hex(&start, rest_px),
        PinLayout::Rings => fit_rings_camera(&start, rest_px),
    };
    KindFit {
        residual_px: residual(&config, rest_px),
        matched: check(&config, rest_px).is_ok(),
        config,
        kept: false,
    }
}

/// The lattice's camera fitted with either mirror, the better kept.
fn fit_hex(cfg: &TacTipConfig, rest_px: &[[f64; 2]]) -> TacTipConfig {
    let mut best: Option<(f64, TacTipConfig)> = None;
    for mirror in [cfg.camera.mirror, !cfg.camera.mirror] {
        let mut trial = cfg.clone();
        trial.camera.mirror = mirror;
        let start = initial_camera(&trial, rest_px);
        let (fitted, cost) = fit_camera(&trial, rest_px, start);
        if best.as_ref().is_none_or(|(c, _)| cost < *c) {
            best = Some((cost, fitted));
        }
    }
    best.expect("two mirror choices tried").1
}

/// Whether `cfg` is valid and its model pins pair one to one with the
/// measured pins (as [`crate::TacTipModel::with_rest_pins`] checks).
fn check(cfg: &TacTipConfig, rest_px: &[[f64; 2]]) -> Result<(), SensorError> {
    cfg.validate()?;
    let proj = Projection::new(&cfg.geometry, &cfg.camera);
    match_rest_pins(&proj, &skin_pins(&cfg.geometry), &cfg.geometry, rest_px).map(|_| ())
}

/// The fit's residual: root mean square nearest-pin distance both ways
/// between the measured pins and the model's, px.
fn residual(cfg: &TacTipConfig, rest_px: &[[f64; 2]]) -> f64 {
    let proj = Projection::new(&cfg.geometry, &cfg.camera);
    let model: Vec<[f64; 2]> = skin_pins(&cfg.geometry)
        .iter()
        .map(|g| proj.project(*g))
        .collect();
    (0.5 * chamfer(rest_px, &model)).sqrt()
}

/// The ring count of a layout of `pins` pins.
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
            "the simulated TacTip lays 1 + 3n(n + 1) pins on n hexagonal or circular rings \
             ({}, ...); check that the reference frame shows every pin once (blob parameters, \
             --params)",
            counts.join(", ")
        ),
    })
}

/// The measured pin nearest the pins' centroid.
pub(crate) fn central_pin(rest_px: &[[f64; 2]]) -> [f64; 2] {
    let n = rest_px.len() as f64;
    let mean = rest_px
        .iter()
        .fold([0.0, 0.0], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    *rest_px
        .iter()
        .min_by(|a, b| dist(**a, mean).total_cmp(&dist(**b, mean)))
        .expect("at least one pin")
}

/// (centre x, centre y, focal px, rotation deg): centre at the pin nearest
/// the pins' centroid, focal from the median nearest-neighbour distance
/// there, rotation from the direction to the nearest neighbour against the
/// lattice's own first-neighbour direction (mirrored with the camera),
/// taken nearest `cfg`'s rotation modulo 60 degrees.
fn initial_camera(cfg: &TacTipConfig, rest_px: &[[f64; 2]]) -> [f64; 4] {
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let centre = central_pin(rest_px);
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
pub(crate) fn chamfer(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
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
    use crate::TacTipModel;

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
