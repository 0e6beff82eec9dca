//! Contact mechanics of the dome pressed onto an extruded object's top face,
//! and the pin motion it causes (docs/sensor-model.md, eqs. S4-S7).
//!
//! The skin is sampled by a hexagonal quadrature patch in surface
//! coordinates. Where the dome dips below the object's top face (z = 0)
//! inside the contour, the penetration is the indentation (eq. S4). An
//! elastic Gaussian kernel spreads it (eq. S5) and pins move down its
//! gradient, away from the pressed region (eq. S6). The pin-patch kernel
//! weights are precomputed, so a tap costs one pass over the contact patch
//! and a few dozen signed-distance queries.
use crate::config::{Mechanics, SlipSpread};
use crate::layout::{hex_lattice, Projection};
use crate::render::floor_i64;
use tactrace_geometry::{Pose, Vec2};

/// A slide the sensor made while in contact, in the sensor frame
/// (mm, mm, deg): the skin sticks to the object and lags behind.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Shear {
    pub dx_mm: f64,
    pub dy_mm: f64,
    pub drz_deg: f64,
}

/// One quadrature point of the skin.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PatchPoint {
    /// Horizontal position in the sensor frame, mm.
    pub horiz: [f64; 2],
    /// Height above the dome's lowest point, mm.
    pub height: f64,
    /// Horizontal distance from the axis, mm.
    pub radius: f64,
}

/// Pin displacements on the skin and the smoothed indentation under each pin.
#[derive(Debug, Clone)]
pub(crate) struct ContactField {
    /// Surface displacement of each pin, mm, sensor frame.
    pub disp: Vec<[f64; 2]>,
    /// Smoothed indentation D at each pin, mm (eq. S5).
    pub smoothed: Vec<f64>,
    /// Contact load P = sum_j p_j dA, the indented volume, mm^3 (eq. S7a).
    pub load_mm3: f64,
    /// Unit normal of the nearest edge into the object (sensor frame)
    /// times the edge's proximity e = clamp(1 - |sd(axis)| / reach, 0, 1)
    /// (eq. S7f); zero when no edge crosses the contact.
    pub edge_normal: [f64; 2],
    /// Cerruti sums at each pin (eq. S7h): [sum p dA / rho,
    /// sum p dA dx dx / rho^3, ... dx dy ..., ... dy dy ...]; empty
    /// unless the slip spread is Cerruti.
    pub cerruti: Vec<[f64; 4]>,
}

impl ContactField {
    /// The part of the state the slip law reads (eq. S7).
    pub fn state(&self) -> crate::slip::ContactState<'_> {
        crate::slip::ContactState {
            smoothed: &self.smoothed,
            load_mm3: self.load_mm3,
            edge_normal: self.edge_normal,
            cerruti: &self.cerruti,
        }
    }
}

/// Precomputed elastic response of every pin to every patch point.
#[derive(Debug, Clone)]
pub(crate) struct ContactModel {
    /// The quadrature patch, sorted by height.
    pub(crate) patch: Vec<PatchPoint>,
    /// `kernel_x[j * pins + i]` = K_x of patch point j on pin i (eq. S6);
    /// likewise K_y and the smoothing weight G (eq. S5). Separate rows keep
    /// the per-tap accumulation a vectorisable pass.
    kernel_x: Vec<f32>,
    kernel_y: Vec<f32>,
    kernel_g: Vec<f32>,
    /// Cerruti weights (eq. S7h) per patch point and pin, in the layout of
    /// `kernel_x`: 1 / rho, dx^2 / rho^3, dx dy / rho^3, dy^2 / rho^3
    /// (times dA); empty unless the slip spread is Cerruti.
    kernel_c: [Vec<f32>; 4],
    pins_g: Vec<[f64; 2]>,
    pub(crate) mech: Mechanics,
}

impl ContactModel {
    /// Lay the patch over the part of the dome within `max_depth_mm` of its
    /// lowest point and tabulate eq. S5/S6 weights for the pins `pins_g`.
    pub fn new(pins_g: Vec<[f64; 2]>, proj: &Projection, radius_mm: f64, mech: &Mechanics) -> Self {
        let h = mech.patch_grid_mm;
        let reach = radius_mm * (1.0 - mech.max_depth_mm / radius_mm).acos();
        let rings = (reach / h).ceil() as usize + 1;
        let mut patch: Vec<([f64; 2], PatchPoint)> = hex_lattice(rings, h)
            .into_iter()
            .filter(|g| g[0].hypot(g[1]) <= reach + 1e-9)
            .map(|g| {
                let (horiz, height) = proj.skin_point(g);
                let radius = horiz[0].hypot(horiz[1]);
                (
                    g,
                    PatchPoint {
                        horiz,
                        height,
                        radius,
                    },
                )
            })
            .collect();
        patch.sort_by(|a, b| a.1.height.total_cmp(&b.1.height));
        let area = 3f64.sqrt() / 2.0 * h * h;
        let widths = (
            mech.flow_core_mm,
            mech.kernel_width_mm,
            mech.flow_screening_per_mm,
        );
        let size = patch.len() * pins_g.len();
        let (mut kernel_x, mut kernel_y, mut kernel_g) = (
            Vec::with_capacity(size),
            Vec::with_capacity(size),
            Vec::with_capacity(size),
        );
        for (gj, _) in &patch {
            for gi in &pins_g {
                let k = kernel_weights(*gi, *gj, widths, area);
                kernel_x.push(k[0]);
                kernel_y.push(k[1]);
                kernel_g.push(k[2]);
            }
        }
        let mut kernel_c: [Vec<f32>; 4] = Default::default();
        if mech.slip_spread == SlipSpread::Cerruti {
            for (gj, _) in &patch {
                for gi in &pins_g {
                    let k = cerruti_weights(*gi, *gj, mech.slip_core_mm, area);
                    for (v, w) in kernel_c.iter_mut().zip(k) {
                        v.push(w);
                    }
                }
            }
        }
        Self {
            kernel_c,
            patch: patch.into_iter().map(|(_, p)| p).collect(),
            kernel_x,
            kernel_y,
            kernel_g,
            pins_g,
            mech: mech.clone(),
        }
    }

    /// Pin displacements for the tip pose `tip` over the object whose top
    /// face is the region `sd(p) < 0` of the plane z = 0 (world frame, mm).
    /// The slide's stick-slip (eq. S7) is added by the caller.
    pub fn field(&self, sd: &dyn Fn(Vec2) -> f64, tip: Pose) -> ContactField {
        let n = self.pins_g.len();
        let mut field = self.no_contact();
        let depth = (-tip.z).min(self.mech.max_depth_mm);
        if depth.is_nan() || depth <= 0.0 {
            return field;
        }
        let (active, reach) = self.active(depth);
        let mut grid = DistanceGrid::new(reach, self.mech.distance_grid_mm, tip);
        let inside = self.inside_fractions(&mut grid, sd, active);
        let depth = self.settle(&inside, depth);
        let area = self.patch_area();
        let (mut ux, mut uy) = (vec![0.0; n], vec![0.0; n]);
        let cerruti = !self.kernel_c[0].is_empty();
        if cerruti {
            field.cerruti = vec![[0.0; 4]; n];
        }
        for (j, (point, chi)) in self.patch.iter().zip(&inside).enumerate() {
            let pen = chi * (depth - point.height);
            if pen > 0.0 {
                field.load_mm3 += pen * area;
                self.accumulate(j, pen, [&mut ux, &mut uy, &mut field.smoothed]);
                if cerruti {
                    self.accumulate_cerruti(j, pen, &mut field.cerruti);
                }
            }
        }
        for ((d, x), y) in field.disp.iter_mut().zip(&ux).zip(&uy) {
            *d = [*x, *y];
        }
        if field.load_mm3 > 0.0 {
            field.edge_normal = edge_normal(&mut grid, sd, reach);
        }
        field
    }

    /// The field of no contact: every pin at rest.
    pub(crate) fn no_contact(&self) -> ContactField {
        let n = self.pins_g.len();
        ContactField {
            disp: vec![[0.0; 2]; n],
            smoothed: vec![0.0; n],
            load_mm3: 0.0,
            edge_normal: [0.0; 2],
            cerruti: Vec::new(),
        }
    }

    /// Patch points that can touch at indentation `depth` (the patch is
    /// sorted by height): their count and horizontal reach, mm.
    fn active(&self, depth: f64) -> (usize, f64) {
        let active = self.patch.partition_point(|p| p.height < depth);
        let reach = self.patch[..active]
            .iter()
            .map(|p| p.radius)
            .fold(0.0, f64::max);
        (active, reach)
    }

    /// Eq. S4a: the depth the compliant dome settles at under the
    /// commanded `depth`, over the first patch points with the inside
    /// fractions `inside` (eq. S4).
    fn settle(&self, inside: &[f64], depth: f64) -> f64 {
        if self.mech.compliance_mm <= 0.0 {
            return depth;
        }
        let area = self.patch_area();
        let points: Vec<(f64, f64)> = self
            .patch
            .iter()
            .zip(inside)
            .map(|(p, chi)| (p.height, chi * area))
            .collect();
        settled_depth(depth, self.mech.compliance_mm / 1000.0, &points)
    }

    /// The inside fractions chi_j (eq. S4) of the first `active` patch
    /// points.
    fn inside_fractions(
        &self,
        grid: &mut DistanceGrid,
        sd: &dyn Fn(Vec2) -> f64,
        active: usize,
    ) -> Vec<f64> {
        self.patch[..active]
            .iter()
            .map(|p| self.inside_fraction(grid, sd, p))
            .collect()
    }

    pub(crate) fn patch_area(&self) -> f64 {
        let h = self.mech.patch_grid_mm;
        3f64.sqrt() / 2.0 * h * h
    }

    /// Eq. S4 at one patch point: the anti-aliased inside-fraction times
    /// the depth below the object's top face.
    fn penetration(
        &self,
        grid: &mut DistanceGrid,
        sd: &dyn Fn(Vec2) -> f64,
        point: &PatchPoint,
        depth: f64,
    ) -> f64 {
        self.inside_fraction(grid, sd, point) * (depth - point.height)
    }

    /// Eq. S4's anti-aliased inside-fraction chi of one patch point.
    fn inside_fraction(
        &self,
        grid: &mut DistanceGrid,
        sd: &dyn Fn(Vec2) -> f64,
        point: &PatchPoint,
    ) -> f64 {
        let h = self.mech.patch_grid_mm;
        (0.5 - grid.interpolate(sd, point.horiz) / h).clamp(0.0, 1.0)
    }

    /// The contact along a slide (eq. B1): the horizontal positions of the
    /// patch points that can touch, and their indentation (eq. S4) at
    /// every pose of `path` (all at the same height).
    pub fn path_contact(&self, sd: &dyn Fn(Vec2) -> f64, path: &[Pose]) -> PathContact {
        let depth = path
            .last()
            .map_or(0.0, |p| (-p.z).min(self.mech.max_depth_mm));
        if depth.is_nan() || depth <= 0.0 {
            return PathContact::default();
        }
        let (active, reach) = self.active(depth);
        let depth = match path.last() {
            Some(last) => {
                let mut grid = DistanceGrid::new(reach, self.mech.distance_grid_mm, *last);
                self.settle(&self.inside_fractions(&mut grid, sd, active), depth)
            }
            None => depth,
        };
        let points = &self.patch[..active];
        let pens = path
            .iter()
            .map(|tip| {
                let mut grid = DistanceGrid::new(reach, self.mech.distance_grid_mm, *tip);
                points
                    .iter()
                    .map(|p| self.penetration(&mut grid, sd, p, depth))
                    .collect()
            })
            .collect();
        PathContact {
            horiz: points.iter().map(|p| p.horiz).collect(),
            pens,
            path: path.to_vec(),
        }
    }

    /// The bristle field as the pins see it (eq. B3): each pin's S5
    /// Gaussian sum of the bristle displacements `b` (one per active
    /// patch point, in patch order), and their total over the contact
    /// area (mm^3).
    pub fn spread_bristles(&self, b: &[[f64; 2]]) -> (Vec<[f64; 2]>, [f64; 2]) {
        let n = self.pins_g.len();
        let (mut sx, mut sy) = (vec![0.0; n], vec![0.0; n]);
        let mut total = [0.0; 2];
        let area = self.patch_area();
        for (j, bj) in b.iter().enumerate() {
            if bj[0] == 0.0 && bj[1] == 0.0 {
                continue;
            }
            total[0] += bj[0] * area;
            total[1] += bj[1] * area;
            let row = &self.kernel_g[j * n..(j + 1) * n];
            for ((x, y), k) in sx.iter_mut().zip(sy.iter_mut()).zip(row) {
                *x += bj[0] * *k as f64;
                *y += bj[1] * *k as f64;
            }
        }
        (sx.into_iter().zip(sy).map(|(x, y)| [x, y]).collect(), total)
    }

    /// Add patch point j's indentation `pen` to every pin's Cerruti sums
    /// (eq. S7h).
    pub(crate) fn accumulate_cerruti(&self, j: usize, pen: f64, sums: &mut [[f64; 4]]) {
        let n = self.pins_g.len();
        for (c, kernel) in self.kernel_c.iter().enumerate() {
            for (s, k) in sums.iter_mut().zip(&kernel[j * n..(j + 1) * n]) {
                s[c] += pen * *k as f64;
            }
        }
    }

    /// Add patch point j's indentation `pen` to every pin (eqs. S5, S6).
    pub(crate) fn accumulate(&self, j: usize, pen: f64, [ux, uy, smoothed]: [&mut Vec<f64>; 3]) {
        let n = self.pins_g.len();
        let flow = 1.0 / self.mech.layer_thickness_mm * pen;
        let rows = j * n..(j + 1) * n;
        for (u, k) in ux.iter_mut().zip(&self.kernel_x[rows.clone()]) {
            *u += flow * *k as f64;
        }
        for (u, k) in uy.iter_mut().zip(&self.kernel_y[rows.clone()]) {
            *u += flow * *k as f64;
        }
        for (u, k) in smoothed.iter_mut().zip(&self.kernel_g[rows]) {
            *u += pen * *k as f64;
        }
    }
}

/// The contact along a slide (eq. B1): see [`ContactModel::path_contact`].
#[derive(Debug, Clone, Default)]
pub(crate) struct PathContact {
    /// Horizontal position of each patch point that can touch, mm.
    pub horiz: Vec<[f64; 2]>,
    /// `pens[k][j]`: indentation of point j at the path's pose k, mm.
    pub pens: Vec<Vec<f64>>,
    /// The path's poses (filled in by the model).
    pub path: Vec<Pose>,
}

/// Solve d + k V(d) = `commanded` for the settled depth d (eq. S4a), where
/// V(d) = sum_j w_j max(0, d - h_j) is the indented volume of patch points
/// at heights h_j with inside-area weights w_j (`points`, sorted by
/// height) and k the compliance, mm per mm^3. V is piecewise linear and
/// rising, so the root is found exactly, segment by segment.
pub(crate) fn settled_depth(commanded: f64, k: f64, points: &[(f64, f64)]) -> f64 {
    let (mut weight, mut moment) = (0.0, 0.0);
    for (m, &(height, w)) in points.iter().enumerate() {
        if height >= commanded {
            break;
        }
        weight += w;
        moment += w * height;
        let next = points.get(m + 1).map_or(commanded, |p| p.0.min(commanded));
        let d = (commanded + k * moment) / (1.0 + k * weight);
        if d <= next {
            return d;
        }
    }
    commanded
}

/// Normal into the object of the edge nearest the sensor's axis (minus the
/// signed distance's gradient there, sensor frame), scaled by the edge's
/// proximity clamp(1 - |sd| / reach, 0, 1) (eq. S7f).
fn edge_normal(grid: &mut DistanceGrid, sd: &dyn Fn(Vec2) -> f64, reach: f64) -> [f64; 2] {
    edge_normal_of(&mut |x, y| grid.interpolate(sd, [x, y]), reach)
}

/// [`edge_normal`] from any interpolated signed distance `at(x, y)` in the
/// sensor's horizontal plane (mm).
pub(crate) fn edge_normal_of(at: &mut dyn FnMut(f64, f64) -> f64, reach: f64) -> [f64; 2] {
    let gx = 0.5 * (at(1.0, 0.0) - at(-1.0, 0.0));
    let gy = 0.5 * (at(0.0, 1.0) - at(0.0, -1.0));
    let size = gx.hypot(gy);
    let proximity = (1.0 - at(0.0, 0.0).abs() / reach.max(1e-9)).clamp(0.0, 1.0);
    if size < 0.5 || !size.is_finite() {
        return [0.0; 2];
    }
    [-gx / size * proximity, -gy / size * proximity]
}

/// Eq. S5/S6 weights of a patch point at `gj` on a pin at `gi`.
///
/// Displacement: the indented gel volume flows sideways in a layer, like a
/// regularised 2-D source, K = dA (gi - gj) / (2 pi (r^2 + c^2)) (divided
/// by the layer thickness later; c = flow core), screened by
/// exp(-s sqrt(r^2 + c^2)) (eq. S6a; s = screening). Smoothing: the
/// unit-mass Gaussian G = dA exp(-r^2 / 2 a^2) / (2 pi a^2) (a = kernel
/// width).
fn kernel_weights(
    gi: [f64; 2],
    gj: [f64; 2],
    (c, a, screening): (f64, f64, f64),
    area: f64,
) -> [f32; 3] {
    let d = [gi[0] - gj[0], gi[1] - gj[1]];
    let r2 = d[0] * d[0] + d[1] * d[1];
    let tau = std::f64::consts::TAU;
    let screen = if screening > 0.0 {
        (-screening * (r2 + c * c).sqrt()).exp()
    } else {
        1.0
    };
    let source = area * screen / (tau * (r2 + c * c));
    let gauss = area * (-r2 / (2.0 * a * a)).exp() / (tau * a * a);
    [(source * d[0]) as f32, (source * d[1]) as f32, gauss as f32]
}

/// Eq. S7h weights of a patch point at `gj` on a pin at `gi`: the
/// surface response of an elastic half-space to a tangential point load
/// (Cerruti), u = (1 - nu) Q / rho + nu d (d . Q) / rho^3 up to a
/// constant, regularised by rho = sqrt(|d|^2 + c^2): dA times [1 / rho,
/// dx^2 / rho^3, dx dy / rho^3, dy^2 / rho^3].
fn cerruti_weights(gi: [f64; 2], gj: [f64; 2], core: f64, area: f64) -> [f32; 4] {
    let d = [gi[0] - gj[0], gi[1] - gj[1]];
    let rho = (d[0] * d[0] + d[1] * d[1] + core * core).sqrt();
    let cube = rho * rho * rho;
    [
        (area / rho) as f32,
        (area * d[0] * d[0] / cube) as f32,
        (area * d[0] * d[1] / cube) as f32,
        (area * d[1] * d[1] / cube) as f32,
    ]
}

/// The object's signed distance sampled lazily on a square grid in the
/// sensor's horizontal plane and interpolated bilinearly (exact for a
/// straight edge).
struct DistanceGrid {
    grid: LazyGrid,
    tip: Pose,
    rot: [f64; 2],
}

impl DistanceGrid {
    fn new(reach: f64, spacing: f64, tip: Pose) -> Self {
        let r = tip.rz.to_radians();
        Self {
            grid: LazyGrid::new(reach, spacing),
            tip,
            rot: [r.cos(), r.sin()],
        }
    }

    fn interpolate(&mut self, sd: &dyn Fn(Vec2) -> f64, q: [f64; 2]) -> f64 {
        let (tip, rot) = (self.tip, self.rot);
        let mut value = |a: f64, b: f64| {
            sd(Vec2::new(
                tip.x + rot[0] * a - rot[1] * b,
                tip.y + rot[1] * a + rot[0] * b,
            ))
        };
        self.grid.interpolate(&mut value, q)
    }
}

/// Values over the sensor's horizontal plane (mm) sampled lazily on a
/// square grid and interpolated bilinearly; a non-finite value is kept as
/// -+1e9 (inside / outside).
pub(crate) struct LazyGrid {
    spacing: f64,
    half: i64,
    values: Vec<f64>,
}

impl LazyGrid {
    /// A grid of `spacing` mm covering the disk of radius `reach` mm.
    pub(crate) fn new(reach: f64, spacing: f64) -> Self {
        let half = (reach / spacing).ceil() as i64 + 1;
        let side = (2 * half + 1) as usize;
        Self {
            spacing,
            half,
            values: vec![f64::NAN; side * side],
        }
    }

    fn node(&mut self, value: &mut dyn FnMut(f64, f64) -> f64, ia: i64, ib: i64) -> f64 {
        let ia = ia.clamp(-self.half, self.half);
        let ib = ib.clamp(-self.half, self.half);
        let side = 2 * self.half + 1;
        let k = ((ib + self.half) * side + ia + self.half) as usize;
        if self.values[k].is_nan() {
            let v = value(ia as f64 * self.spacing, ib as f64 * self.spacing);
            self.values[k] = if v.is_finite() {
                v
            } else if v < 0.0 {
                -1e9
            } else {
                1e9
            };
        }
        self.values[k]
    }

    /// The bilinear interpolation at `q` (mm) of `value(a, b)`, the value
    /// at the node (a, b) of the sensor's plane (mm).
    pub(crate) fn interpolate(
        &mut self,
        value: &mut dyn FnMut(f64, f64) -> f64,
        q: [f64; 2],
    ) -> f64 {
        let (u, v) = (q[0] / self.spacing, q[1] / self.spacing);
        let (ia, ib) = (floor_i64(u), floor_i64(v));
        let (fu, fv) = (u - ia as f64, v - ib as f64);
        let v00 = self.node(value, ia, ib);
        let v10 = self.node(value, ia + 1, ib);
        let v01 = self.node(value, ia, ib + 1);
        let v11 = self.node(value, ia + 1, ib + 1);
        let top = v00 + fu * (v10 - v00);
        let bottom = v01 + fu * (v11 - v01);
        top + fv * (bottom - top)
    }
}

#[cfg(test)]
mod tests {
    use super::settled_depth;

    /// The residual d + k V(d) - commanded of eq. S4a.
    fn residual(d: f64, k: f64, commanded: f64, points: &[(f64, f64)]) -> f64 {
        let volume: f64 = points.iter().map(|&(h, w)| w * (d - h).max(0.0)).sum();
        d + k * volume - commanded
    }

    #[test]
    fn the_settled_depth_solves_eq_s4a_exactly() {
        let points: Vec<(f64, f64)> = (0..40)
            .map(|j| (0.15 * j as f64, 1.0 + (j % 7) as f64 * 0.3))
            .collect();
        for (k, commanded) in [(1e-4, 5.0), (2e-3, 5.0), (0.05, 3.3), (1.0, 6.5)] {
            let d = settled_depth(commanded, k, &points);
            assert!(
                residual(d, k, commanded, &points).abs() < 1e-9,
                "k {k}: d {d}"
            );
            assert!(
                d > 0.0 && d < commanded,
                "k {k}: {d} not in (0, {commanded})"
            );
        }
    }

    #[test]
    fn a_rigid_mount_or_no_contact_keeps_the_commanded_depth() {
        let points = [(0.0, 2.0), (1.0, 3.0)];
        assert_eq!(settled_depth(4.0, 0.0, &points), 4.0);
        assert_eq!(settled_depth(4.0, 0.1, &[]), 4.0);
        assert_eq!(settled_depth(4.0, 0.1, &[(4.5, 1.0)]), 4.0);
    }

    #[test]
    fn one_flat_patch_settles_at_the_spring_divider() {
        // V(d) = A d for a flat patch at height 0: d = D / (1 + k A).
        let d = settled_depth(6.0, 0.01, &[(0.0, 50.0)]);
        assert!((d - 6.0 / 1.5).abs() < 1e-12, "{d}");
    }

    #[test]
    fn a_stiffer_mount_or_wider_contact_settles_deeper_or_shallower_as_it_should() {
        let narrow = [(0.0, 10.0), (1.0, 10.0)];
        let wide = [(0.0, 30.0), (1.0, 30.0)];
        let soft = settled_depth(5.0, 0.01, &narrow);
        assert!(settled_depth(5.0, 0.001, &narrow) > soft);
        assert!(settled_depth(5.0, 0.01, &wide) < soft);
    }
}
