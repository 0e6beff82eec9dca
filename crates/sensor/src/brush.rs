//! Brush law of the skin's stick-slip (docs/sensor-model.md, eq. B1-B4):
//! the slide is replayed along its path, and every patch point of the skin
//! in contact holds the object like a bristle.
//!
//! A bristle that touches the object sticks to it, so while the sensor
//! body moves on, the skin there is displaced with the object relative to
//! the body (B1). Friction caps that displacement at the slip ratio zeta
//! times the local indentation (Coulomb: tangential traction <= mu times
//! the normal pressure, both proportional to the displacement and the
//! indentation; B2); a bristle that leaves the contact lets go, one that
//! arrives mid-slide starts unloaded. The pins see the bristles' field
//! spread by the skin (the S5 Gaussian, gain g_l) and the whole membrane's
//! drag by the total traction (gain g_w, radial profile of eq. S7c; B3).
//! Slide, twist, partial slip, load and the edge all enter through the
//! path; nothing depends on the labels.
use crate::contact::Shear;
use tactrace_geometry::Pose;

/// Contact area (mm^2) at which the whole-skin drag per mm of bristle
/// displacement equals `brush_skin_gain` (eq. B3).
pub const REFERENCE_AREA_MM2: f64 = 100.0;

/// The poses of a slide (eq. B1): from where the tap began, `tip` moved
/// back by the sensor-frame `shear`, to `tip`, in `steps` equal steps
/// (translation and yaw interpolated linearly); `steps + 1` poses.
pub fn slide_path(tip: Pose, shear: Shear, steps: usize) -> Vec<Pose> {
    let steps = steps.max(1);
    let (s, c) = tip.rz.to_radians().sin_cos();
    let world = [
        c * shear.dx_mm - s * shear.dy_mm,
        s * shear.dx_mm + c * shear.dy_mm,
    ];
    (0..=steps)
        .map(|k| {
            let left = 1.0 - k as f64 / steps as f64;
            let mut p = tip;
            p.x -= left * world[0];
            p.y -= left * world[1];
            p.rz -= left * shear.drz_deg;
            p
        })
        .collect()
}

/// Where a point fixed to the object, under the body point `h` (sensor
/// frame, mm) at pose `from`, is in the body frame at pose `to`.
fn carried(h: [f64; 2], from: &Pose, to: &Pose) -> [f64; 2] {
    let (s0, c0) = from.rz.to_radians().sin_cos();
    let w = [
        from.x + c0 * h[0] - s0 * h[1],
        from.y + s0 * h[0] + c0 * h[1],
    ];
    let d = [w[0] - to.x, w[1] - to.y];
    let (s1, c1) = to.rz.to_radians().sin_cos();
    [c1 * d[0] + s1 * d[1], -s1 * d[0] + c1 * d[1]]
}

/// Bristle displacements (mm, sensor frame) at the end of the slide
/// (eqs. B1, B2). `horiz[j]` is patch point j's position in the sensor
/// frame; `pens[k][j]` its indentation (mm) at pose `path[k]`;
/// `slip_ratio` is zeta. A bristle in contact at two successive poses is
/// carried with the object, then held to |b| <= zeta pen; out of contact
/// it is unloaded.
pub fn bristles(
    horiz: &[[f64; 2]],
    pens: &[Vec<f64>],
    path: &[Pose],
    slip_ratio: f64,
) -> Vec<[f64; 2]> {
    let mut b = vec![[0.0; 2]; horiz.len()];
    for k in 1..path.len().min(pens.len()) {
        let (before, now) = (&pens[k - 1], &pens[k]);
        for (j, (bj, h)) in b.iter_mut().zip(horiz).enumerate() {
            let pen = now.get(j).copied().unwrap_or(0.0);
            if pen <= 0.0 {
                *bj = [0.0; 2];
                continue;
            }
            if before.get(j).copied().unwrap_or(0.0) > 0.0 {
                let to = carried(*h, &path[k - 1], &path[k]);
                bj[0] += to[0] - h[0];
                bj[1] += to[1] - h[1];
            }
            let size = bj[0].hypot(bj[1]);
            let cap = slip_ratio * pen;
            if size > cap {
                let f = cap / size;
                *bj = [bj[0] * f, bj[1] * f];
            }
        }
    }
    b
}

/// The pins' slip (mm on the skin, sensor frame; eq. B3): the bristle
/// field spread by the skin (`spread[i]`, the S5 Gaussian sum over the
/// bristles) times g_l, plus the whole membrane dragged by the total
/// bristle displacement `total` (mm^3, summed over the contact area) per
/// [`REFERENCE_AREA_MM2`] times g_w and the radial profile `profile[i]`.
pub fn brush_slip(
    spread: &[[f64; 2]],
    total: [f64; 2],
    profile: &[f64],
    (local_gain, skin_gain): (f64, f64),
) -> Vec<[f64; 2]> {
    let drag = [
        skin_gain * total[0] / REFERENCE_AREA_MM2,
        skin_gain * total[1] / REFERENCE_AREA_MM2,
    ];
    spread
        .iter()
        .zip(profile)
        .map(|(s, phi)| {
            [
                local_gain * s[0] + phi * drag[0],
                local_gain * s[1] + phi * drag[1],
            ]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slide(dx: f64, dy: f64, drz: f64) -> Shear {
        Shear {
            dx_mm: dx,
            dy_mm: dy,
            drz_deg: drz,
        }
    }

    #[test]
    fn the_path_ends_at_the_tip_and_starts_one_slide_back() {
        let tip = Pose::planar(3.0, -1.0, -5.0, 90.0);
        let path = slide_path(tip, slide(2.0, 0.0, 4.0), 4);
        assert_eq!(path.len(), 5);
        assert_eq!(path[4], tip);
        // Sensor x at yaw 90 deg is world +y: the start is 2 mm down y.
        assert!((path[0].x - 3.0).abs() < 1e-12 && (path[0].y + 3.0).abs() < 1e-12);
        assert!((path[0].rz - 86.0).abs() < 1e-12);
        assert!((path[2].y + 2.0).abs() < 1e-12 && path[2].z == -5.0);
    }

    #[test]
    fn a_stuck_bristle_moves_with_the_object_against_the_slide() {
        let tip = Pose::planar(0.0, 0.0, -5.0, 30.0);
        let path = slide_path(tip, slide(1.5, -0.5, 0.0), 6);
        let horiz = [[0.0, 0.0], [4.0, 2.0]];
        let pens = vec![vec![1.0, 1.0]; path.len()];
        let b = bristles(&horiz, &pens, &path, 100.0);
        for bj in b {
            assert!(
                (bj[0] + 1.5).abs() < 1e-9 && (bj[1] - 0.5).abs() < 1e-9,
                "{bj:?}"
            );
        }
    }

    #[test]
    fn a_twist_turns_the_stuck_skin_the_other_way() {
        let tip = Pose::planar(0.0, 0.0, -5.0, 0.0);
        let path = slide_path(tip, slide(0.0, 0.0, 2.0), 8);
        let horiz = [[0.0, 0.0], [5.0, 0.0]];
        let pens = vec![vec![1.0, 1.0]; path.len()];
        let b = bristles(&horiz, &pens, &path, 100.0);
        assert!(b[0][0].abs() < 1e-12 && b[0][1].abs() < 1e-12);
        // The body turned +2 deg, so the stuck point at +x lags to -y
        // (to 1e-4 mm: the steps are summed at the patch point, not along
        // the moving material).
        let want = 5.0 * (-2f64).to_radians().sin();
        assert!((b[1][1] - want).abs() < 1e-4, "{:?}", b[1]);
    }

    #[test]
    fn friction_caps_the_bristle_and_losing_contact_unloads_it() {
        let tip = Pose::planar(0.0, 0.0, -5.0, 0.0);
        let path = slide_path(tip, slide(3.0, 0.0, 0.0), 3);
        let horiz = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        // Point 0 always pressed; point 1 lets go at the end; point 2
        // arrives at the last step.
        let pens = vec![
            vec![0.5, 1.0, 0.0],
            vec![0.5, 1.0, 0.0],
            vec![0.5, 1.0, 0.0],
            vec![0.5, 0.0, 1.0],
        ];
        let b = bristles(&horiz, &pens, &path, 2.0);
        assert!(
            (b[0][0] + 1.0).abs() < 1e-12,
            "capped at zeta pen: {:?}",
            b[0]
        );
        assert_eq!(b[1], [0.0; 2]);
        assert_eq!(b[2], [0.0; 2]);
    }

    #[test]
    fn slip_is_the_spread_field_plus_the_profiled_drag() {
        let spread = [[1.0, 0.0], [0.0, 2.0]];
        let profile = [1.0, 0.5];
        let s = brush_slip(&spread, [-200.0, 100.0], &profile, (0.5, 0.25));
        assert_eq!(s[0], [0.5 - 0.5, 0.25]);
        assert_eq!(s[1], [-0.25, 1.0 + 0.125]);
    }
}
