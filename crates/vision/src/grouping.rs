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
        let weight: f64 = self.members.iter().map(|m| m.confidence).sum();
        let (sx, sy) = self.members.iter().fold((0.0, 0.0), |(sx, sy), m| {
            (sx + m.confidence * m.x, sy + m.confidence * m.y)
        });
        let (x, y) = if weight > 0.0 {
            (sx / weight, sy / weight)
        } else {
            let n = self.members.len() as f64;
            let (ux, uy) = self
                .members
                .iter()
                .fold((0.0, 0.0), |(a, b), m| (a + m.x, b + m.y));
            (ux / n, uy / n)
        };
        KeyPoint {
            x,
            y,
            size: 2.0 * self.representative().radius,
        }
    }
}

/// Groups built so far, plus the grid over their representatives.
#[derive(Default)]
pub struct Grouper {
    groups: Vec<Group>,
    grid: RepGrid,
}

impl Grouper {
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
        self.grid.build(&self.groups, found, reach);
        for centre in found {
            let target = self
                .grid
                .candidates(centre)
                .filter(|&j| joins(self.groups[j].representative(), centre, min_dist, reach))
                .min();
            match target {
                Some(j) => {
                    self.groups[j].insert(*centre);
                    let rep = *self.groups[j].representative();
                    self.grid.moved_to(j, &rep);
                }
                None => self.groups.push(Group {
                    members: vec![*centre],
                }),
            }
        }
        debug_assert!(self.groups.len() >= existing);
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
const MAX_CELLS: f64 = 24.0;

/// Representatives of the existing groups bucketed by cell (compressed rows).
/// A representative that leaves its cell during a threshold (or its grid)
/// is moved to a short list that every query checks.
#[derive(Default)]
struct RepGrid {
    origin: [f64; 2],
    cell: f64,
    dims: [usize; 2],
    cell_of: Vec<usize>,
    starts: Vec<usize>,
    entries: Vec<usize>,
    moved: Vec<usize>,
    is_moved: Vec<bool>,
    scratch: Vec<usize>,
}

impl RepGrid {
    fn build(&mut self, groups: &[Group], found: &[Centre], reach: f64) {
        let points = groups.iter().map(Group::representative).chain(found);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for c in points {
            lo = [lo[0].min(c.x), lo[1].min(c.y)];
            hi = [hi[0].max(c.x), hi[1].max(c.y)];
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(0.0);
        self.origin = lo;
        self.cell = reach.max(1.0).max(extent / MAX_CELLS);
        self.dims = [0, 1].map(|a| {
            let span = ((hi[a] - lo[a]) / self.cell).floor();
            if span.is_finite() && span >= 0.0 {
                span as usize + 1
            } else {
                1
            }
        });
        let n_cells = self.dims[0] * self.dims[1];
        self.cell_of.clear();
        self.moved.clear();
        self.is_moved.clear();
        self.is_moved.resize(groups.len(), false);
        self.starts.clear();
        self.starts.resize(n_cells + 1, 0);
        for (j, g) in groups.iter().enumerate() {
            match self.cell_index(g.representative()) {
                Some(k) => {
                    self.cell_of.push(k);
                    self.starts[k + 1] += 1;
                }
                None => {
                    self.cell_of.push(usize::MAX);
                    self.is_moved[j] = true;
                    self.moved.push(j);
                }
            }
        }
        for k in 0..n_cells {
            self.starts[k + 1] += self.starts[k];
        }
        self.entries.clear();
        self.entries.resize(self.starts[n_cells], 0);
        self.scratch.clear();
        self.scratch.extend_from_slice(&self.starts[..n_cells]);
        for (j, &k) in self.cell_of.iter().enumerate() {
            if k != usize::MAX {
                self.entries[self.scratch[k]] = j;
                self.scratch[k] += 1;
            }
        }
    }

    fn cell_xy(&self, c: &Centre) -> Option<[usize; 2]> {
        let fx = ((c.x - self.origin[0]) / self.cell).floor();
        let fy = ((c.y - self.origin[1]) / self.cell).floor();
        let inside = |f: f64, n: usize| f >= 0.0 && f < n as f64;
        (inside(fx, self.dims[0]) && inside(fy, self.dims[1])).then_some([fx as usize, fy as usize])
    }

    fn cell_index(&self, c: &Centre) -> Option<usize> {
        self.cell_xy(c).map(|[x, y]| y * self.dims[0] + x)
    }

    /// Existing groups whose representative may lie within the cell width
    /// of `c` on both axes (a superset of those that can join).
    fn candidates<'a>(&'a self, c: &Centre) -> impl Iterator<Item = usize> + 'a {
        let near = self.cell_xy(c).map(|[x, y]| {
            let xs = x.saturating_sub(1)..=(x + 1).min(self.dims[0] - 1);
            let ys = y.saturating_sub(1)..=(y + 1).min(self.dims[1] - 1);
            ys.flat_map(move |cy| {
                let row = cy * self.dims[0];
                let (a, b) = (
                    self.starts[row + xs.start()],
                    self.starts[row + xs.end() + 1],
                );
                self.entries[a..b].iter().copied()
            })
        });
        near.into_iter()
            .flatten()
            .filter(|&j| !self.is_moved[j])
            .chain(self.moved.iter().copied())
    }

    /// Records that group `j`'s representative is now `rep`.
    fn moved_to(&mut self, j: usize, rep: &Centre) {
        if self.is_moved[j] || self.cell_index(rep) == Some(self.cell_of[j]) {
            return;
        }
        self.is_moved[j] = true;
        self.moved.push(j);
    }
}

/// Whether `centre` belongs to the group represented by `rep`. `reach`
/// bounds every distance that can qualify and only prunes the square root.
fn joins(rep: &Centre, centre: &Centre, min_dist: f64, reach: f64) -> bool {
    let (dx, dy) = (rep.x - centre.x, rep.y - centre.y);
    if dx.abs() > reach || dy.abs() > reach {
        return false;
    }
    let dist = dx.hypot(dy);
    !(dist >= min_dist && dist >= rep.radius && dist >= centre.radius)
}
