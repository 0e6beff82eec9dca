//! Shape measures of one traced contour, as OpenCV's blob detector computes
//! them (report ch. 4.1): polygon moments (Green's theorem over the boundary
//! pixel centres), perimeter, circularity, inertia ratio, convex-hull
//! convexity and the median boundary radius.

/// Raw and central moments of a closed polygon, up to second order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    pub m00: f64,
    pub m10: f64,
    pub m01: f64,
    pub mu20: f64,
    pub mu11: f64,
    pub mu02: f64,
}

impl Moments {
    /// Moments of the polygon through `points` (closed). The area is taken
    /// positive whatever the orientation; a degenerate polygon (area below
    /// f32 epsilon) has all moments zero, as in OpenCV's `moments`.
    pub fn of_polygon(points: &[[i32; 2]]) -> Self {
        let mut a = [0.0f64; 6];
        let mut prev = match points.last() {
            Some(&[x, y]) => (f64::from(x), f64::from(y)),
            None => return Self::default(),
        };
        for &[x, y] in points {
            let (xi, yi) = prev;
            let (xj, yj) = (f64::from(x), f64::from(y));
            let cross = xi * yj - xj * yi;
            a[0] += cross;
            a[1] += cross * (xi + xj);
            a[2] += cross * (yi + yj);
            a[3] += cross * (xi * xi + xi * xj + xj * xj);
            a[4] += cross * (xi * (2.0 * yi + yj) + xj * (yi + 2.0 * yj));
            a[5] += cross * (yi * yi + yi * yj + yj * yj);
            prev = (xj, yj);
        }
        if a[0].abs() <= f64::from(f32::EPSILON) {
            return Self::default();
        }
        let sign = a[0].signum();
        let m00 = sign * a[0] / 2.0;
        let m10 = sign * a[1] / 6.0;
        let m01 = sign * a[2] / 6.0;
        let (m20, m11, m02) = (sign * a[3] / 12.0, sign * a[4] / 24.0, sign * a[5] / 12.0);
        let (cx, cy) = (m10 / m00, m01 / m00);
        Self {
            m00,
            m10,
            m01,
            mu20: m20 - m10 * cx,
            mu11: m11 - m10 * cy,
            mu02: m02 - m01 * cy,
        }
    }

    /// Smallest over largest principal second moment (1 for a disc, 0 for a
    /// line); 1 when the moments are isotropic to within 1e-2, as OpenCV.
    pub fn inertia_ratio(&self) -> f64 {
        let spread = (self.mu20 - self.mu02).hypot(2.0 * self.mu11);
        if spread > 1e-2 {
            let sum = self.mu20 + self.mu02;
            (sum - spread) / (sum + spread)
        } else {
            1.0
        }
    }
}

/// Length of the closed polyline through `points` (OpenCV `arcLength(.., true)`).
pub fn perimeter(points: &[[i32; 2]]) -> f64 {
    let Some(&last) = points.last() else {
        return 0.0;
    };
    let mut prev = last;
    let mut total = 0.0;
    for &p in points {
        let dx = f64::from(p[0] - prev[0]);
        let dy = f64::from(p[1] - prev[1]);
        total += dx.hypot(dy);
        prev = p;
    }
    total
}

/// Circularity 4 pi A / P^2 (1 for a disc).
pub fn circularity(area: f64, perimeter: f64) -> f64 {
    4.0 * std::f64::consts::PI * area / (perimeter * perimeter)
}

/// Area of the convex hull of `points` (Andrew's monotone chain).
pub fn hull_area(points: &[[i32; 2]]) -> f64 {
    let mut sorted: Vec<[i64; 2]> = points
        .iter()
        .map(|&[x, y]| [i64::from(x), i64::from(y)])
        .collect();
    sorted.sort_unstable();
    sorted.dedup();
    if sorted.len() < 3 {
        return 0.0;
    }
    let lower = half_hull(sorted.iter());
    let upper = half_hull(sorted.iter().rev());
    let hull = lower[..lower.len() - 1]
        .iter()
        .chain(&upper[..upper.len() - 1]);
    let ring: Vec<[i64; 2]> = hull.copied().collect();
    let mut twice_area = 0i64;
    for (i, p) in ring.iter().enumerate() {
        let q = ring[(i + 1) % ring.len()];
        twice_area += p[0] * q[1] - q[0] * p[1];
    }
    twice_area.abs() as f64 / 2.0
}

/// One monotone half of the hull, keeping only strict left turns.
fn half_hull<'a>(points: impl Iterator<Item = &'a [i64; 2]>) -> Vec<[i64; 2]> {
    let mut chain: Vec<[i64; 2]> = Vec::new();
    for &p in points {
        while chain.len() >= 2 && turn(chain[chain.len() - 2], chain[chain.len() - 1], p) <= 0 {
            chain.pop();
        }
        chain.push(p);
    }
    chain
}

fn turn(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Median distance from `centre` to the contour points (mean of the two
/// middle values for an even count): OpenCV's blob radius.
pub fn median_radius(points: &[[i32; 2]], centre: [f64; 2], scratch: &mut Vec<f64>) -> f64 {
    scratch.clear();
    scratch.extend(
        points
            .iter()
            .map(|&[x, y]| (f64::from(x) - centre[0]).hypot(f64::from(y) - centre[1])),
    );
    if scratch.is_empty() {
        return 0.0;
    }
    scratch.sort_unstable_by(f64::total_cmp);
    let n = scratch.len();
    (scratch[(n - 1) / 2] + scratch[n / 2]) / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE: [[i32; 2]; 4] = [[0, 0], [0, 4], [4, 4], [4, 0]];

    #[test]
    fn square_moments_match_closed_form() {
        let m = Moments::of_polygon(&SQUARE);
        assert!((m.m00 - 16.0).abs() < 1e-12);
        assert!((m.m10 / m.m00 - 2.0).abs() < 1e-12);
        assert!((m.m01 / m.m00 - 2.0).abs() < 1e-12);
        // mu20 of a side-a square is a^4 / 12.
        assert!((m.mu20 - 256.0 / 12.0).abs() < 1e-9);
        assert!(m.mu11.abs() < 1e-9);
        assert!((m.inertia_ratio() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn orientation_does_not_change_moments() {
        let mut reversed = SQUARE;
        reversed.reverse();
        assert_eq!(Moments::of_polygon(&SQUARE), Moments::of_polygon(&reversed));
    }

    #[test]
    fn rectangle_inertia_ratio_is_squared_aspect() {
        // Second moments of a w x h rectangle scale as w^2 and h^2.
        let rect = [[0, 0], [0, 2], [6, 2], [6, 0]];
        let ratio = Moments::of_polygon(&rect).inertia_ratio();
        assert!((ratio - 1.0 / 9.0).abs() < 1e-12);
    }

    #[test]
    fn hull_of_an_l_shape_fills_the_notch() {
        let l_shape = [[0, 0], [0, 4], [4, 4], [4, 2], [2, 2], [2, 0]];
        assert!((hull_area(&l_shape) - 14.0).abs() < 1e-12);
        assert!((Moments::of_polygon(&l_shape).m00 - 12.0).abs() < 1e-12);
    }

    #[test]
    fn perimeter_and_circularity_of_a_square() {
        assert!((perimeter(&SQUARE) - 16.0).abs() < 1e-12);
        let c = circularity(16.0, 16.0);
        assert!((c - std::f64::consts::PI / 4.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_polygons_have_zero_moments() {
        assert_eq!(Moments::of_polygon(&[[3, 3]]), Moments::default());
        assert_eq!(Moments::of_polygon(&[]), Moments::default());
        assert_eq!(hull_area(&[[0, 0], [1, 1], [2, 2]]), 0.0);
    }
}
