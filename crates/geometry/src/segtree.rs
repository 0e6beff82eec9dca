//! A bounding-box tree over a polygon's edges, so that nearest-edge queries
//! cost O(log n) instead of O(n).
//!
//! The edges of a dense outline are spatially coherent along the chain, so a
//! tree that halves the index range at each level gives tight boxes without
//! any sorting. Queries are exact: boxes only prune, every candidate edge is
//! measured with the exact point-to-segment distance.
use crate::Vec2;

/// Edges per leaf: small enough to prune well, big enough to keep the tree shallow.
const LEAF_SIZE: usize = 8;

/// One edge `a -> a + d` with its cached length and outward normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Segment {
    pub a: Vec2,
    pub d: Vec2,
    pub len: f64,
    /// Unit outward normal of a counter-clockwise polygon (the right of `d`).
    pub normal: Vec2,
}

impl Segment {
    pub fn new(a: Vec2, b: Vec2) -> Self {
        let d = b - a;
        let len = d.norm();
        let normal = if len > 0.0 {
            Vec2::new(d.y, -d.x) / len
        } else {
            Vec2::zeros()
        };
        Self { a, d, len, normal }
    }

    pub fn end(&self) -> Vec2 {
        self.a + self.d
    }

    /// Parameter in [0, 1] of the point of this segment closest to `p`.
    pub fn closest_param(&self, p: Vec2) -> f64 {
        let len2 = self.len * self.len;
        if len2 == 0.0 {
            return 0.0;
        }
        ((p - self.a).dot(&self.d) / len2).clamp(0.0, 1.0)
    }

    pub fn point_at(&self, t: f64) -> Vec2 {
        self.a + self.d * t
    }
}

/// The closest edge point found by a query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Hit {
    pub segment: usize,
    /// Parameter along the segment, in [0, 1].
    pub t: f64,
    pub point: Vec2,
    pub dist2: f64,
}

#[derive(Debug, Clone, PartialEq)]
struct Node {
    min: Vec2,
    max: Vec2,
    lo: usize,
    hi: usize,
    /// Indices of the two children, or `None` for a leaf.
    children: Option<(usize, usize)>,
}

/// The tree: nodes over contiguous ranges of segment indices; node 0 is the root.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SegTree {
    nodes: Vec<Node>,
}

impl SegTree {
    pub fn build(segments: &[Segment]) -> Self {
        let mut tree = SegTree {
            nodes: Vec::with_capacity(2 * segments.len() / LEAF_SIZE + 2),
        };
        if !segments.is_empty() {
            tree.build_range(segments, 0, segments.len());
        }
        tree
    }

    fn build_range(&mut self, segments: &[Segment], lo: usize, hi: usize) -> usize {
        let (min, max) = range_bounds(&segments[lo..hi]);
        let index = self.nodes.len();
        self.nodes.push(Node {
            min,
            max,
            lo,
            hi,
            children: None,
        });
        if hi - lo > LEAF_SIZE {
            let mid = lo + (hi - lo) / 2;
            let left = self.build_range(segments, lo, mid);
            let right = self.build_range(segments, mid, hi);
            self.nodes[index].children = Some((left, right));
        }
        index
    }

    /// The exact closest point of any segment to `p` (`None` only when empty).
    pub fn nearest(&self, segments: &[Segment], p: Vec2) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut best_d2 = f64::INFINITY;
        let mut stack: Vec<(usize, f64)> = Vec::with_capacity(64);
        if !self.nodes.is_empty() {
            stack.push((0, 0.0));
        }
        while let Some((index, box_d2)) = stack.pop() {
            if box_d2 >= best_d2 {
                continue;
            }
            let node = &self.nodes[index];
            match node.children {
                None => {
                    for (k, seg) in segments[node.lo..node.hi].iter().enumerate() {
                        let t = seg.closest_param(p);
                        let point = seg.point_at(t);
                        let dist2 = (point - p).norm_squared();
                        if dist2 < best_d2 {
                            best_d2 = dist2;
                            best = Some(Hit {
                                segment: node.lo + k,
                                t,
                                point,
                                dist2,
                            });
                        }
                    }
                }
                Some((left, right)) => {
                    let dl = self.box_dist2(left, p);
                    let dr = self.box_dist2(right, p);
                    // Push the farther child first so the nearer one is searched first.
                    if dl <= dr {
                        stack.push((right, dr));
                        stack.push((left, dl));
                    } else {
                        stack.push((left, dl));
                        stack.push((right, dr));
                    }
                }
            }
        }
        best
    }

    /// Indices of segments whose bounding boxes overlap the box `[min, max]`.
    pub fn overlapping(&self, min: Vec2, max: Vec2, out: &mut Vec<usize>) {
        out.clear();
        let mut stack: Vec<usize> = Vec::with_capacity(64);
        if !self.nodes.is_empty() {
            stack.push(0);
        }
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index];
            let disjoint = node.max.x < min.x
                || node.min.x > max.x
                || node.max.y < min.y
                || node.min.y > max.y;
            if disjoint {
                continue;
            }
            match node.children {
                None => out.extend(node.lo..node.hi),
                Some((left, right)) => {
                    stack.push(left);
                    stack.push(right);
                }
            }
        }
    }

    fn box_dist2(&self, index: usize, p: Vec2) -> f64 {
        let node = &self.nodes[index];
        let dx = (node.min.x - p.x).max(p.x - node.max.x).max(0.0);
        let dy = (node.min.y - p.y).max(p.y - node.max.y).max(0.0);
        dx * dx + dy * dy
    }
}

/// Bounding box of a run of segments.
fn range_bounds(segments: &[Segment]) -> (Vec2, Vec2) {
    let mut min = Vec2::repeat(f64::INFINITY);
    let mut max = Vec2::repeat(f64::NEG_INFINITY);
    for seg in segments {
        for q in [seg.a, seg.end()] {
            min = min.inf(&q);
            max = max.sup(&q);
        }
    }
    (min, max)
}
