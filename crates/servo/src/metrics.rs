//! Contour-following metrics: the report's L2 measure (ch. 5.3, Fig. 5.4)
//! and what the report lacks (tracking error, coverage, closure).
use serde::Serialize;
use tactrace_geometry::{Contour, Vec2};

/// Everything measured on one trajectory against the true contour.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct FollowMetrics {
    /// The report's metric: mean over 1000 evenly spaced contour points of
    /// the distance to the nearest trajectory point, mm.
    pub mean_l2_mm: f64,
    /// Largest of those distances, mm.
    pub max_l2_mm: f64,
    /// Mean |distance| of each trajectory point to the contour, mm.
    pub mean_track_error_mm: f64,
    /// 95th percentile of that distance, mm.
    pub p95_track_error_mm: f64,
    pub max_track_error_mm: f64,
    /// Fraction of the contour traced: of 1000 contour points evenly spaced
    /// by arc length, those passed by the trajectory while it stayed within
    /// `coverage_radius_mm` of the contour (see [`traced_fraction`]). A
    /// trajectory standing still covers nothing, however small the contour;
    /// a closed one includes the step back to its start.
    pub coverage: f64,
    pub coverage_radius_mm: f64,
    /// The trajectory came back to its start after leaving it.
    pub closed: bool,
    pub steps: usize,
    /// Trajectory length, mm.
    pub path_length_mm: f64,
}

/// The report's error curve: for each of `n` contour points evenly spaced by
/// arc length, the distance to the nearest trajectory point (mm). Point `k`
/// lies at arc length `k P / n` from the contour's first vertex, `P` the
/// perimeter ([`l2_curve_arc_mm`]).
pub fn l2_curve(contour: &Contour, trajectory: &[Vec2], n: usize) -> Vec<f64> {
    contour
        .resample(n)
        .iter()
        .map(|c| {
            trajectory
                .iter()
                .map(|t| (t - c).norm())
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// Arc length (mm) along `contour` of each of the `n` points of
/// [`l2_curve`], the error curve's x axis.
pub fn l2_curve_arc_mm(contour: &Contour, n: usize) -> Vec<f64> {
    let step = contour.perimeter() / n.max(1) as f64;
    (0..n).map(|k| k as f64 * step).collect()
}

/// Detects, point by point, that a trajectory has come back to its start:
/// after getting at least `min_excursion` mm from its first point, a later
/// segment (not just a vertex, so a step cannot jump over the start) passes
/// within `radius` mm of it. Used live by the servo loop and after the run
/// by the metrics, so both agree.
#[derive(Debug, Clone)]
pub struct ClosureDetector {
    radius: f64,
    min_excursion: f64,
    start: Option<Vec2>,
    last: Option<Vec2>,
    away: bool,
}

impl ClosureDetector {
    pub fn new(radius: f64, min_excursion: f64) -> Self {
        Self {
            radius,
            min_excursion,
            start: None,
            last: None,
            away: false,
        }
    }

    /// Add the next trajectory point; true once the loop has closed.
    pub fn observe(&mut self, p: Vec2) -> bool {
        let start = *self.start.get_or_insert(p);
        let closed = match self.last {
            Some(prev) => {
                self.away |= (p - start).norm() >= self.min_excursion;
                self.away && point_segment_distance(start, prev, p) <= self.radius
            }
            None => false,
        };
        self.last = Some(p);
        closed
    }
}

/// Whether a trajectory closes (see [`ClosureDetector`]).
pub fn trajectory_closes(trajectory: &[Vec2], radius: f64, min_excursion: f64) -> bool {
    let mut detector = ClosureDetector::new(radius, min_excursion);
    trajectory.iter().any(|p| detector.observe(*p))
}

fn point_segment_distance(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).norm()
}

/// The fraction of `contour` traced by `trajectory`: each trajectory point
/// within `radius` mm of the contour marks the nearest of `n` contour points
/// evenly spaced by arc length, and each step between two such points marks
/// the contour points between their nearest ones (the shorter way round)
/// when that arc is no longer than the step plus `2 radius` (so a step
/// cannot claim an arc it did not pass along).
pub fn traced_fraction(contour: &Contour, trajectory: &[Vec2], radius: f64, n: usize) -> f64 {
    let n = n.max(1);
    let spacing = contour.perimeter() / n as f64;
    let mut covered = vec![false; n];
    let mut prev: Option<(Vec2, usize)> = None;
    for &p in trajectory {
        let hit = contour.nearest(p);
        // A NaN distance (a non-finite point) is not near either.
        let near = hit.signed_distance.abs() <= radius;
        if !near {
            prev = None;
            continue;
        }
        let k = (hit.arc_length / spacing).round() as usize % n;
        covered[k] = true;
        if let Some((q, j)) = prev {
            let forward = (k + n - j) % n;
            let (from, len) = if forward <= n - forward {
                (j, forward)
            } else {
                (k, n - forward)
            };
            if len as f64 * spacing <= (p - q).norm() + 2.0 * radius {
                for i in 0..=len {
                    covered[(from + i) % n] = true;
                }
            }
        }
        prev = Some((p, k));
    }
    covered.iter().filter(|c| **c).count() as f64 / n as f64
}

/// Compute all metrics for a trajectory (sensor tip x, y per step, mm).
pub fn evaluate(
    contour: &Contour,
    trajectory: &[Vec2],
    close_radius: f64,
    min_excursion: f64,
) -> FollowMetrics {
    let curve = l2_curve(contour, trajectory, 1000);
    let coverage_radius_mm = 2.0;
    let mut track: Vec<f64> = trajectory
        .iter()
        .map(|p| contour.signed_distance(*p).abs())
        .collect();
    track.sort_by(f64::total_cmp);
    let mean = |v: &[f64]| {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let closed = trajectory_closes(trajectory, close_radius, min_excursion);
    // A closed loop's last step leads back to its start.
    let traced: Vec<Vec2> = match (closed, trajectory.first()) {
        (true, Some(first)) => trajectory.iter().chain([first]).copied().collect(),
        _ => trajectory.to_vec(),
    };
    let p95 = track
        .get(((track.len() as f64 * 0.95).ceil() as usize).saturating_sub(1))
        .copied()
        .unwrap_or(f64::NAN);
    FollowMetrics {
        mean_l2_mm: mean(&curve),
        max_l2_mm: curve.iter().copied().fold(0.0, f64::max),
        mean_track_error_mm: mean(&track),
        p95_track_error_mm: p95,
        max_track_error_mm: track.last().copied().unwrap_or(f64::NAN),
        coverage: traced_fraction(contour, &traced, coverage_radius_mm, 1000),
        coverage_radius_mm,
        closed,
        steps: trajectory.len(),
        path_length_mm: trajectory.windows(2).map(|w| (w[1] - w[0]).norm()).sum(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(r: f64, n: usize) -> Vec<Vec2> {
        (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                Vec2::new(r * t.cos(), r * t.sin())
            })
            .collect()
    }

    #[test]
    fn concentric_trajectory_has_offset_error() {
        let contour = Contour::new(circle(50.0, 2000)).unwrap();
        let traj = circle(51.0, 3000);
        let m = evaluate(&contour, &traj, 1.5, 20.0);
        assert!((m.mean_l2_mm - 1.0).abs() < 0.02, "{}", m.mean_l2_mm);
        assert!((m.mean_track_error_mm - 1.0).abs() < 0.02);
        assert!(m.closed);
        assert!((m.coverage - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_step_over_the_start_closes_the_loop() {
        // Out along y = 0 and back along y = 2 with a 4 mm step across
        // x = 0: no later vertex comes within 2.8 mm of the start, but the
        // step's segment passes 2 mm from it.
        let traj: Vec<Vec2> = [
            (0.0, 0.0),
            (10.0, 0.0),
            (20.0, 0.0),
            (30.0, 0.0),
            (30.0, 2.0),
            (20.0, 2.0),
            (10.0, 2.0),
            (2.0, 2.0),
            (-2.0, 2.0),
        ]
        .iter()
        .map(|&(x, y)| Vec2::new(x, y))
        .collect();
        let mut detector = ClosureDetector::new(2.5, 20.0);
        assert_eq!(traj.iter().position(|p| detector.observe(*p)), Some(8));
        assert!(!trajectory_closes(&traj, 1.5, 20.0));
        // Without the excursion the same path is not a loop.
        assert!(!trajectory_closes(&traj, 2.5, 40.0));
    }

    /// Issue 10: a contour given in metres (0.05 mm radius) and a run that
    /// stood still for 3 taps was scored as fully covered.
    #[test]
    fn a_trajectory_standing_still_covers_nothing_of_a_tiny_contour() {
        let contour = Contour::new(circle(0.05, 100)).unwrap();
        let traj = vec![Vec2::new(0.02, 0.0); 3];
        let m = evaluate(&contour, &traj, 3.0, 20.0);
        assert!(m.coverage <= 0.002, "{}", m.coverage);
        assert!(!m.closed);
    }

    #[test]
    fn a_closed_loop_covers_the_contour_up_to_its_last_step_home() {
        // 100 taps 3.1 mm apart: the loop closes on its last tap, and the
        // step from it back to the start completes the coverage.
        let contour = Contour::new(circle(50.0, 2000)).unwrap();
        let m = evaluate(&contour, &circle(50.0, 100), 3.5, 20.0);
        assert!(m.closed);
        assert!((m.coverage - 1.0).abs() < 1e-9, "{}", m.coverage);
    }

    #[test]
    fn half_trajectory_is_open_and_half_covered() {
        let contour = Contour::new(circle(50.0, 2000)).unwrap();
        let traj: Vec<Vec2> = circle(50.0, 2000).into_iter().take(1000).collect();
        let m = evaluate(&contour, &traj, 1.5, 20.0);
        assert!(!m.closed);
        assert!((m.coverage - 0.5).abs() < 0.03, "{}", m.coverage);
        assert!(m.mean_l2_mm > 10.0);
    }

    /// Issue 20: the L2 curve was plotted against "contour point" 0-1000;
    /// its x axis is now the arc length in mm, and each value belongs to
    /// the contour point at that arc length.
    #[test]
    fn l2_curve_points_sit_at_their_arc_length() {
        let contour = Contour::new(circle(50.0, 2000)).unwrap();
        let arc = l2_curve_arc_mm(&contour, 1000);
        assert_eq!(arc.len(), 1000);
        assert_eq!(arc[0], 0.0);
        let step = contour.perimeter() / 1000.0;
        assert!((arc[999] - 999.0 * step).abs() < 1e-9);
        // A single trajectory point at the contour point of arc length
        // arc[250] is 0 mm from it, and the curve says so at index 250.
        let at = contour.at_arc_length(arc[250]).0;
        let curve = l2_curve(&contour, &[at], 1000);
        assert!(curve[250] < 1e-9, "{}", curve[250]);
        assert!(curve[750] > 99.0, "the opposite point is a diameter away");
    }
}
