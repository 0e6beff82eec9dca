//! A bounding-volume hierarchy over a mesh's triangles (axis-aligned
//! boxes, median splits along the longest side), so the nearest-triangle
//! query visits O(log n) boxes instead of every triangle.
use crate::Vec3;

/// Triangles per leaf.
const LEAF: usize = 4;

#[derive(Debug, Clone)]
struct Node {
    min: Vec3,
    max: Vec3,
    /// The node's triangles: `order[start..start + count]`.
    start: usize,
    count: usize,
    /// An inner node's children (node indices); `None` for a leaf.
    children: Option<(usize, usize)>,
}

/// The hierarchy: nodes (root first) and the triangle order of its leaves.
#[derive(Debug, Clone)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    order: Vec<usize>,
}

impl Bvh {
    /// Build over triangles given by their corners.
    pub(crate) fn new(triangles: &[[Vec3; 3]]) -> Self {
        let mut bvh = Self {
            nodes: Vec::new(),
            order: (0..triangles.len()).collect(),
        };
        let centroids: Vec<Vec3> = triangles
            .iter()
            .map(|t| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        bvh.build(triangles, &centroids, 0, triangles.len());
        bvh
    }

    fn build(
        &mut self,
        tris: &[[Vec3; 3]],
        centroids: &[Vec3],
        start: usize,
        count: usize,
    ) -> usize {
        let (mut min, mut max) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
        for &t in &self.order[start..start + count] {
            for c in &tris[t] {
                min = min.inf(c);
                max = max.sup(c);
            }
        }
        let id = self.nodes.len();
        self.nodes.push(Node {
            min,
            max,
            start,
            count,
            children: None,
        });
        if count > LEAF {
            let axis = (max - min).imax();
            let half = count / 2;
            self.order[start..start + count].select_nth_unstable_by(half, |a, b| {
                centroids[*a][axis].total_cmp(&centroids[*b][axis])
            });
            let left = self.build(tris, centroids, start, half);
            let right = self.build(tris, centroids, start + half, count - half);
            self.nodes[id].children = Some((left, right));
        }
        id
    }

    /// Visit the triangles that may lie nearer `p` than the best squared
    /// distance so far: `visit(triangle)` returns its squared distance.
    pub(crate) fn nearest(&self, p: Vec3, mut visit: impl FnMut(usize) -> f64) {
        let mut best = f64::INFINITY;
        let mut stack = vec![0usize];
        while let Some(id) = stack.pop() {
            let node = &self.nodes[id];
            if box_distance2(node, p) >= best {
                continue;
            }
            match node.children {
                None => {
                    for &t in &self.order[node.start..node.start + node.count] {
                        best = best.min(visit(t));
                    }
                }
                Some((l, r)) => {
                    let (dl, dr) = (
                        box_distance2(&self.nodes[l], p),
                        box_distance2(&self.nodes[r], p),
                    );
                    // The nearer child is searched first (pushed last).
                    if dl <= dr {
                        stack.push(r);
                        stack.push(l);
                    } else {
                        stack.push(l);
                        stack.push(r);
                    }
                }
            }
        }
    }
}

/// Squared distance from `p` to a node's box (0 inside).
fn box_distance2(node: &Node, p: Vec3) -> f64 {
    let d = (node.min - p).sup(&Vec3::zeros()).sup(&(p - node.max));
    d.norm_squared()
}
