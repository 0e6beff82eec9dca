//! The outer border of a component with one run a row (a "chain" of runs,
//! as nearly every pin of a binarised TacTip frame is), written from its
//! runs without walking it (report ch. 4.1: the blob detector's contours).
//! The walk from the component's first pixel (`ContourScanner::
//! outer_border_at`, OpenCV's border following) goes down the left side,
//! along the bottom row, up the right side and back along the top row;
//! between two rows it takes the tightest path through border pixels, so
//! where a side moves by `d` pixels from one row to the next it steps
//! `|d| - 1` pixels along the row that reaches farther and one pixel
//! diagonally (one pixel straight down or up where `d = 0`). The points
//! here are the walk's, in the walk's order, so every measurement made
//! from them (polygon moments summed in order, perimeter, median radius)
//! is the walk's bit for bit; the tests walk random components and
//! compare.

use crate::runs::Run;
use crate::shape::Moments;

/// The border points of the component whose runs, one a row over
/// consecutive rows from the top, are `runs` (non-empty), into `points`
/// (cleared first): the points of the outer border walked from the first
/// run's first pixel, in order. Returns how many of the border's steps
/// (from each point to the next, and from the last back to the first) are
/// diagonal.
pub(crate) fn chain_border(runs: &[Run], points: &mut Vec<[i32; 2]>) -> usize {
    points.clear();
    let (Some(first), Some(last)) = (runs.first(), runs.last()) else {
        return 0;
    };
    points.reserve(border_len(runs).max(1));
    let mut diagonal = 0;
    // Down the left side.
    for pair in runs.windows(2) {
        let (y, a, b) = (pair[0].y as i32, pair[0].x0 as i32, pair[1].x0 as i32);
        if b < a {
            // One pixel diagonally down, then left along the lower row.
            points.push([a, y]);
            let mut x = a - 1;
            while x > b {
                points.push([x, y + 1]);
                x -= 1;
            }
        } else {
            // Right along the upper row, then one pixel diagonally down
            // (or straight down where the sides line up).
            for x in a..b.max(a + 1) {
                points.push([x, y]);
            }
        }
        diagonal += usize::from(a != b);
    }
    // Along the bottom row, left to right.
    let y = last.y as i32;
    for x in last.x0 as i32..last.x1 as i32 {
        points.push([x, y]);
    }
    // Up the right side.
    for pair in runs.windows(2).rev() {
        let (y, a, b) = (pair[1].y as i32, pair[1].x1 as i32, pair[0].x1 as i32);
        if b > a {
            // One pixel diagonally up, then right along the upper row.
            points.push([a, y]);
            for x in a + 1..b {
                points.push([x, y - 1]);
            }
        } else {
            // Left along the lower row, then one pixel diagonally up (or
            // straight up where the sides line up).
            let mut x = a;
            while x > b.min(a - 1) {
                points.push([x, y]);
                x -= 1;
            }
        }
        diagonal += usize::from(a != b);
    }
    // Back along the top row, right to left, to the first pixel.
    let y = first.y as i32;
    let mut x = first.x1 as i32;
    while x > first.x0 as i32 {
        points.push([x, y]);
        x -= 1;
    }
    if points.is_empty() {
        // A lone pixel: its border is that one point, with no step.
        points.push([first.x0 as i32, y]);
    }
    diagonal
}

/// How many steps the border of [`chain_border`] has: a side that moves
/// by `d` between two rows takes `max(|d|, 1)`, the bottom and top rows
/// their widths less one.
pub(crate) fn border_len(runs: &[Run]) -> usize {
    let width = |r: &Run| (r.x1 - r.x0) as usize;
    let moved = |a: u32, b: u32| a.abs_diff(b).max(1) as usize;
    let sides: usize = runs
        .windows(2)
        .map(|p| moved(p[0].x0, p[1].x0) + moved(p[0].x1, p[1].x1))
        .sum();
    sides + runs.first().map_or(0, width) + runs.last().map_or(0, width)
}

/// The polygon moments of the border of [`chain_border`], without its
/// points: the same numbers, bit for bit, as `Moments::of_polygon` of
/// those points, or `None` where that cannot be promised. The polygon's
/// edge sums are integers (its vertices are), so where every partial
/// sum stays under 2^53 in magnitude the floating-point sums are exact,
/// in any order and over any polygon enclosing the same region: the
/// border encloses, between each two rows, the trapezoid from the
/// sides' diagonal steps (`trapezoid_sums`), and its back-and-forth
/// parts enclose nothing. These integer sums are those of the
/// trapezoids.
pub(crate) fn chain_moments(runs: &[Run]) -> Option<Moments> {
    let rows = runs.len() as f64;
    let far = runs.iter().map(|r| r.x1).max()?.max(runs[runs.len() - 1].y) as f64 + 1.0;
    // Every step of the border is one pixel, so an edge's cross product
    // is at most 2 far and its terms at most 12 far^3; the border has at
    // most (rows + 1)(2 far + 2) edges.
    let edges = (rows + 1.0) * (2.0 * far + 2.0);
    if far > 4096.0 || edges * 12.0 * far.powi(3) >= 2f64.powi(53) {
        return None;
    }
    let mut a = [0i64; 6];
    for pair in runs.windows(2) {
        let (upper, lower) = (pair[0], pair[1]);
        let ([x0, x1], [u0, u1]) = (
            [upper.x0, upper.x1].map(i64::from),
            [lower.x0, lower.x1].map(i64::from),
        );
        // Where a side moves, the border's diagonal step is at the row
        // that reaches less far.
        let top = [x0.max(u0 - 1), x1.min(u1 + 1)];
        let bottom = [u0.max(x0 - 1), u1.min(x1 + 1)];
        let t = trapezoid_sums(top, bottom, i64::from(upper.y));
        a.iter_mut().zip(t).for_each(|(sum, v)| *sum += v);
    }
    Some(Moments::of_sums(a.map(|v| v as f64)))
}

/// The six sums of `Moments::of_polygon` (twice the area; 6, 6, 12, 24
/// and 12 times the moments in x, y, x^2, xy and y^2) of the trapezoid
/// with corners `(top[0], y)`, `(top[1], y)`, `(bottom[1], y + 1)`,
/// `(bottom[0], y + 1)`, counter-clockwise in the image (area
/// positive): the integrals over it of the sides `L(t)`, `R(t)` linear
/// in `t` from row `y` to `y + 1`, in closed form.
fn trapezoid_sums([a, b]: [i64; 2], [c, d]: [i64; 2], y: i64) -> [i64; 6] {
    let (top, bottom) = (b - a, d - c);
    let area2 = top + bottom;
    // int R^2 dt = (b^2 + bd + d^2) / 3, int R^3 dt = (b + d)(b^2 + d^2) / 4,
    // int t R^2 dt = (b^2 + 2bd + 3d^2) / 12; the same for L with a, c.
    let x6 = (b * b + b * d + d * d) - (a * a + a * c + c * c);
    let xx12 = (b + d) * (b * b + d * d) - (a + c) * (a * a + c * c);
    let tx12 = (b * b + 2 * b * d + 3 * d * d) - (a * a + 2 * a * c + 3 * c * c);
    [
        area2,
        x6,
        3 * y * area2 + top + 2 * bottom,
        xx12,
        4 * y * x6 + tx12,
        6 * y * y * area2 + 4 * y * top + 8 * y * bottom + top + 3 * bottom,
    ]
}

/// How many of the steps of [`chain_border`] are diagonal: one for each
/// side that moves between two rows.
pub(crate) fn diagonal_steps(runs: &[Run]) -> usize {
    runs.windows(2)
        .map(|p| usize::from(p[0].x0 != p[1].x0) + usize::from(p[0].x1 != p[1].x1))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn runs_of(rows: &[(u32, u32)]) -> Vec<Run> {
        rows.iter()
            .enumerate()
            .map(|(y, &(x0, x1))| Run {
                y: y as u32 + 3,
                x0,
                x1,
            })
            .collect()
    }

    #[test]
    fn a_lone_pixel_and_a_single_row_go_out_and_back() {
        let mut points = Vec::new();
        assert_eq!(chain_border(&runs_of(&[(4, 4)]), &mut points), 0);
        assert_eq!(points, [[4, 3]]);
        assert_eq!(chain_border(&runs_of(&[(1, 4)]), &mut points), 0);
        assert_eq!(points, [[1, 3], [2, 3], [3, 3], [4, 3], [3, 3], [2, 3]]);
    }

    #[test]
    fn a_square_is_walked_down_its_left_side_first() {
        let mut points = Vec::new();
        assert_eq!(chain_border(&runs_of(&[(0, 1), (0, 1)]), &mut points), 0);
        assert_eq!(points, [[0, 3], [0, 4], [1, 4], [1, 3]]);
    }

    /// Random chains of runs (each row's run touching the one above,
    /// sides moving by up to five pixels, one-pixel-wide and diagonal
    /// links included): the moments without the points are those of the
    /// written points, bit for bit, and the diagonal steps are counted.
    #[test]
    fn moments_from_the_runs_are_the_polygons_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2212);
        let mut points = Vec::new();
        let bits = |m: Moments| [m.m00, m.m10, m.m01, m.mu20, m.mu11, m.mu02].map(f64::to_bits);
        for _ in 0..3000 {
            let (mut x0, mut x1) = (rng.random_range(0..200i64), 0);
            x1 += x0 + rng.random_range(0..8);
            let y0 = rng.random_range(0..200u32);
            let mut runs = Vec::new();
            for k in 0..rng.random_range(1..30u32) {
                runs.push(Run {
                    y: y0 + k,
                    x0: x0 as u32,
                    x1: x1 as u32,
                });
                // The next run touches this one (8-connected).
                let (a, b) = (rng.random_range(-5..=5), rng.random_range(-5..=5));
                let (n0, n1) = ((x0 + a).max(0), (x1 + b).max(0));
                let (n0, n1) = (n0.min(n1), n0.max(n1));
                (x0, x1) = (n0.min(x1 + 1), n1.max(x0 - 1).max(n0.min(x1 + 1)));
            }
            let diagonal = chain_border(&runs, &mut points);
            assert_eq!(diagonal_steps(&runs), diagonal);
            let moments = chain_moments(&runs).expect("small enough");
            assert_eq!(
                bits(moments),
                bits(Moments::of_polygon(&points)),
                "{runs:?}"
            );
        }
        // Far from the origin the sums could round: no promise is made.
        let far = runs_of(&[(5000, 5003), (5000, 5003)]);
        assert!(chain_moments(&far).is_none());
    }

    #[test]
    fn the_step_count_is_the_borders_length() {
        let mut points = Vec::new();
        for rows in [
            &[(4, 4)][..],
            &[(1, 4)],
            &[(2, 4), (1, 5), (0, 4), (2, 3)],
            &[(0, 1), (2, 4), (4, 4)],
            &[(5, 6), (1, 4), (0, 9)],
        ] {
            let runs = runs_of(rows);
            chain_border(&runs, &mut points);
            assert_eq!(points.len(), border_len(&runs).max(1), "{rows:?}");
        }
    }
}
