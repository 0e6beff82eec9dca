//! Contact mechanics of the dome pressed into a 3D object at any tilt
//! (docs/3d.md, eqs. C1-C3): the indentation of eq. S4 read along the
//! sensor's axis from the object's surface, then the same smoothing, gel
//! flow, compliance and edge state (eqs. S4a-S7f) as the planar contact.
//!
//! The planar contact (`ContactModel::field`) is the case of an object
//! whose upper surface stands at one height over every column: the same
//! penetrations, in the same order, give the same field.
use crate::contact::{edge_normal_of, settled_depth, ContactField, ContactModel, LazyGrid};
use nalgebra::{Isometry3, Point3};
use tactrace_geometry::Pose;
use tactrace_shape3d::{Object3d, Vec3};

/// The tip's placement: its isometry and the sensor's axis in the world.
struct Placement {
    iso: Isometry3<f64>,
    axis: Vec3,
}

impl Placement {
    fn new(tip: Pose) -> Self {
        let iso = tip.to_isometry();
        let axis = iso.rotation * Vec3::z();
        Self { iso, axis }
    }

    /// The world point of the sensor's horizontal plane at (a, b) mm.
    fn foot(&self, a: f64, b: f64) -> Vec3 {
        (self.iso * Point3::new(a, b, 0.0)).coords
    }
}

/// One patch point that touches: its index, its height shifted by the
/// column's surface (h_j - (T_j - T_max)) and its inside fraction chi_j.
struct Touch {
    index: usize,
    shifted: f64,
    inside: f64,
}

/// A tip pose pressed into an object: the touching patch points, the
/// highest column and the rim grid (eqs. C1, C2).
struct Pressed {
    touches: Vec<Touch>,
    reference: f64,
    grid: LazyGrid,
    place: Placement,
}

impl ContactModel {
    /// Pin displacements for the tip at `tip` (world frame: the dome's
    /// lowest point, mm; the sensor's orientation, deg, its z axis along
    /// the dome's axis from the skin into the sensor) pressed into
    /// `object`. Eqs. C1-C3, then S4a-S7f as [`Self::field`].
    pub fn field_3d(&self, object: &dyn Object3d, tip: Pose) -> ContactField {
        let mut field = self.no_contact();
        let Some(mut pressed) = self.press(object, tip) else {
            return field;
        };
        let depth = self.settle_3d(&pressed.touches, pressed.reference);
        let area = self.patch_area();
        let (mut ux, mut uy) = (vec![0.0; field.disp.len()], vec![0.0; field.disp.len()]);
        let cerruti = self.mech.slip_spread == crate::SlipSpread::Cerruti;
        if cerruti {
            field.cerruti = vec![[0.0; 4]; field.disp.len()];
        }
        let mut touch_reach: f64 = 0.0;
        for t in &pressed.touches {
            let pen = t.inside * (depth - t.shifted);
            touch_reach = touch_reach.max(self.patch[t.index].radius);
            if pen > 0.0 {
                field.load_mm3 += pen * area;
                self.accumulate(t.index, pen, [&mut ux, &mut uy, &mut field.smoothed]);
                if cerruti {
                    self.accumulate_cerruti(t.index, pen, &mut field.cerruti);
                }
            }
        }
        for ((d, x), y) in field.disp.iter_mut().zip(&ux).zip(&uy) {
            *d = [*x, *y];
        }
        if field.load_mm3 > 0.0 {
            let max = self.mech.max_depth_mm;
            let place = &pressed.place;
            let mut footprint = |a: f64, b: f64| footprint_at(object, place, max, a, b);
            let grid = &mut pressed.grid;
            let mut at = |x: f64, y: f64| grid.interpolate(&mut footprint, [x, y]);
            field.edge_normal = edge_normal_of(&mut at, touch_reach);
        }
        field
    }

    /// The contact along a slide (eq. B1 in 3D): the slide `shear` in the
    /// sensor's plane ending at `tip`, as planar poses in the tip's frame
    /// (the brush law reads only their relative motion), and the
    /// indentation of every patch point at each, all settled as the tip
    /// (eq. C3).
    pub fn path_contact_3d(
        &self,
        object: &dyn Object3d,
        tip: Pose,
        shear: crate::Shear,
        steps: usize,
    ) -> crate::contact::PathContact {
        let path = crate::slide_path(Pose::default(), shear, steps);
        let Some(last) = self.press(object, tip) else {
            return Default::default();
        };
        let settled = self.settle_3d(&last.touches, last.reference);
        let tip_iso = tip.to_isometry();
        let pens = path
            .iter()
            .map(|rel| {
                let mut pens = vec![0.0; self.patch.len()];
                let pose = Pose::from_isometry(&(tip_iso * rel.to_isometry()));
                if let Some(p) = self.press(object, pose) {
                    for t in &p.touches {
                        let shifted = t.shifted - (p.reference - last.reference);
                        pens[t.index] = (t.inside * (settled - shifted)).max(0.0);
                    }
                }
                pens
            })
            .collect();
        crate::contact::PathContact {
            horiz: self.patch.iter().map(|p| p.horiz).collect(),
            pens,
            path,
        }
    }

    /// Eqs. C1, C2 at one tip pose: `None` when nothing touches.
    fn press(&self, object: &dyn Object3d, tip: Pose) -> Option<Pressed> {
        if !tip.is_finite() {
            return None;
        }
        let place = Placement::new(tip);
        let max = self.mech.max_depth_mm;
        // Eq. C1: the height of the object's (top) face over each skin
        // point's column.
        let faces: Vec<f64> = self
            .patch
            .iter()
            .map(|p| {
                let foot = place.foot(p.horiz[0], p.horiz[1]);
                object.face_top(foot, place.axis, max).min(max)
            })
            .collect();
        let reference = faces.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if reference.is_nan() || reference <= 0.0 {
            return None;
        }
        let reach = self.patch.iter().map(|p| p.radius).fold(0.0, f64::max);
        let mut grid = LazyGrid::new(reach, self.mech.distance_grid_mm);
        let mut footprint = |a: f64, b: f64| footprint_at(object, &place, max, a, b);
        let h = self.mech.patch_grid_mm;
        let touches: Vec<Touch> = self
            .patch
            .iter()
            .zip(&faces)
            .enumerate()
            .filter(|(_, (p, face))| **face > p.height)
            .map(|(index, (p, face))| {
                // Eq. C2: the anti-aliased inside fraction of an edged
                // face, or the wall below its rim where that presses more.
                let edge = grid.interpolate(&mut footprint, p.horiz);
                let inside = (0.5 - edge / h).clamp(0.0, 1.0);
                let (top, inside) = if edge > 0.0 {
                    let foot = place.foot(p.horiz[0], p.horiz[1]);
                    let wall = object.column_top(foot, place.axis, max).min(max);
                    // A column that meets the face after all (the
                    // interpolated edge is off by the rim's curvature)
                    // keeps the face's fraction.
                    if wall < *face && wall - p.height > inside * (face - p.height) {
                        (wall, 1.0)
                    } else {
                        (*face, inside)
                    }
                } else {
                    (*face, inside)
                };
                Touch {
                    index,
                    shifted: p.height - (top - reference),
                    inside,
                }
            })
            .collect();
        Some(Pressed {
            touches,
            reference,
            grid,
            place,
        })
    }

    /// Eq. S4a along the axis: the settled depth of the highest column
    /// (the others keep their offsets from it) under the commanded
    /// `reference`.
    fn settle_3d(&self, touches: &[Touch], reference: f64) -> f64 {
        if self.mech.compliance_mm <= 0.0 {
            return reference;
        }
        let area = self.patch_area();
        let mut points: Vec<(f64, f64)> = touches
            .iter()
            .map(|t| (t.shifted, t.inside * area))
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        settled_depth(reference, self.mech.compliance_mm / 1000.0, &points)
    }
}

/// The footprint's signed distance (mm, negative inside; -1e9 for an
/// object without an edged top face) where the column through the
/// sensor-plane point (a, b) meets the object's (extended) top face
/// (eq. C2).
fn footprint_at(object: &dyn Object3d, place: &Placement, max: f64, a: f64, b: f64) -> f64 {
    let foot = place.foot(a, b);
    let top = object.face_top(foot, place.axis, max);
    let at = if top.is_finite() {
        foot + place.axis * top
    } else {
        foot
    };
    object.footprint_distance(at).unwrap_or(-1e9)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{skin_pins, Projection};
    use crate::TacTipConfig;
    use nalgebra::{Unit, UnitQuaternion};
    use tactrace_shape3d::HeightField;

    /// The contact model of a configuration and its pins' skin
    /// coordinates.
    fn model(cfg: &TacTipConfig) -> (ContactModel, Vec<[f64; 2]>) {
        let proj = Projection::new(&cfg.geometry, &cfg.camera);
        let pins = skin_pins(&cfg.geometry);
        let contact = ContactModel::new(
            pins.clone(),
            &proj,
            cfg.geometry.dome_radius_mm,
            &cfg.mechanics,
        );
        (contact, pins)
    }

    /// The pose of the dome's pole at depth `depth` under z = 0, the
    /// sensor tilted by `tilt` deg about the horizontal direction
    /// `azimuth` deg.
    fn tilted(depth: f64, tilt: f64, azimuth: f64) -> Pose {
        let a = azimuth.to_radians();
        let axis = Unit::new_normalize(Vec3::new(a.cos(), a.sin(), 0.0));
        let rotation = UnitQuaternion::from_axis_angle(&axis, tilt.to_radians());
        let iso = Isometry3::from_parts(nalgebra::Translation3::new(0.0, 0.0, -depth), rotation);
        Pose::from_isometry(&iso)
    }

    fn turn(v: [f64; 2], deg: f64) -> [f64; 2] {
        let (s, c) = deg.to_radians().sin_cos();
        [c * v[0] - s * v[1], s * v[0] + c * v[1]]
    }

    /// Theory: a plane is unchanged by a turn about z, so turning the
    /// sensor's tilt direction by 60 deg turns its whole contact field
    /// by 60 deg in the sensor frame: the pin at g moves as the pin at
    /// g turned by 60 deg did, turned by 60 deg. Both layouts are
    /// six-fold symmetric, and so is the quadrature patch, so the turned
    /// field is the same sum in another order (equal to the kernels'
    /// f32 rounding).
    #[test]
    fn a_tilted_plane_s_field_turns_with_the_tilt() {
        let plane = HeightField::ramp(0.0, 0.0, 0.0).unwrap();
        let mut rings = TacTipConfig::default();
        rings.geometry.layout = crate::PinLayout::Rings;
        for cfg in [TacTipConfig::default(), rings] {
            let (contact, pins) = model(&cfg);
            let partner: Vec<usize> = pins
                .iter()
                .map(|g| {
                    let t = turn(*g, 60.0);
                    pins.iter()
                        .position(|h| (h[0] - t[0]).hypot(h[1] - t[1]) < 1e-9)
                        .expect("the layout is six-fold symmetric")
                })
                .collect();
            for (tilt, azimuth, depth) in [(10.0, 0.0, 3.0), (25.0, 37.0, 5.0), (-18.0, 200.0, 1.5)]
            {
                let a = contact.field_3d(&plane, tilted(depth, tilt, azimuth));
                let b = contact.field_3d(&plane, tilted(depth, tilt, azimuth + 60.0));
                assert!(a.load_mm3 > 0.0, "tilt {tilt}: no contact");
                assert!((a.load_mm3 - b.load_mm3).abs() < 1e-9 * a.load_mm3);
                let size = a.disp.iter().map(|d| d[0].hypot(d[1])).fold(0.0, f64::max);
                for (i, &k) in partner.iter().enumerate() {
                    let want = turn(a.disp[i], 60.0);
                    let got = b.disp[k];
                    let err = (want[0] - got[0]).hypot(want[1] - got[1]);
                    // The kernels are tabulated in f32.
                    assert!(
                        err < 1e-5 * size,
                        "tilt {tilt} az {azimuth}: pin {i} off by {err} mm"
                    );
                    assert!((a.smoothed[i] - b.smoothed[k]).abs() < 1e-6);
                }
                // A tilted plane presses off-centre: the field is not the
                // level one.
                let level = contact.field_3d(&plane, tilted(depth, 0.0, 0.0));
                let moved = a
                    .disp
                    .iter()
                    .zip(&level.disp)
                    .map(|(x, y)| (x[0] - y[0]).hypot(x[1] - y[1]))
                    .fold(0.0, f64::max);
                assert!(moved > 0.01, "tilt {tilt}: field equals the level one");
            }
        }
    }
}
