//! Where the pins are: a hexagonal lattice or concentric rings laid on the
//! hemispherical skin, and their projection into the internal camera's
//! image.
//!
//! Skin points are addressed by *surface coordinates* `g` (mm): the
//! azimuthal-equidistant map of the dome about its lowest point, so `|g|` is
//! the geodesic distance from the pole and `g`'s direction is the azimuth in
//! the sensor frame. Pins sit on a flat hexagonal lattice in `g` (eq. S1)
//! or on concentric circles about the pole (eq. S1r).
use crate::config::{CameraConfig, PinLayout, SkinGeometry};

/// Surface coordinates of the skin's pins (mm) in the configured layout,
/// centre first, ring by ring, each ring counter-clockwise from the +x
/// axis.
pub fn skin_pins(g: &SkinGeometry) -> Vec<[f64; 2]> {
    match g.layout {
        PinLayout::Hex => hex_lattice(g.rings, g.pin_spacing_mm),
        PinLayout::Rings => concentric_rings(g.rings, g.pin_spacing_mm, &g.ring_phase_deg),
    }
}

/// Surface coordinates of pins on concentric circles, centre first, ring
/// by ring, each ring counter-clockwise from the +x axis (eq. S1r: ring
/// k = 1..=n has radius k s and 6k pins at angles phi_k + 60 j / k deg,
/// j = 0..6k). `phase_deg` holds phi_k per ring, innermost first; rings
/// beyond its end have phase 0.
pub fn concentric_rings(rings: usize, spacing_mm: f64, phase_deg: &[f64]) -> Vec<[f64; 2]> {
    let mut pins = Vec::with_capacity(pin_count(rings));
    pins.push([0.0, 0.0]);
    for k in 1..=rings {
        let count = 6 * k;
        let radius = k as f64 * spacing_mm;
        let phase = phase_deg.get(k - 1).copied().unwrap_or(0.0);
        let mut ring: Vec<(f64, [f64; 2])> = (0..count)
            .map(|j| {
                let a = (phase + 360.0 * j as f64 / count as f64).to_radians();
                let (sin, cos) = a.sin_cos();
                (
                    a.rem_euclid(std::f64::consts::TAU),
                    [radius * cos, radius * sin],
                )
            })
            .collect();
        ring.sort_by(|a, b| a.0.total_cmp(&b.0));
        pins.extend(ring.into_iter().map(|(_, g)| g));
    }
    pins
}

/// Surface coordinates of the pins, ring by ring (centre first), each ring
/// counter-clockwise from the +x axis; vertices of the hexagon point along
/// +-y (eq. S1: g = s (i a1 + j a2), a1 = (cos 30, sin 30), a2 = (0, 1)).
pub fn hex_lattice(rings: usize, spacing_mm: f64) -> Vec<[f64; 2]> {
    let n = rings as i64;
    let a1 = [30f64.to_radians().cos(), 30f64.to_radians().sin()];
    let mut pins: Vec<(i64, f64, [f64; 2])> = Vec::new();
    for i in -n..=n {
        for j in -n..=n {
            let ring = (i.abs() + j.abs() + (i + j).abs()) / 2;
            if ring > n {
                continue;
            }
            let g = [
                spacing_mm * (i as f64 * a1[0]),
                spacing_mm * (i as f64 * a1[1] + j as f64),
            ];
            let angle = g[1].atan2(g[0]).rem_euclid(std::f64::consts::TAU);
            pins.push((ring, angle, g));
        }
    }
    pins.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pins.into_iter().map(|(_, _, g)| g).collect()
}

/// Number of pins in a layout with `rings` rings (hexagonal or
/// concentric, 6k pins on ring k): 1 + 3 n (n + 1).
pub fn pin_count(rings: usize) -> usize {
    1 + 3 * rings * (rings + 1)
}

/// The dome and the pinhole camera on its axis.
#[derive(Debug, Clone)]
pub struct Projection {
    radius: f64,
    focal: f64,
    cam_height: f64,
    centre: [f64; 2],
    /// Rotation (cos, sin) of the sensor frame in the image.
    rot: [f64; 2],
    mirror: f64,
}

impl Projection {
    /// From validated skin and camera settings.
    pub fn new(skin: &SkinGeometry, camera: &CameraConfig) -> Self {
        let r = camera.rotation_deg.to_radians();
        Self {
            radius: skin.dome_radius_mm,
            focal: camera.focal_px,
            cam_height: camera.height_mm,
            centre: camera.centre_px,
            rot: [r.cos(), r.sin()],
            mirror: if camera.mirror { -1.0 } else { 1.0 },
        }
    }

    /// Horizontal position (mm, sensor frame) and height above the dome's
    /// lowest point (mm) of the skin point with surface coordinates `g`
    /// (eq. S2: rho = R sin(|g|/R), h = R (1 - cos(|g|/R))).
    pub fn skin_point(&self, g: [f64; 2]) -> ([f64; 2], f64) {
        let s = g[0].hypot(g[1]);
        if s < 1e-12 {
            return (g, 0.0);
        }
        let phi = s / self.radius;
        let rho = self.radius * phi.sin();
        let height = self.radius * (1.0 - phi.cos());
        ([g[0] * rho / s, g[1] * rho / s], height)
    }

    /// Image position (px) of the skin point `g` seen by the pinhole camera
    /// at height H on the axis (eq. S3: r_px = f rho / (H - h)).
    pub fn project(&self, g: [f64; 2]) -> [f64; 2] {
        self.project_lifted(g, 0.0)
    }

    /// As [`Self::project`] with the skin point pushed `lift` mm up towards
    /// the camera (eq. S8: r_px = f rho / (H - h - w)).
    pub fn project_lifted(&self, g: [f64; 2], lift: f64) -> [f64; 2] {
        let (q, skin_height) = self.skin_point(g);
        let h = skin_height + lift;
        let depth = (self.cam_height - h).max(1e-6);
        let k = self.focal / depth;
        let (x, y) = (k * q[0], self.mirror * k * q[1]);
        [
            self.centre[0] + self.rot[0] * x - self.rot[1] * y,
            self.centre[1] + self.rot[1] * x + self.rot[0] * y,
        ]
    }

    /// Local image scale at `g`, px per mm of skin (square root of the
    /// projection's Jacobian determinant, by central differences).
    pub fn scale(&self, g: [f64; 2]) -> f64 {
        let e = 1e-3;
        let dx = sub(
            self.project([g[0] + e, g[1]]),
            self.project([g[0] - e, g[1]]),
        );
        let dy = sub(
            self.project([g[0], g[1] + e]),
            self.project([g[0], g[1] - e]),
        );
        let det = (dx[0] * dy[1] - dx[1] * dy[0]).abs() / (4.0 * e * e);
        det.sqrt()
    }
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn six_rings_give_127_pins_centre_first() {
        let pins = hex_lattice(6, 3.0);
        assert_eq!(pins.len(), 127);
        assert_eq!(pin_count(6), 127);
        assert!(pins[0][0].abs() < 1e-12 && pins[0][1].abs() < 1e-12);
        for p in &pins[1..7] {
            assert!((p[0].hypot(p[1]) - 3.0).abs() < 1e-9);
        }
    }

    #[test]
    fn lattice_neighbours_are_one_spacing_apart() {
        let pins = hex_lattice(3, 2.5);
        for (i, a) in pins.iter().enumerate() {
            let nearest = pins
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                .fold(f64::INFINITY, f64::min);
            assert!((nearest - 2.5).abs() < 1e-9);
        }
    }
}
