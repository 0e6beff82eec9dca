//! Synthetic TacTips whose truth is known: the rest pins of the two layouts
//! a TacTip's pins come in (a hexagonal lattice, concentric rings), in
//! pixels of a square frame, with the rim annulus the camera sees around
//! them. The vision crate's tests and the binary's tests draw their taps
//! over the same two sensors; how each draws a frame is its own.

/// A synthetic sensor as its camera sees it (pixels): frame size, centre,
/// rest pins, pin radius, rim annulus and static one-pixel specks.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticSensor {
    /// Width and height of the square frame (px).
    pub size: u32,
    /// Centre of the layout and of the rim (px).
    pub centre: [f64; 2],
    /// The pins at rest (px), centre pin first.
    pub rest: Vec<[f64; 2]>,
    /// Radius of a drawn pin (px).
    pub pin_radius: f64,
    /// Rim annulus: inner and outer radius (px).
    pub rim: [f64; 2],
    /// Static specks between the pins and the rim (px), for renderers
    /// that draw dirt.
    pub specks: Vec<[f64; 2]>,
}

/// The pins of a hexagonal lattice of `shells` shells around a centre pin
/// at `centre`, `spacing` px apart: axial coordinates (q, r) with
/// |q + r| <= shells, at x = c_x + s (q + r / 2), y = c_y + s (sqrt(3) / 2) r;
/// 1 + 3 shells (shells + 1) pins (127 for 6, 331 for 10).
pub fn hex_lattice(centre: [f64; 2], spacing: f64, shells: i32) -> Vec<[f64; 2]> {
    let mut pins = Vec::new();
    for q in -shells..=shells {
        for r in -shells..=shells {
            if (q + r).abs() <= shells {
                let x = centre[0] + spacing * (f64::from(q) + 0.5 * f64::from(r));
                let y = centre[1] + spacing * 0.75f64.sqrt() * f64::from(r);
                pins.push([x, y]);
            }
        }
    }
    pins
}

/// The pins of concentric rings around a centre pin: ring k = 1..=`rings`
/// holds 6k pins at radius `step` k, turned by `twist` k rad so that no
/// spoke is straight; 1 + 3 rings (rings + 1) pins (331 for 10).
pub fn concentric_rings(centre: [f64; 2], rings: u32, step: f64, twist: f64) -> Vec<[f64; 2]> {
    let mut pins = vec![centre];
    for k in 1..=rings {
        for j in 0..6 * k {
            let t = std::f64::consts::TAU * f64::from(j) / f64::from(6 * k) + twist * f64::from(k);
            let r = step * f64::from(k);
            pins.push([centre[0] + r * t.cos(), centre[1] + r * t.sin()]);
        }
    }
    pins
}

/// 331 pins on ten concentric rings 4.8 px apart (turned 0.05 rad a ring)
/// in 128 x 128 frames; pins of radius 1.45 px, rim at 55-62 px, four
/// specks at 53 px.
pub fn ring_sensor() -> SyntheticSensor {
    let centre = [63.6, 63.3];
    let specks = [0.4f64, 1.9, 3.3, 4.6]
        .iter()
        .map(|t| [centre[0] + 53.0 * t.cos(), centre[1] + 53.0 * t.sin()])
        .collect();
    SyntheticSensor {
        size: 128,
        centre,
        rest: concentric_rings(centre, 10, 4.8, 0.05),
        pin_radius: 1.45,
        rim: [55.0, 62.0],
        specks,
    }
}

/// 127 pins on a hexagonal lattice of six shells 14 px apart in 256 x 256
/// frames; pins of radius 3.4 px, rim at 118-126 px, two specks.
pub fn hex_sensor() -> SyntheticSensor {
    let centre = [128.4, 127.7];
    SyntheticSensor {
        size: 256,
        centre,
        rest: hex_lattice(centre, 14.0, 6),
        pin_radius: 3.4,
        rim: [118.0, 126.0],
        specks: vec![[40.0, 40.0], [215.0, 220.0]],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pin_counts_follow_the_shell_formula() {
        assert_eq!(ring_sensor().rest.len(), 331);
        assert_eq!(hex_sensor().rest.len(), 127);
        assert_eq!(hex_lattice([0.0, 0.0], 1.0, 10).len(), 331);
    }

    #[test]
    fn neighbours_are_one_spacing_apart() {
        let pins = hex_lattice([0.0, 0.0], 14.0, 6);
        let centre = pins[pins.len() / 2];
        assert_eq!(centre, [0.0, 0.0]);
        let near = pins
            .iter()
            .filter(|p| ((p[0] - centre[0]).hypot(p[1] - centre[1]) - 14.0).abs() < 1e-9)
            .count();
        assert_eq!(near, 6);
        let rings = concentric_rings([0.0, 0.0], 3, 4.8, 0.05);
        for (k, first) in [(1, 1), (2, 7), (3, 19)] {
            let p = rings[first];
            assert!((p[0].hypot(p[1]) - 4.8 * f64::from(k)).abs() < 1e-9);
        }
    }

    #[test]
    fn every_pin_lies_inside_the_rim() {
        for s in [ring_sensor(), hex_sensor()] {
            for p in &s.rest {
                assert!((p[0] - s.centre[0]).hypot(p[1] - s.centre[1]) < s.rim[0]);
            }
        }
    }
}
