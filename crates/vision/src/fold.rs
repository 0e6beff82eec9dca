//! Fold-over check for ordered pins (report ch. 4.1: every entry of the
//! displacement vector must belong to its own pin). The skin deforms
//! smoothly and never turns over, so every triangle of mutually
//! neighbouring reference pins keeps its orientation in a correct
//! ordering; two swapped pins turn some of them over (signed-area ratio
//! near -1). The tracker checks this after its final stage, which costs one
//! pass over the triangles (175 for the 127-pin sensor), and only when a
//! triangle has turned over re-orders the points of the pins around it
//! ([`reorder_region`]).

/// A triangle whose tracked/reference signed-area ratio is below this has
/// turned over. A swap gives about -1; a triangle squashed flat against the
/// edge (ratio near 0) may tip slightly below 0 by detection noise alone.
pub const TURNED_RATIO: f64 = -0.25;
/// Reference pins closer than this many spacings are neighbours.
const NEIGHBOUR_REACH: f64 = 1.5;
/// Triangles with a reference area (twice the area, px^2) below this share
/// of the squared spacing are too thin to have an orientation and are left
/// out (none in a hexagonal layout).
const MIN_AREA_SHARE: f64 = 0.1;

/// The triangles of mutually neighbouring reference pins and their
/// orientation.
pub struct FoldCheck {
    /// Corners of each triangle, ordered so that its reference area is
    /// positive.
    triangles: Vec<[usize; 3]>,
    /// Per triangle, [`TURNED_RATIO`] times twice its reference area, px^2:
    /// the triangle has turned over when twice its signed area is below.
    limits: Vec<f64>,
    /// Reference neighbours of all pins, ascending per pin; pin `i`'s are
    /// `neighbours[starts[i]..starts[i + 1]]` (one allocation).
    neighbours: Vec<usize>,
    starts: Vec<usize>,
}

impl FoldCheck {
    /// Every triangle of three `reference` pins (px) whose sides are all
    /// shorter than 1.5 `spacing` (px), listed once.
    pub fn new(reference: &[[f64; 2]], spacing: f64) -> Self {
        let reach2 = (NEIGHBOUR_REACH * spacing).powi(2);
        let near = |a: usize, b: usize| distance2(reference[a], reference[b]) < reach2;
        let n = reference.len();
        let (mut neighbours, mut starts) = (Vec::new(), vec![0]);
        for i in 0..n {
            neighbours.extend((0..n).filter(|&j| j != i && near(i, j)));
            starts.push(neighbours.len());
        }
        let around = |i: usize| &neighbours[starts[i]..starts[i + 1]];
        let (mut triangles, mut limits) = (Vec::new(), Vec::new());
        for i in 0..n {
            for &j in around(i).iter().filter(|&&j| j > i) {
                for &k in around(j).iter().filter(|&&k| k > j) {
                    let area = signed_area(reference, [i, j, k]);
                    if near(i, k) && area.abs() >= MIN_AREA_SHARE * spacing * spacing {
                        triangles.push(if area > 0.0 { [i, j, k] } else { [i, k, j] });
                        limits.push(TURNED_RATIO * area.abs());
                    }
                }
            }
        }
        Self {
            triangles,
            limits,
            neighbours,
            starts,
        }
    }

    /// Reference neighbours of pin `i`, ascending.
    pub(crate) fn around(&self, i: usize) -> &[usize] {
        &self.neighbours[self.starts[i]..self.starts[i + 1]]
    }

    /// Number of reference pins.
    fn pins(&self) -> usize {
        self.starts.len() - 1
    }

    /// Number of reference triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether any triangle of `pins` (reference order, px) has turned over.
    pub fn any_turned(&self, pins: &[[f64; 2]]) -> bool {
        self.triangles
            .iter()
            .zip(&self.limits)
            .any(|(&t, &limit)| signed_area(pins, t) < limit)
    }

    /// Indices of the triangles of `pins` that have turned over.
    pub fn turned(&self, pins: &[[f64; 2]]) -> Vec<usize> {
        self.triangles
            .iter()
            .zip(&self.limits)
            .enumerate()
            .filter(|(_, (&t, &limit))| signed_area(pins, t) < limit)
            .map(|(i, _)| i)
            .collect()
    }

    /// The corners of the triangles `turned`, then the neighbours of those
    /// corners for which `include(pin)` holds, ascending in each part.
    pub fn corners_and(&self, turned: &[usize], include: impl Fn(usize) -> bool) -> Vec<usize> {
        let mut corner = vec![false; self.pins()];
        for &t in turned {
            for &i in &self.triangles[t] {
                corner[i] = true;
            }
        }
        let mut out: Vec<usize> = (0..corner.len()).filter(|&i| corner[i]).collect();
        let mut extra: Vec<usize> = out
            .iter()
            .flat_map(|&i| self.around(i).iter().copied())
            .filter(|&j| !corner[j] && include(j))
            .collect();
        extra.sort_unstable();
        extra.dedup();
        out.extend(extra);
        out
    }

    /// Per pin, whether it is a corner of one of the triangles `turned`
    /// or lies within `rings` neighbour steps of one.
    pub fn region(&self, turned: &[usize], rings: usize) -> Vec<bool> {
        let mut inside = vec![false; self.pins()];
        for &t in turned {
            for &i in &self.triangles[t] {
                inside[i] = true;
            }
        }
        for _ in 0..rings {
            let grown: Vec<usize> = (0..inside.len())
                .filter(|&i| !inside[i] && self.around(i).iter().any(|&j| inside[j]))
                .collect();
            for i in grown {
                inside[i] = true;
            }
        }
        inside
    }

    /// Smoothness energy of an ordering: the sum over neighbouring pin
    /// pairs of the squared difference of their displacements, px^2. Ties
    /// between fold-free repairs go to the smoother one.
    pub fn roughness(&self, reference: &[[f64; 2]], pins: &[[f64; 2]]) -> f64 {
        let d = |i: usize| [pins[i][0] - reference[i][0], pins[i][1] - reference[i][1]];
        (0..self.pins())
            .flat_map(|i| {
                self.around(i)
                    .iter()
                    .filter(move |&&j| j > i)
                    .map(move |&j| (i, j))
            })
            .map(|(i, j)| distance2(d(i), d(j)))
            .sum()
    }
}

/// The best re-ordering of the points of a few pins around a fold: every
/// assignment of the points the pins of `region` hold (`matches[i]`, an
/// index into `points`) to those same pins, each point to one pin, the
/// rest left unmatched, is tried (`region.len()!` at most), so no point is
/// lost or gained, except that no pin may take a point farther than `gate`
/// (px) from its prediction. Pins outside the region stay at `pins` (px); an
/// unmatched region pin is put at `predicted` (px, the caller's prediction
/// from the pins outside the region). Among the assignments with no
/// turned-over triangle, the one with the smallest field residual (sum of
/// squared distances of the region's points to their pins' predictions,
/// px^2) is returned as the new matches of every pin; `None` if all turn
/// some triangle over.
pub fn reorder_region(
    check: &FoldCheck,
    pins: &[[f64; 2]],
    points: &[[f64; 2]],
    matches: &[Option<usize>],
    region: &[usize],
    predicted: &[[f64; 2]],
    gate: f64,
) -> Option<Vec<Option<usize>>> {
    let gate2 = gate * gate;
    let mut slots: Vec<Option<usize>> = region.iter().map(|&i| matches[i]).collect();
    let mut trial = pins.to_vec();
    let mut best: Option<(f64, Vec<Option<usize>>)> = None;
    let mut visit = |slots: &[Option<usize>]| {
        let mut residual = 0.0;
        for (&i, slot) in region.iter().zip(slots) {
            trial[i] = slot.map_or(predicted[i], |k| points[k]);
            let d2 = slot.map_or(0.0, |k| distance2(points[k], predicted[i]));
            if d2 > gate2 {
                return;
            }
            residual += d2;
        }
        let better = best.as_ref().is_none_or(|(r, _)| residual < *r);
        if better && !check.any_turned(&trial) {
            best = Some((residual, slots.to_vec()));
        }
    };
    // Heap's algorithm: every permutation of the slots, one swap apart.
    visit(&slots);
    let mut counters = vec![0; slots.len()];
    let mut i = 1;
    while i < slots.len() {
        if counters[i] < i {
            let j = if i % 2 == 0 { 0 } else { counters[i] };
            slots.swap(j, i);
            visit(&slots);
            counters[i] += 1;
            i = 1;
        } else {
            counters[i] = 0;
            i += 1;
        }
    }
    best.map(|(_, slots)| {
        let mut out = matches.to_vec();
        for (&i, slot) in region.iter().zip(slots) {
            out[i] = slot;
        }
        out
    })
}

/// Twice the signed area of triangle `t` of `p`.
#[inline]
fn signed_area(p: &[[f64; 2]], t: [usize; 3]) -> f64 {
    let (a, b, c) = (p[t[0]], p[t[1]], p[t[2]]);
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn distance2(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4 x 4 square-ish grid with alternate rows shifted (hexagonal).
    fn hex(n: usize) -> Vec<[f64; 2]> {
        let mut pins = Vec::new();
        for r in 0..n {
            for q in 0..n {
                let x = 10.0 * q as f64 + 5.0 * (r % 2) as f64;
                pins.push([x, 10.0 * 0.75f64.sqrt() * r as f64]);
            }
        }
        pins
    }

    #[test]
    fn a_swap_turns_triangles_and_a_shift_does_not() {
        let reference = hex(4);
        let check = FoldCheck::new(&reference, 10.0);
        // Each of the 3 gaps between rows (offset by half a spacing) holds
        // 2 * 4 - 2 = 6 triangles.
        assert_eq!(check.len(), 18);
        let shifted: Vec<[f64; 2]> = reference
            .iter()
            .map(|p| [p[0] + 30.0, p[1] - 7.0])
            .collect();
        assert!(!check.any_turned(&shifted) && check.turned(&shifted).is_empty());
        let mut swapped = shifted.clone();
        swapped.swap(5, 6);
        assert!(check.any_turned(&swapped));
        let turned = check.turned(&swapped);
        assert!(!turned.is_empty());
        let region = check.region(&turned, 0);
        assert!(region[5] && region[6] && !region[15]);
        assert!(check.region(&turned, 1).iter().filter(|&&r| r).count() > 2);
        assert!(check.roughness(&reference, &swapped) > check.roughness(&reference, &shifted));
        assert_eq!(check.roughness(&reference, &shifted), 0.0);
    }

    #[test]
    fn reorder_undoes_a_swap_and_gives_up_on_an_unavoidable_fold() {
        let reference = hex(4);
        let check = FoldCheck::new(&reference, 10.0);
        let points: Vec<[f64; 2]> = reference.iter().map(|p| [p[0] + 3.0, p[1] + 2.0]).collect();
        // Pins 5 and 6 hold each other's points; 9 is unmatched.
        let mut matches: Vec<Option<usize>> = (0..16).map(Some).collect();
        matches.swap(5, 6);
        matches[9] = None;
        let mut pins: Vec<[f64; 2]> = matches
            .iter()
            .zip(&points)
            .map(|(m, p)| m.map_or(*p, |k| points[k]))
            .collect();
        let turned = check.turned(&pins);
        let region = check.corners_and(&turned, |j| matches[j].is_none());
        assert!(region.contains(&5) && region.contains(&6) && region.contains(&9));
        let fixed = reorder_region(&check, &pins, &points, &matches, &region, &points, 5.0)
            .expect("a fold-free order exists");
        let want: Vec<Option<usize>> = (0..16).map(|i| (i != 9).then_some(i)).collect();
        assert_eq!(fixed, want);
        // Pin 15 (outside the region) folded over the region: no re-order helps.
        pins[15] = [pins[10][0] - 12.0, pins[10][1] - 12.0];
        let turned = check.turned(&pins);
        let region = check.corners_and(&turned, |_| false);
        let fixed = reorder_region(&check, &pins, &points, &matches, &region[..2], &points, 5.0);
        assert_eq!(fixed, None);
    }
}
