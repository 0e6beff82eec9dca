//! Grouping of blob centres across thresholds, as OpenCV's
//! `SimpleBlobDetector` does it (report ch. 4.1): a centre joins the first
//! existing group whose representative (median member by radius) lies
//! closer than `min_dist_between_blobs` or either radius. The search for
//! that group goes through a uniform grid of representatives whose cells are
//! at least as wide as any joining distance, and still returns the group
//! with the smallest index, so the result is that of the linear scan.

use crate::blob::KeyPoint;

/// A blob found at one threshold.
#[derive(Clone, Copy, Debug)]
pub struct Centre {
    pub x: f64,
    pub y: f64,
    pub radius: f64,
    pub confidence: f64,
}

/// Centres found at successive thresholds for the same blob, kept sorted by
/// radius; the middle one stands for the group.
pub struct Group {
    members: Vec<Centre>,
}

impl Group {
    fn representative(&self) -> &Centre {
        &self.members[self.members.len() / 2]
    }

    fn insert(&mut self, centre: Centre) {
        let at = self.members.partition_point(|m| m.radius <= centre.radius);
        self.members.insert(at, centre);
    }

    fn keypoint(&self) -> KeyPoint {
        keypoint_of(self.members.iter().copied(), self.representative().radius)
    }
}

/// The keypoint of a group with these members (in order) and representative
/// radius: confidence-weighted mean centre (plain mean when the weights sum
/// to zero), size twice the radius. Shared by every path that builds groups,
/// so that they round alike.
pub(crate) fn keypoint_of(
    members: impl Iterator<Item = Centre> + Clone,
    rep_radius: f64,
) -> KeyPoint {
    let weight: f64 = members.clone().map(|m| m.confidence).sum();
    let (sx, sy) = members.clone().fold((0.0, 0.0), |(sx, sy), m| {
        (sx + m.confidence * m.x, sy + m.confidence * m.y)
    });
    let (x, y) = if weight > 0.0 {
        (sx / weight, sy / weight)
    } else {
        let n = members.clone().count() as f64;
        let (ux, uy) = members.fold((0.0, 0.0), |(a, b), m| (a + m.x, b + m.y));
        (ux / n, uy / n)
    };
    KeyPoint {
        x,
        y,
        size: 2.0 * rep_radius,
    }
}

/// Groups built so far, plus the grid over their representatives.
pub struct Grouper {
    groups: Vec<Group>,
    /// Most members a group can get (one per threshold).
    capacity: usize,
    grid: RepGrid,
}

impl Grouper {
    /// A grouper for centres of a `width` x `height` frame (centres outside
    /// it are handled too, just without the grid's help) over `thresholds`
    /// thresholds.
    pub fn new(width: usize, height: usize, thresholds: usize) -> Self {
        Self {
            groups: Vec::new(),
            capacity: thresholds,
            grid: RepGrid {
                size: [width as f64, height as f64],
                cell: 0.0,
                dims: [0, 0],
                cells: Vec::new(),
                cell_of: Vec::new(),
                outside: Vec::new(),
            },
        }
    }

    /// Adds one threshold's centres, in contour order. New groups become
    /// visible only at the next threshold.
    pub fn add(&mut self, found: &[Centre], min_dist: f64) {
        let existing = self.groups.len();
        // Every representative is a stored centre, and inserting a centre
        // never makes a representative wider than it or the old one, so
        // this bounds every radius in the joining rule during the threshold.
        let max_radius = self
            .groups
            .iter()
            .map(|g| g.representative().radius)
            .chain(found.iter().map(|c| c.radius))
            .fold(0.0f64, f64::max);
        let reach = min_dist.max(max_radius);
        self.grid.index(&self.groups, reach);
        for centre in found {
            let groups = &self.groups;
            let target = self.grid.first_joining(centre, existing, |j| {
                joins(groups[j].representative(), centre, min_dist, reach)
            });
            match target {
                Some(j) => {
                    self.groups[j].insert(*centre);
                    let rep = *self.groups[j].representative();
                    self.grid.relocate(j, &rep);
                }
                None => {
                    let mut members = Vec::with_capacity(self.capacity);
                    members.push(*centre);
                    self.groups.push(Group { members });
                }
            }
        }
    }

    /// Keypoints of the groups with at least `min_repeatability` members.
    pub fn keypoints(&self, min_repeatability: usize) -> Vec<KeyPoint> {
        self.groups
            .iter()
            .filter(|g| g.members.len() >= min_repeatability)
            .map(Group::keypoint)
            .collect()
    }
}

/// Most cells per axis (cells widen beyond the joining distance if needed).
const MAX_CELLS: f64 = 64.0;

/// Where group `j`'s representative is filed.
#[derive(Clone, Copy, PartialEq)]
enum Slot {
    Cell(usize),
    Outside,
}

/// Representatives bucketed by square cells over the frame, at least as
/// wide as the joining reach, so every group that can join a centre is
/// filed in the 3 x 3 cells around it (or in the short `outside` list).
/// Kept across thresholds: new groups are filed at the next threshold,
/// moved representatives are refiled, and the grid is rebuilt only when
/// the reach outgrows the cells.
struct RepGrid {
    size: [f64; 2],
    cell: f64,
    dims: [usize; 2],
    cells: Vec<Vec<usize>>,
    cell_of: Vec<Slot>,
    outside: Vec<usize>,
}

impl RepGrid {
    /// Files every group not yet filed; rebuilds when `reach` exceeds the cells.
    fn index(&mut self, groups: &[Group], reach: f64) {
        let fits = reach <= self.cell;
        if !fits {
            self.cell = reach
                .max(1.0)
                .max(self.size[0].max(self.size[1]) / MAX_CELLS);
            self.dims = [0, 1].map(|a| {
                let n = (self.size[a] / self.cell).ceil();
                if n.is_finite() && n >= 1.0 {
                    n as usize
                } else {
                    1
                }
            });
            self.cells.clear();
            self.cells.resize(self.dims[0] * self.dims[1], Vec::new());
            self.cell_of.clear();
            self.outside.clear();
        }
        for (j, group) in groups.iter().enumerate().skip(self.cell_of.len()) {
            let slot = self.slot(group.representative());
            self.file(j, slot);
            self.cell_of.push(slot);
        }
    }

    fn file(&mut self, j: usize, slot: Slot) {
        match slot {
            Slot::Cell(k) => self.cells[k].push(j),
            Slot::Outside => self.outside.push(j),
        }
    }

    fn cell_xy(&self, c: &Centre) -> Option<[usize; 2]> {
        // Truncation is floor for the non-negative values kept.
        let (fx, fy) = (c.x / self.cell, c.y / self.cell);
        let inside = |f: f64, n: usize| f >= 0.0 && f < n as f64;
        (inside(fx, self.dims[0]) && inside(fy, self.dims[1])).then_some([fx as usize, fy as usize])
    }

    fn slot(&self, c: &Centre) -> Slot {
        match self.cell_xy(c) {
            Some([x, y]) => Slot::Cell(y * self.dims[0] + x),
            None => Slot::Outside,
        }
    }

    /// The smallest group index `j < existing` for which `joins(j)` holds,
    /// among the groups filed in the cells that meet the square of half-side
    /// 1.001 cell widths around `c` (a superset of those whose representative
    /// is within the reach on both axes), wherever `c` lies.
    fn first_joining(
        &self,
        c: &Centre,
        existing: usize,
        mut joins: impl FnMut(usize) -> bool,
    ) -> Option<usize> {
        let mut best = existing;
        let mut consider = |j: usize| {
            if j < best && joins(j) {
                best = j;
            }
        };
        let xs = cell_range(c.x, self.cell, self.dims[0]);
        let ys = cell_range(c.y, self.cell, self.dims[1]);
        if let (Some((x0, x1)), Some((y0, y1))) = (xs, ys) {
            for cy in y0..=y1 {
                for cx in x0..=x1 {
                    for &j in &self.cells[cy * self.dims[0] + cx] {
                        consider(j);
                    }
                }
            }
        }
        for &j in &self.outside {
            consider(j);
        }
        (best < existing).then_some(best)
    }

    /// Refiles group `j`, whose representative is now `rep`.
    fn relocate(&mut self, j: usize, rep: &Centre) {
        let slot = self.slot(rep);
        let old = self.cell_of[j];
        if slot == old {
            return;
        }
        let list = match old {
            Slot::Cell(k) => &mut self.cells[k],
            Slot::Outside => &mut self.outside,
        };
        if let Some(at) = list.iter().position(|&g| g == j) {
            list.swap_remove(at);
        }
        self.file(j, slot);
        self.cell_of[j] = slot;
    }
}

/// Indices of the cells (of `n` along one axis) that meet
/// `[v - 1.001 cell, v + 1.001 cell]` (a margin against rounding at cell
/// edges); `None` when none does.
fn cell_range(v: f64, cell: f64, n: usize) -> Option<(usize, usize)> {
    if n == 0 {
        return None;
    }
    let lo = ((v - 1.001 * cell) / cell).floor().max(0.0);
    let hi = ((v + 1.001 * cell) / cell).floor().min((n - 1) as f64);
    (lo <= hi).then_some((lo as usize, hi as usize))
}

/// Whether `centre` belongs to the group represented by `rep`. `reach`
/// bounds every distance that can qualify and only prunes the square root.
pub(crate) fn joins(rep: &Centre, centre: &Centre, min_dist: f64, reach: f64) -> bool {
    let (dx, dy) = (rep.x - centre.x, rep.y - centre.y);
    if dx.abs() > reach || dy.abs() > reach {
        return false;
    }
    let dist = dx.hypot(dy);
    !(dist >= min_dist && dist >= rep.radius && dist >= centre.radius)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The plain linear scan the grid replaces (OpenCV's loop).
    fn linear(thresholds: &[Vec<Centre>], min_dist: f64) -> Vec<KeyPoint> {
        let mut groups: Vec<Group> = Vec::new();
        for found in thresholds {
            let existing = groups.len();
            for centre in found {
                let target = (0..existing)
                    .find(|&j| joins(groups[j].representative(), centre, min_dist, f64::INFINITY));
                match target {
                    Some(j) => groups[j].insert(*centre),
                    None => groups.push(Group {
                        members: vec![*centre],
                    }),
                }
            }
        }
        groups
            .iter()
            .filter(|g| g.members.len() >= 2)
            .map(Group::keypoint)
            .collect()
    }

    #[test]
    fn grid_search_matches_the_linear_scan() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..200 {
            let size = rng.random_range(4.0..80.0);
            let seeds: Vec<[f64; 2]> = (0..rng.random_range(1..40))
                .map(|_| [rng.random_range(-3.0..size), rng.random_range(-3.0..size)])
                .collect();
            let mut thresholds: Vec<Vec<Centre>> = Vec::new();
            for _ in 0..rng.random_range(1..8) {
                let mut found = Vec::new();
                for s in &seeds {
                    if rng.random_bool(0.8) {
                        found.push(Centre {
                            x: s[0] + rng.random_range(-2.0..2.0),
                            y: s[1] + rng.random_range(-2.0..2.0),
                            radius: rng.random_range(0.0..6.0),
                            confidence: rng.random_range(0.0..1.0),
                        });
                    }
                }
                thresholds.push(found);
            }
            let min_dist = rng.random_range(0.0..8.0);
            let mut grouper = Grouper::new(size as usize, size as usize, thresholds.len());
            for found in &thresholds {
                grouper.add(found, min_dist);
            }
            assert_eq!(grouper.keypoints(2), linear(&thresholds, min_dist));
        }
    }
}
