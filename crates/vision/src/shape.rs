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
        Self::of_sums(a)
    }

    /// The moments from the polygon's six edge sums (`a[0]`: twice the
    /// signed area; then x, y, x^2, xy and y^2, as summed by
    /// [`Moments::of_polygon`]), either orientation.
    pub(crate) fn of_sums(a: [f64; 6]) -> Self {
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
/// Steps between 8-neighbours (all steps of a traced border) take their
/// length from a table holding exactly what `hypot` gives; the sum runs in
/// the same order, so the result is the same as summing `hypot` per step.
pub fn perimeter(points: &[[i32; 2]]) -> f64 {
    let Some(&last) = points.last() else {
        return 0.0;
    };
    // SQRT_2 is what `1.0f64.hypot(1.0)` gives (a test checks it).
    let steps = [0.0, 1.0, std::f64::consts::SQRT_2];
    let mut prev = last;
    let mut total = 0.0;
    for &p in points {
        let (dx, dy) = (p[0] - prev[0], p[1] - prev[1]);
        total += if dx.abs() <= 1 && dy.abs() <= 1 {
            steps[(dx * dx + dy * dy) as usize]
        } else {
            f64::from(dx).hypot(f64::from(dy))
        };
        prev = p;
    }
    total
}

/// The length of a closed border of `points` points whose steps (from
/// each point to the next, and from the last to the first) are all one
/// pixel along an axis or diagonal, `diagonal` of them diagonal: the exact
/// sum `(points - diagonal) + diagonal sqrt 2` rounded twice, where
/// [`perimeter`] rounds once a step. The two differ by at most
/// `(points + 2) u` relatively (u = 2^-53, the error bound of a sum of
/// positive terms), so they can decide a filter only where its value lies
/// outside that margin of the bound (`blob.rs`). A lone pixel has length 0.
pub fn perimeter_of_steps(points: usize, diagonal: usize) -> f64 {
    if points < 2 {
        return 0.0;
    }
    (points - diagonal) as f64 + diagonal as f64 * std::f64::consts::SQRT_2
}

/// Circularity 4 pi A / P^2 (1 for a disc).
pub fn circularity(area: f64, perimeter: f64) -> f64 {
    4.0 * std::f64::consts::PI * area / (perimeter * perimeter)
}

/// Reusable buffers for [`hull_area_with`].
#[derive(Default)]
pub struct HullScratch {
    rows: Vec<[i32; 2]>,
    sorted: Vec<[i64; 2]>,
    chain: Vec<[i64; 2]>,
}

/// Area of the convex hull of `points` (Andrew's monotone chain).
#[cfg(test)]
pub fn hull_area(points: &[[i32; 2]]) -> f64 {
    hull_area_with(points, &mut HullScratch::default())
}

/// [`hull_area`] with caller-owned buffers. Only the leftmost and rightmost
/// point of each row can be hull vertices (the others lie on the segment
/// between them), so the chain runs over those, already sorted by (y, x):
/// no sort, and the same hull (integer area) as over all points.
pub fn hull_area_with(points: &[[i32; 2]], s: &mut HullScratch) -> f64 {
    let Some(y0) = points.iter().map(|p| p[1]).min() else {
        return 0.0;
    };
    let y1 = points.iter().map(|p| p[1]).max().unwrap_or(y0);
    s.rows.clear();
    s.rows.resize((y1 - y0) as usize + 1, [i32::MAX, i32::MIN]);
    for &[x, y] in points {
        let r = &mut s.rows[(y - y0) as usize];
        *r = [r[0].min(x), r[1].max(x)];
    }
    s.sorted.clear();
    for (dy, &[lo, hi]) in s.rows.iter().enumerate() {
        if lo > hi {
            continue;
        }
        let y = i64::from(y0) + dy as i64;
        s.sorted.push([y, i64::from(lo)]);
        if hi > lo {
            s.sorted.push([y, i64::from(hi)]);
        }
    }
    if s.sorted.len() < 3 {
        return 0.0;
    }
    // Points are (y, x): a mirror image of the set, with the same hull area.
    let mut twice_area = 0i64;
    for upper in [false, true] {
        s.chain.clear();
        let mut push = |p: [i64; 2]| {
            while s.chain.len() >= 2
                && turn(s.chain[s.chain.len() - 2], s.chain[s.chain.len() - 1], p) <= 0
            {
                s.chain.pop();
            }
            s.chain.push(p);
        };
        if upper {
            s.sorted.iter().rev().for_each(|&p| push(p));
        } else {
            s.sorted.iter().for_each(|&p| push(p));
        }
        // Shoelace over this half's edges; the two halves close the ring.
        for w in s.chain.windows(2) {
            twice_area += w[0][0] * w[1][1] - w[1][0] * w[0][1];
        }
    }
    twice_area.abs() as f64 / 2.0
}

/// An upper bound on [`hull_area`] in O(n): the area of the octagon cut
/// from the bounding box by the extreme values of x + y and x - y, which
/// holds every point and so their hull. Infinite when the corner cuts
/// overlap (the formula would not be the octagon's area then).
pub fn hull_area_upper_bound(points: &[[i32; 2]]) -> f64 {
    let Some(&[x, y]) = points.first() else {
        return f64::INFINITY;
    };
    let mut octagon = Octagon::row(y, x, x);
    for &[x, y] in points {
        octagon.add_row(y, x, x);
    }
    octagon.area()
}

/// The extreme values of x, y, x + y and x - y over a set of pixels,
/// `[min, max]` each: the octagon of [`hull_area_upper_bound`]. Taken
/// over a hole-free component's pixels it is the one of its outer border
/// (every extreme pixel has a background 4-neighbour, so lies on it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Octagon {
    pub x: [i64; 2],
    pub y: [i64; 2],
    pub sum: [i64; 2],
    pub diff: [i64; 2],
}

impl Octagon {
    /// The octagon of pixels `x0..=x1` of row `y`.
    pub fn row(y: i32, x0: i32, x1: i32) -> Self {
        let (y, x0, x1) = (i64::from(y), i64::from(x0), i64::from(x1));
        Self {
            x: [x0, x1],
            y: [y, y],
            sum: [x0 + y, x1 + y],
            diff: [x0 - y, x1 - y],
        }
    }

    /// Adds pixels `x0..=x1` of row `y` (x0 <= x1): their extremes are at
    /// the ends.
    pub fn add_row(&mut self, y: i32, x0: i32, x1: i32) {
        let (y, x0, x1) = (i64::from(y), i64::from(x0), i64::from(x1));
        self.x = [self.x[0].min(x0), self.x[1].max(x1)];
        self.y = [self.y[0].min(y), self.y[1].max(y)];
        self.sum = [self.sum[0].min(x0 + y), self.sum[1].max(x1 + y)];
        self.diff = [self.diff[0].min(x0 - y), self.diff[1].max(x1 - y)];
    }

    /// Adds every pixel of `other`: the extremes of both.
    pub fn merge(&mut self, other: &Self) {
        let lo_hi = |a: [i64; 2], b: [i64; 2]| [a[0].min(b[0]), a[1].max(b[1])];
        self.x = lo_hi(self.x, other.x);
        self.y = lo_hi(self.y, other.y);
        self.sum = lo_hi(self.sum, other.sum);
        self.diff = lo_hi(self.diff, other.diff);
    }

    /// The octagon's area (infinite when its corner cuts overlap).
    pub fn area(&self) -> f64 {
        let ([x0, x1], [y0, y1]) = (self.x, self.y);
        let ([s0, s1], [d0, d1]) = (self.sum, self.diff);
        octagon_area([x0, x1, y0, y1], [s0, s1, d0, d1])
    }
}

/// The area of the box `[x0, x1, y0, y1]` with its corners cut by the
/// lines x + y = s0, s1 and x - y = d0, d1 (`[s0, s1, d0, d1]`);
/// infinite when the cuts overlap.
fn octagon_area([x0, x1, y0, y1]: [i64; 4], [s0, s1, d0, d1]: [i64; 4]) -> f64 {
    let (w, h) = (x1 - x0, y1 - y0);
    // Legs of the corner triangles cut off: top-left, top-right,
    // bottom-left, bottom-right (y down).
    let (tl, tr) = (s0 - (x0 + y0), (x1 - y0) - d1);
    let (bl, br) = (d0 - (x0 - y1), (x1 + y1) - s1);
    if tl + tr > w || bl + br > w || tl + bl > h || tr + br > h {
        return f64::INFINITY;
    }
    let twice = 2 * w * h - tl * tl - tr * tr - bl * bl - br * br;
    twice as f64 / 2.0
}

fn turn(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Reusable buffers for [`median_radius`].
#[derive(Default)]
pub struct MedianScratch {
    keys: Vec<u64>,
    window: Vec<u64>,
    band: Vec<f64>,
}

/// Median distance from `centre` to the contour points (mean of the two
/// middle values for an even count): OpenCV's blob radius, as the values
/// `hypot` gives. The middle ranks are selected on squared distances (by
/// their bit patterns, which order finite non-negative floats as their
/// values; first within a window about their mean, `middle_keys`);
/// only the points whose squared distance is within a relative
/// 1e-9 of the middle ones (far above rounding error, so every other point
/// is surely nearer or farther) get `hypot`, and the exact middle values
/// are picked among those.
pub fn median_radius(points: &[[i32; 2]], centre: [f64; 2], s: &mut MedianScratch) -> f64 {
    let n = points.len();
    if n == 0 {
        return 0.0;
    }
    if !(centre[0].is_finite() && centre[1].is_finite()) {
        return exact_median(points, centre, &mut s.band);
    }
    let offsets = |&[x, y]: &[i32; 2]| (f64::from(x) - centre[0], f64::from(y) - centre[1]);
    s.keys.clear();
    let mut sum = 0.0;
    s.keys.extend(points.iter().map(offsets).map(|(dx, dy)| {
        let d2 = dx * dx + dy * dy;
        sum += d2;
        d2.to_bits()
    }));
    let (lower_rank, upper_rank) = ((n - 1) / 2, n / 2);
    let ranks = [lower_rank, upper_rank];
    let (lower_bits, upper_bits) = middle_keys(&mut s.keys, sum / n as f64, ranks, &mut s.window);
    let (lower_d2, upper_d2) = (f64::from_bits(lower_bits), f64::from_bits(upper_bits));
    if !(lower_d2.is_finite() && upper_d2.is_finite()) {
        return exact_median(points, centre, &mut s.band);
    }
    let scratch = &mut s.band;
    let (lo, hi) = (lower_d2 * (1.0 - 1e-9), upper_d2 * (1.0 + 1e-9));
    let mut nearer = 0;
    scratch.clear();
    for p in points {
        let (dx, dy) = offsets(p);
        let d2 = dx * dx + dy * dy;
        if d2 < lo {
            nearer += 1;
        } else if d2 <= hi {
            scratch.push(dx.hypot(dy));
        }
    }
    scratch.sort_unstable_by(f64::total_cmp);
    (scratch[lower_rank - nearer] + scratch[upper_rank - nearer]) / 2.0
}

/// The keys (bit patterns of finite non-negative squared distances) of
/// ranks `lower` and `upper` among `keys`, whose values' mean is `mean`.
/// First from a window of +-10 % about the mean, which on a blob's
/// border (every point near one radius) holds both middle ranks and few
/// other keys: the keys below it counted, those in it sorted. Else (the
/// window misses a rank) by a selection over all keys. The same keys
/// either way (`median_radius_matches_sorting` and the random sets'
/// test reach both).
fn middle_keys(
    keys: &mut [u64],
    mean: f64,
    [lower, upper]: [usize; 2],
    window: &mut Vec<u64>,
) -> (u64, u64) {
    let (lo, hi) = ((mean * 0.9).to_bits(), (mean * 1.1).to_bits());
    let mut under = 0;
    window.clear();
    for &key in keys.iter() {
        if key < lo {
            under += 1;
        } else if key <= hi {
            window.push(key);
        }
    }
    if mean.is_finite() && under <= lower && under + window.len() > upper {
        window.sort_unstable();
        return (window[lower - under], window[upper - under]);
    }
    let (below, &mut upper_key, _) = keys.select_nth_unstable(upper);
    let lower_key = if lower == upper {
        upper_key
    } else {
        below.iter().copied().max().unwrap_or(upper_key)
    };
    (lower_key, upper_key)
}

/// The median of all `hypot` distances by sorting (reference definition).
fn exact_median(points: &[[i32; 2]], centre: [f64; 2], scratch: &mut Vec<f64>) -> f64 {
    scratch.clear();
    scratch.extend(
        points
            .iter()
            .map(|&[x, y]| (f64::from(x) - centre[0]).hypot(f64::from(y) - centre[1])),
    );
    scratch.sort_unstable_by(f64::total_cmp);
    let n = scratch.len();
    (scratch[(n - 1) / 2] + scratch[n / 2]) / 2.0
}

#[cfg(test)]
mod tests;
