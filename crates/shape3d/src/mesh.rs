//! Triangle meshes: the signed distance by the closest triangle and the
//! angle-weighted pseudo-normal of its nearest feature (face, edge or
//! vertex), so the sign is right for closed meshes and for an open surface
//! patch seen from near it (Baerentzen and Aanaes 2005).
use crate::bvh::Bvh;
use crate::{Object3d, Shape3dError, Vec3};
use std::collections::HashMap;

/// Which part of a triangle a point is nearest.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Feature {
    Face,
    /// The edge from corner k to corner (k + 1) % 3.
    Edge(usize),
    Vertex(usize),
}

/// A triangle mesh in millimetres, counter-clockwise faces seen from
/// outside (outward normals by the right-hand rule).
#[derive(Debug, Clone)]
pub struct TriangleMesh {
    vertices: Vec<Vec3>,
    triangles: Vec<[usize; 3]>,
    face_normals: Vec<Vec3>,
    vertex_normals: Vec<Vec3>,
    edge_normals: HashMap<(usize, usize), Vec3>,
    bvh: Bvh,
}

impl TriangleMesh {
    /// A mesh from vertices (mm) and triangles (vertex indices). Refuses an
    /// empty mesh, an index out of range and a non-finite vertex;
    /// degenerate (zero-area) triangles are dropped.
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[usize; 3]>) -> Result<Self, Shape3dError> {
        let bad = |reason: String| Shape3dError::Mesh {
            format: "triangle",
            reason,
        };
        if let Some(i) = vertices
            .iter()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(bad(format!("vertex {i} is not finite")));
        }
        if let Some(t) = triangles
            .iter()
            .position(|t| t.iter().any(|&i| i >= vertices.len()))
        {
            return Err(bad(format!("triangle {t} names a vertex out of range")));
        }
        let triangles: Vec<[usize; 3]> = triangles
            .into_iter()
            .filter(|t| raw_normal(&vertices, t).norm() > 1e-12)
            .collect();
        if triangles.is_empty() {
            return Err(bad("no triangle with an area".into()));
        }
        let face_normals: Vec<Vec3> = triangles
            .iter()
            .map(|t| raw_normal(&vertices, t).normalize())
            .collect();
        let mut vertex_normals = vec![Vec3::zeros(); vertices.len()];
        let mut edge_normals: HashMap<(usize, usize), Vec3> = HashMap::new();
        for (t, n) in triangles.iter().zip(&face_normals) {
            for k in 0..3 {
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let (u, v) = (vertices[b] - vertices[a], vertices[c] - vertices[a]);
                let angle = u.angle(&v);
                vertex_normals[a] += n * angle;
                *edge_normals.entry((a.min(b), a.max(b))).or_default() += n;
            }
        }
        let corners: Vec<[Vec3; 3]> = triangles
            .iter()
            .map(|t| [vertices[t[0]], vertices[t[1]], vertices[t[2]]])
            .collect();
        Ok(Self {
            bvh: Bvh::new(&corners),
            vertices,
            triangles,
            face_normals,
            vertex_normals,
            edge_normals,
        })
    }

    /// The mesh of the surface z = `f(x, y)` sampled on the square grid
    /// of `step_mm` over [-half, half]^2 (mm), two triangles a cell,
    /// facing up (an open surface: the solid is below it).
    pub fn from_heights(
        half_mm: f64,
        step_mm: f64,
        f: impl Fn(f64, f64) -> f64,
    ) -> Result<Self, Shape3dError> {
        if !(step_mm > 0.0 && half_mm > 0.0 && half_mm / step_mm <= 2000.0) {
            return Err(Shape3dError::Config {
                field: "step_mm",
                value: step_mm,
                reason: "the grid must have 1 to 4000 cells a side",
            });
        }
        let n = (2.0 * half_mm / step_mm).round().max(1.0) as usize;
        let at = |k: usize| -half_mm + 2.0 * half_mm * k as f64 / n as f64;
        let mut vertices = Vec::with_capacity((n + 1) * (n + 1));
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (at(i), at(j));
                vertices.push(Vec3::new(x, y, f(x, y)));
            }
        }
        let id = |i: usize, j: usize| j * (n + 1) + i;
        let mut triangles = Vec::with_capacity(2 * n * n);
        for j in 0..n {
            for i in 0..n {
                triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Self::new(vertices, triangles)
    }

    /// The vertices, mm.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// The triangles (vertex indices).
    pub fn triangles(&self) -> &[[usize; 3]] {
        &self.triangles
    }

    /// Edges shared by two faces whose normals differ by more than
    /// `min_angle_deg`: (the edge's ends, mm, and the two face normals).
    pub fn sharp_edges(&self, min_angle_deg: f64) -> Vec<([Vec3; 2], [Vec3; 2])> {
        let mut faces: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
        for (f, t) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                faces.entry((a.min(b), a.max(b))).or_default().push(f);
            }
        }
        let limit = min_angle_deg.to_radians();
        let mut out: Vec<([Vec3; 2], [Vec3; 2])> = faces
            .into_iter()
            .filter_map(|((a, b), f)| match f[..] {
                [f0, f1] => {
                    let n = [self.face_normals[f0], self.face_normals[f1]];
                    (n[0].angle(&n[1]) > limit).then(|| ([self.vertices[a], self.vertices[b]], n))
                }
                _ => None,
            })
            .collect();
        out.sort_by(|x, y| {
            let key = |e: &([Vec3; 2], [Vec3; 2])| (e.0[0].x, e.0[0].y, e.0[0].z);
            key(x)
                .partial_cmp(&key(y))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        out
    }

    /// The nearest surface point to `p`, its squared distance and the
    /// pseudo-normal of its feature.
    fn nearest(&self, p: Vec3) -> (Vec3, f64, Vec3) {
        let mut best = (p, f64::INFINITY, Vec3::z());
        self.bvh.nearest(p, |f| {
            let t = &self.triangles[f];
            let corners = [
                self.vertices[t[0]],
                self.vertices[t[1]],
                self.vertices[t[2]],
            ];
            let (q, feature) = closest_on_triangle(p, corners);
            let d2 = (p - q).norm_squared();
            if d2 < best.1 {
                let normal = match feature {
                    Feature::Face => self.face_normals[f],
                    Feature::Edge(k) => {
                        let (a, b) = (t[k], t[(k + 1) % 3]);
                        self.edge_normals[&(a.min(b), a.max(b))]
                    }
                    Feature::Vertex(k) => self.vertex_normals[t[k]],
                };
                best = (q, d2, normal);
            }
            d2
        });
        best
    }
}

fn raw_normal(v: &[Vec3], t: &[usize; 3]) -> Vec3 {
    (v[t[1]] - v[t[0]]).cross(&(v[t[2]] - v[t[0]]))
}

/// The point of the triangle `c` nearest `p` and the feature it lies on
/// (the Voronoi regions of the corners, edges and face).
fn closest_on_triangle(p: Vec3, c: [Vec3; 3]) -> (Vec3, Feature) {
    let (a, b, cc) = (c[0], c[1], c[2]);
    let (ab, ac, ap) = (b - a, cc - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (a + ab * (d1 / (d1 - d3)), Feature::Edge(0));
    }
    let cp = p - cc;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (cc, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (a + ac * (d2 / (d2 - d6)), Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (cc - b) * w, Feature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    (a + ab * (vb * denom) + ac * (vc * denom), Feature::Face)
}

impl Object3d for TriangleMesh {
    /// The distance to the nearest triangle, negative when `p` lies
    /// behind the pseudo-normal of the nearest feature.
    fn signed_distance(&self, p: Vec3) -> f64 {
        let (q, d2, n) = self.nearest(p);
        let d = d2.sqrt();
        if (p - q).dot(&n) < 0.0 {
            -d
        } else {
            d
        }
    }

    fn closest_point(&self, p: Vec3) -> Vec3 {
        self.nearest(p).0
    }

    /// The normal of the nearest feature (face, or the pseudo-normal of an
    /// edge or vertex), unit length.
    fn normal(&self, p: Vec3) -> Vec3 {
        self.nearest(p).2.normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hierarchy finds the same distance as visiting every triangle.
    #[test]
    fn the_bvh_finds_the_nearest_triangle() {
        let mesh =
            TriangleMesh::from_heights(20.0, 0.7, |x, y| 2.0 * (0.2 * x).sin() * (0.15 * y).cos())
                .unwrap();
        for k in 0..300 {
            let a = k as f64;
            let p = Vec3::new(
                25.0 * (0.37 * a).sin(),
                25.0 * (0.23 * a).cos(),
                6.0 * (0.71 * a).sin(),
            );
            let brute = mesh
                .triangles
                .iter()
                .map(|t| {
                    let c = [
                        mesh.vertices[t[0]],
                        mesh.vertices[t[1]],
                        mesh.vertices[t[2]],
                    ];
                    (p - closest_on_triangle(p, c).0).norm()
                })
                .fold(f64::INFINITY, f64::min);
            let got = mesh.signed_distance(p).abs();
            assert!((got - brute).abs() < 1e-12, "at {p}: {got} vs {brute}");
        }
    }
}
