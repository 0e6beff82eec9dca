//! Small geometric measures for the inspection: a circle fitted to pixels
//! (the rim of the dome), nearest-neighbour spacing and counts, the
//! six-fold orientational order of a pin set (hexagonal lattice or
//! concentric rings) and the rings of a ring layout.

use crate::preprocess::MaskCircle;

/// Least-squares circle through `points` (Kasa's algebraic fit:
/// `x^2 + y^2 + D x + E y + F = 0` linear in D, E, F), in coordinates
/// centred on the points' mean for conditioning. `None` for fewer than
/// three points or collinear ones.
pub(crate) fn fit_circle(points: &[[f64; 2]]) -> Option<MaskCircle> {
    if points.len() < 3 {
        return None;
    }
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p[0]).sum::<f64>() / n;
    let my = points.iter().map(|p| p[1]).sum::<f64>() / n;
    let (mut suu, mut svv, mut suv) = (0.0, 0.0, 0.0);
    let (mut suuu, mut svvv, mut suvv, mut svuu) = (0.0, 0.0, 0.0, 0.0);
    for p in points {
        let (u, v) = (p[0] - mx, p[1] - my);
        suu += u * u;
        svv += v * v;
        suv += u * v;
        suuu += u * u * u;
        svvv += v * v * v;
        suvv += u * v * v;
        svuu += v * u * u;
    }
    let det = suu * svv - suv * suv;
    if det.abs() <= 1e-9 * (suu * svv).max(1e-300) {
        return None;
    }
    let (a, b) = (0.5 * (suuu + suvv), 0.5 * (svvv + svuu));
    let uc = (a * svv - b * suv) / det;
    let vc = (b * suu - a * suv) / det;
    let radius = (uc * uc + vc * vc + (suu + svv) / n).sqrt();
    radius.is_finite().then_some(MaskCircle {
        centre: [mx + uc, my + vc],
        radius,
    })
}

/// Per point, the distance to its nearest other point (infinite alone).
pub(crate) fn nearest_distances(points: &[[f64; 2]]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_unstable_by(|&a, &b| points[a][0].total_cmp(&points[b][0]));
    let mut out = vec![f64::INFINITY; points.len()];
    for (k, &i) in order.iter().enumerate() {
        let p = points[i];
        let mut best = f64::INFINITY;
        for &j in &order[k + 1..] {
            if points[j][0] - p[0] >= best {
                break;
            }
            best = best.min(distance(p, points[j]));
        }
        for &j in order[..k].iter().rev() {
            if p[0] - points[j][0] >= best {
                break;
            }
            best = best.min(distance(p, points[j]));
        }
        out[i] = best;
    }
    out
}

/// Per point, how many other points lie within `reach`.
pub(crate) fn neighbour_counts(points: &[[f64; 2]], reach: f64) -> Vec<usize> {
    points
        .iter()
        .map(|&p| {
            points
                .iter()
                .filter(|&&q| q != p && distance(p, q) < reach)
                .count()
        })
        .collect()
}

pub(crate) fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Six-fold orientational order of a pin set, each 0..=1: per pin with at
/// least four neighbours within 1.4 `spacing`, `psi = mean exp(6 i theta)`
/// over the bonds to them, and the result `|sum psi| / sum |psi|`, with
/// `theta` the bond's direction in the frame (`lattice`) and relative to
/// the pin's direction from `centre` (`polar`). A hexagonal lattice has the
/// same bond directions everywhere: lattice order near 1 (also under a
/// smooth camera distortion), polar order near 0. On concentric rings the
/// bonds turn with the position around the centre: the polar order is the
/// higher of the two on the 331-pin sensor's rings (0.62-0.65 against
/// 0.80-0.83), and the lattice order falls well short of a lattice's
/// (0.996 on the 127-pin sensor).
pub(crate) fn orientational_order(points: &[[f64; 2]], spacing: f64, centre: [f64; 2]) -> Order {
    let reach = 1.4 * spacing;
    let mut lattice = Psi::default();
    let mut polar = Psi::default();
    for &p in points {
        let bonds: Vec<f64> = points
            .iter()
            .filter(|&&q| q != p && distance(p, q) < reach)
            .map(|q| (q[1] - p[1]).atan2(q[0] - p[0]))
            .collect();
        if bonds.len() < 4 {
            continue;
        }
        let phi = (p[1] - centre[1]).atan2(p[0] - centre[0]);
        lattice.add(&bonds, 0.0);
        polar.add(&bonds, phi);
    }
    Order {
        lattice: lattice.order(),
        polar: polar.order(),
    }
}

/// The two six-fold orders of [`orientational_order`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Order {
    pub lattice: f64,
    pub polar: f64,
}

/// Running sums of per-pin six-fold bond orders.
#[derive(Default)]
struct Psi {
    re: f64,
    im: f64,
    norm: f64,
}

impl Psi {
    fn add(&mut self, bonds: &[f64], phi: f64) {
        let k = bonds.len() as f64;
        let (r, i) = bonds.iter().fold((0.0, 0.0), |(r, i), &t| {
            let a = 6.0 * (t - phi);
            (r + a.cos() / k, i + a.sin() / k)
        });
        self.re += r;
        self.im += i;
        self.norm += r.hypot(i);
    }

    fn order(&self) -> f64 {
        if self.norm == 0.0 {
            0.0
        } else {
            self.re.hypot(self.im) / self.norm
        }
    }
}

/// The rings of a ring layout around `centre`: the pins' distances to it,
/// sorted, split where consecutive distances differ by more than
/// `0.4 spacing`; returns the number of pins on each ring, innermost
/// first (a centre pin counts as a ring of one).
pub(crate) fn rings(points: &[[f64; 2]], centre: [f64; 2], spacing: f64) -> Vec<usize> {
    let mut radii: Vec<f64> = points.iter().map(|&p| distance(p, centre)).collect();
    radii.sort_unstable_by(f64::total_cmp);
    let mut out = Vec::new();
    let mut count = 0;
    for (k, r) in radii.iter().enumerate() {
        if k > 0 && r - radii[k - 1] > 0.4 * spacing {
            out.push(count);
            count = 0;
        }
        count += 1;
    }
    if count > 0 {
        out.push(count);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_through_points_of_a_circle_and_an_arc() {
        for span in [std::f64::consts::TAU, 1.5] {
            let points: Vec<[f64; 2]> = (0..40)
                .map(|k| {
                    let t = span * f64::from(k) / 40.0;
                    [30.0 + 12.5 * t.cos(), -4.0 + 12.5 * t.sin()]
                })
                .collect();
            let c = fit_circle(&points).expect("circle");
            assert!((c.centre[0] - 30.0).abs() < 1e-9 && (c.centre[1] + 4.0).abs() < 1e-9);
            assert!((c.radius - 12.5).abs() < 1e-9);
        }
        assert!(fit_circle(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).is_none());
    }

    #[test]
    fn nearest_distances_match_brute_force() {
        let points: Vec<[f64; 2]> = (0..50)
            .map(|k| {
                let k = f64::from(k);
                [(k * 7.3) % 13.0, (k * 3.1) % 11.0]
            })
            .collect();
        let fast = nearest_distances(&points);
        for (i, &p) in points.iter().enumerate() {
            let slow = points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &q)| distance(p, q))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(fast[i], slow);
        }
    }
}
