//! Tests of the shape measures against closed forms, brute force and the
//! bounds their fast paths rely on.

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

/// Hull area by sorting every point (the textbook monotone chain).
fn hull_area_sorted(points: &[[i32; 2]]) -> f64 {
    let mut pts: Vec<[i64; 2]> = points
        .iter()
        .map(|p| [i64::from(p[0]), i64::from(p[1])])
        .collect();
    pts.sort_unstable();
    pts.dedup();
    if pts.len() < 3 {
        return 0.0;
    }
    let chain = |it: &mut dyn Iterator<Item = [i64; 2]>| {
        let mut c: Vec<[i64; 2]> = Vec::new();
        for p in it {
            while c.len() >= 2 && turn(c[c.len() - 2], c[c.len() - 1], p) <= 0 {
                c.pop();
            }
            c.push(p);
        }
        c
    };
    let lower = chain(&mut pts.iter().copied());
    let upper = chain(&mut pts.iter().rev().copied());
    let ring: Vec<[i64; 2]> = lower[..lower.len() - 1]
        .iter()
        .chain(&upper[..upper.len() - 1])
        .copied()
        .collect();
    let twice: i64 = (0..ring.len())
        .map(|i| {
            let (p, q) = (ring[i], ring[(i + 1) % ring.len()]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum();
    twice.abs() as f64 / 2.0
}

#[test]
fn row_extreme_hull_equals_full_sort_hull() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    for _ in 0..500 {
        let n = rng.random_range(0..30);
        let span = rng.random_range(1..12);
        let pts: Vec<[i32; 2]> = (0..n)
            .map(|_| [rng.random_range(-span..span), rng.random_range(-span..span)])
            .collect();
        assert_eq!(hull_area(&pts), hull_area_sorted(&pts), "{pts:?}");
    }
}

#[test]
fn octagon_bounds_the_hull_and_is_tight_for_a_square() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    for _ in 0..2000 {
        let n = rng.random_range(1..30);
        let pts: Vec<[i32; 2]> = (0..n)
            .map(|_| [rng.random_range(-6..6), rng.random_range(-6..6)])
            .collect();
        assert!(hull_area_upper_bound(&pts) >= hull_area(&pts), "{pts:?}");
    }
    assert_eq!(hull_area_upper_bound(&SQUARE), 16.0);
}

#[test]
fn median_radius_matches_sorting() {
    let pts = [[0, 0], [3, 0], [0, 4], [5, 5], [1, 1], [2, 7]];
    let mut scratch = MedianScratch::default();
    for n in 1..=pts.len() {
        let c = [0.7, 1.3];
        let mut d: Vec<f64> = pts[..n]
            .iter()
            .map(|p| (f64::from(p[0]) - c[0]).hypot(f64::from(p[1]) - c[1]))
            .collect();
        d.sort_by(f64::total_cmp);
        let want = (d[(n - 1) / 2] + d[n / 2]) / 2.0;
        assert_eq!(median_radius(&pts[..n], c, &mut scratch), want);
    }
}

#[test]
fn banded_median_radius_equals_full_sort_on_random_sets() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut a = MedianScratch::default();
    let mut b = Vec::new();
    for _ in 0..2000 {
        let n = rng.random_range(1..40);
        let pts: Vec<[i32; 2]> = (0..n)
            .map(|_| [rng.random_range(0..12), rng.random_range(0..12)])
            .collect();
        // Half the centres on the half-pixel grid: many exact ties.
        let c = if rng.random_bool(0.5) {
            [
                f64::from(rng.random_range(0..24)) / 2.0,
                f64::from(rng.random_range(0..24)) / 2.0,
            ]
        } else {
            [rng.random_range(0.0..12.0), rng.random_range(0.0..12.0)]
        };
        assert_eq!(
            median_radius(&pts, c, &mut a),
            exact_median(&pts, c, &mut b)
        );
    }
}

#[test]
fn sqrt_2_is_the_hypot_of_a_diagonal_step() {
    assert_eq!(1.0f64.hypot(1.0), std::f64::consts::SQRT_2);
}

/// The length from the step counts is within the bound of the sum
/// point by point, on random 8-connected closed walks.
#[test]
fn perimeter_of_steps_is_within_its_bound_of_the_sum() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let moves = [
        [1, 0],
        [1, 1],
        [0, 1],
        [-1, 1],
        [-1, 0],
        [-1, -1],
        [0, -1],
        [1, -1],
    ];
    for _ in 0..2000 {
        let n = rng.random_range(2..400);
        let mut points = vec![[0, 0]];
        for _ in 1..n {
            let [x, y] = points[points.len() - 1];
            let [dx, dy] = moves[rng.random_range(0..8)];
            points.push([x + dx, y + dy]);
        }
        // Close it: the last step back to the first point must be one
        // pixel too, so retrace the walk backwards.
        let back: Vec<[i32; 2]> = points[1..points.len() - 1].iter().rev().copied().collect();
        points.extend(back);
        let diagonal = (0..points.len())
            .filter(|&i| {
                let (p, q) = (points[i], points[(i + 1) % points.len()]);
                p[0] != q[0] && p[1] != q[1]
            })
            .count();
        let (sum, steps) = (
            perimeter(&points),
            perimeter_of_steps(points.len(), diagonal),
        );
        let bound = (points.len() + 2) as f64 * f64::EPSILON / 2.0 * sum;
        assert!((sum - steps).abs() <= bound, "{sum} {steps} {bound}");
    }
    assert_eq!(perimeter_of_steps(1, 0), perimeter(&[[3, 4]]));
    assert_eq!(
        perimeter_of_steps(4, 0),
        perimeter(&[[0, 0], [1, 0], [1, 1], [0, 1]])
    );
}

/// The middle keys are the sorted keys' ranks, by the window about
/// the mean (keys all near one value, as on a blob's border) and by
/// the selection (keys spread widely); both paths are taken.
#[test]
fn middle_keys_are_the_sorted_ranks_by_either_path() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
    let (mut windowed, mut selected) = (0, 0);
    let mut window = Vec::new();
    for _ in 0..3000 {
        let n = rng.random_range(1..60);
        let spread = if rng.random_bool(0.5) { 0.05 } else { 1.0 };
        let values: Vec<f64> = (0..n)
            .map(|_| 10.0 * (1.0 + rng.random_range(-spread..spread)))
            .collect();
        let mean = values.iter().sum::<f64>() / n as f64;
        let mut keys: Vec<u64> = values.iter().map(|v| v.to_bits()).collect();
        let mut sorted = keys.clone();
        sorted.sort_unstable();
        let ranks = [(n - 1) / 2, n / 2];
        let got = middle_keys(&mut keys, mean, ranks, &mut window);
        assert_eq!(got, (sorted[ranks[0]], sorted[ranks[1]]), "{values:?}");
        let under = values.iter().filter(|&&v| v < mean * 0.9).count();
        let inside = values
            .iter()
            .filter(|&&v| (mean * 0.9..=mean * 1.1).contains(&v));
        if under <= ranks[0] && under + inside.count() > ranks[1] {
            windowed += 1;
        } else {
            selected += 1;
        }
    }
    assert!(windowed > 300 && selected > 300, "{windowed} / {selected}");
}

#[test]
fn perimeter_table_matches_hypot() {
    let ring = [[0, 0], [1, 1], [2, 1], [2, 2], [5, 2], [4, 1]];
    let mut want = 0.0;
    let mut prev = ring[ring.len() - 1];
    for p in ring {
        want += f64::from(p[0] - prev[0]).hypot(f64::from(p[1] - prev[1]));
        prev = p;
    }
    assert_eq!(perimeter(&ring), want);
}
