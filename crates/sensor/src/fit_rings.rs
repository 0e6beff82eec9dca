//! The camera of a concentric-rings TacTip fitted to its measured rest
//! pins (eq. S1r through S2-S3): the centre, the focal length and the
//! camera height (the perspective that sets how the rings' image radii
//! grow outwards), with each ring's phase measured from the pins in closed
//! form. The sensor frame's orientation (rotation, mirror) stays as given:
//! circles do not show it, the phases take up the pins' angles.
use crate::layout::{concentric_rings, Projection};
use crate::nelder_mead::minimise;
use crate::TacTipConfig;

/// The highest camera the fit considers, mm (nearly orthographic).
const MAX_HEIGHT_MM: f64 = 1e5;

/// `cfg` (a rings layout with its ring count and spacing set) with the
/// camera centre, focal length, height and ring phases fitted to
/// `rest_px` by Nelder-Mead on the symmetric mean squared nearest-pin
/// distance.
pub(crate) fn fit_rings_camera(cfg: &TacTipConfig, rest_px: &[[f64; 2]]) -> TacTipConfig {
    let start = initial(cfg, rest_px);
    let cost = |x: &[f64]| match candidate(cfg, x) {
        Some(c) => super::fit_layout::chamfer(rest_px, &projected(&with_phases(c, rest_px))),
        None => f64::INFINITY,
    };
    let step = [2.0, 2.0, 0.05 * start[2], 0.2];
    let (x, _) = minimise(&cost, &start, &step, 400);
    let (x, _) = minimise(&cost, &x, &[0.5, 0.5, 0.01 * start[2], 0.05], 400);
    candidate(cfg, &x).map_or_else(|| cfg.clone(), |c| with_phases(c, rest_px))
}

/// The configuration at x = (centre x, centre y, focal / height px per
/// mm, ln height), or `None` where the camera would not sit above the
/// outer ring or beyond [`MAX_HEIGHT_MM`].
fn candidate(cfg: &TacTipConfig, x: &[f64]) -> Option<TacTipConfig> {
    let height = x[3].exp();
    let rim = rim_height(cfg);
    if !(x[2] > 0.0 && height > rim * 1.001 + 1e-6 && height <= MAX_HEIGHT_MM) {
        return None;
    }
    let mut c = cfg.clone();
    c.camera.centre_px = [x[0], x[1]];
    c.camera.focal_px = x[2] * height;
    c.camera.height_mm = height;
    Some(c)
}

/// Height of the outer ring above the dome's lowest point, mm (eq. S2).
fn rim_height(cfg: &TacTipConfig) -> f64 {
    let g = &cfg.geometry;
    let outer = g.rings as f64 * g.pin_spacing_mm / g.dome_radius_mm;
    g.dome_radius_mm * (1.0 - outer.cos())
}

/// Image positions of the model's pins, px.
fn projected(cfg: &TacTipConfig) -> Vec<[f64; 2]> {
    let g = &cfg.geometry;
    let proj = Projection::new(g, &cfg.camera);
    concentric_rings(g.rings, g.pin_spacing_mm, &g.ring_phase_deg)
        .into_iter()
        .map(|p| proj.project(p))
        .collect()
}

/// `cfg` with each ring's phase measured from the pins: every measured
/// pin goes to the ring whose image radius is nearest its distance from
/// the camera centre, its angle is taken into the sensor frame (rotation,
/// mirror), and ring k's phase is the circular mean of 6k times those
/// angles over 6k, wrapped to within half the ring's pin step of zero.
fn with_phases(mut cfg: TacTipConfig, rest_px: &[[f64; 2]]) -> TacTipConfig {
    let n = cfg.geometry.rings;
    let proj = Projection::new(&cfg.geometry, &cfg.camera);
    let centre = cfg.camera.centre_px;
    let radius_px = |k: usize| {
        let p = proj.project([k as f64 * cfg.geometry.pin_spacing_mm, 0.0]);
        (p[0] - centre[0]).hypot(p[1] - centre[1])
    };
    let radii: Vec<f64> = (0..=n).map(radius_px).collect();
    let rotation = cfg.camera.rotation_deg.to_radians();
    let mirror = if cfg.camera.mirror { -1.0 } else { 1.0 };
    let mut sums = vec![[0.0f64; 2]; n + 1];
    for p in rest_px {
        let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
        let r = dx.hypot(dy);
        let ring = nearest_ring(&radii, r);
        if ring == 0 {
            continue;
        }
        let angle = mirror * (dy.atan2(dx) - rotation);
        let (s, c) = (6.0 * ring as f64 * angle).sin_cos();
        sums[ring][0] += s;
        sums[ring][1] += c;
    }
    cfg.geometry.ring_phase_deg = (1..=n)
        .map(|k| {
            let [s, c] = sums[k];
            if s == 0.0 && c == 0.0 {
                return 0.0;
            }
            s.atan2(c).to_degrees() / (6.0 * k as f64)
        })
        .collect();
    cfg
}

/// Index of the radius in `radii` (rising) nearest `r`.
fn nearest_ring(radii: &[f64], r: f64) -> usize {
    let above = radii.partition_point(|&v| v < r);
    match above {
        0 => 0,
        k if k == radii.len() => k - 1,
        k if r - radii[k - 1] <= radii[k] - r => k - 1,
        k => k,
    }
}

/// Start of the fit, x = (centre x, centre y, focal / height, ln height):
/// the centre at the pin nearest the pins' centroid; the measured rings
/// taken as the pins sorted by distance from it in groups of 1, 6, 12,
/// ...; the height the one of a log-spaced scan whose projected ring radii
/// (focal fitted by least squares) best match the groups' mean radii.
fn initial(cfg: &TacTipConfig, rest_px: &[[f64; 2]]) -> [f64; 4] {
    let centre = super::fit_layout::central_pin(rest_px);
    let mut dist: Vec<f64> = rest_px
        .iter()
        .map(|p| (p[0] - centre[0]).hypot(p[1] - centre[1]))
        .collect();
    dist.sort_by(f64::total_cmp);
    let g = &cfg.geometry;
    let mut measured = Vec::with_capacity(g.rings);
    let mut at = 1;
    for k in 1..=g.rings {
        let group = &dist[at.min(dist.len())..(at + 6 * k).min(dist.len())];
        at += 6 * k;
        if !group.is_empty() {
            measured.push((k, group.iter().sum::<f64>() / group.len() as f64));
        }
    }
    let rim = rim_height(cfg);
    let (low, high) = ((rim * 1.01 + 1e-3).ln(), MAX_HEIGHT_MM.ln());
    let mut best = (
        f64::INFINITY,
        cfg.camera.focal_px / cfg.camera.height_mm,
        cfg.camera.height_mm.ln(),
    );
    for step in 0..=60 {
        let ln_h = low + (high - low) * step as f64 / 60.0;
        let height = ln_h.exp();
        // Image radius per px of focal length (eqs. S2-S3).
        let unit = |k: usize| {
            let phi = k as f64 * g.pin_spacing_mm / g.dome_radius_mm;
            g.dome_radius_mm * phi.sin() / (height - g.dome_radius_mm * (1.0 - phi.cos()))
        };
        let (uu, um) = measured.iter().fold((0.0, 0.0), |(uu, um), &(k, m)| {
            (uu + unit(k) * unit(k), um + unit(k) * m)
        });
        if uu <= 0.0 {
            continue;
        }
        let focal = um / uu;
        let misfit: f64 = measured
            .iter()
            .map(|&(k, m)| (focal * unit(k) - m).powi(2))
            .sum();
        if misfit < best.0 {
            best = (misfit, focal / height, ln_h);
        }
    }
    [centre[0], centre[1], best.1, best.2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_ring_picks_the_closer_radius() {
        let radii = [0.0, 5.0, 10.0, 14.0];
        assert_eq!(nearest_ring(&radii, 0.1), 0);
        assert_eq!(nearest_ring(&radii, 2.4), 0);
        assert_eq!(nearest_ring(&radii, 2.6), 1);
        assert_eq!(nearest_ring(&radii, 12.5), 3);
        assert_eq!(nearest_ring(&radii, 40.0), 3);
    }
}
