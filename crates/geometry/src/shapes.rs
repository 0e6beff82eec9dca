//! The report's four objects (appendix, with the ERRATA's trine fix) as
//! dense polygons, and the `--shape` argument that names one of them or a
//! CSV file.
//!
//! Curves are sampled adaptively in their parameter until every chord is at
//! most [`MAX_CHORD_MM`] long and its midpoint sagitta at most
//! [`MAX_SAGITTA_MM`], so the polygon stays within about 0.001 mm of the
//! formula everywhere, including the teardrop's sharp point at t = 0.
use crate::{Contour, GeometryError, ParametricShape, Vec2};
use std::f64::consts::{FRAC_PI_2, TAU};
use std::path::PathBuf;

pub use crate::csv::parse_contour_csv;

/// Longest polygon edge on a curved part, mm.
pub const MAX_CHORD_MM: f64 = 0.2;
/// Largest allowed gap between a chord's midpoint and the curve, mm.
pub const MAX_SAGITTA_MM: f64 = 0.001;
/// Trine apex (ERRATA: the sector is built from the apex and the arc).
pub const TRINE_APEX: (f64, f64) = (-37.0, -8.0);
/// Trine arc radius about the apex, mm.
pub const TRINE_RADIUS_MM: f64 = 76.0;
/// Trine arc parameter range (x = 76 sin t - 37, y = 76 cos t - 8).
pub const TRINE_ARC_T: (f64, f64) = (1.41, 3.27);

/// One of the report's built-in objects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BuiltinShape {
    Disk,
    Flower,
    Trine,
    Teardrop,
}

impl BuiltinShape {
    /// All four, in the report's order.
    pub const ALL: [BuiltinShape; 4] = [Self::Disk, Self::Flower, Self::Trine, Self::Teardrop];
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Disk => "disk",
            Self::Flower => "flower",
            Self::Trine => "trine",
            Self::Teardrop => "teardrop",
        }
    }
    /// The built-in with this name (case-insensitive, surrounding spaces ignored).
    pub fn from_name(name: &str) -> Option<BuiltinShape> {
        let name = name.trim();
        Self::ALL
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(name))
    }
    /// The appendix curve point at parameter `t` (radians); for the trine,
    /// the arc only (`t` in [`TRINE_ARC_T`]).
    pub fn curve_point(self, t: f64) -> Vec2 {
        match self {
            Self::Disk => Vec2::new(55.2 * t.cos() + 5.5, 55.2 * t.sin() - 51.5),
            Self::Flower => {
                let r = 1.09 * (50.0 + 6.0 * (5.0 * t - FRAC_PI_2).sin());
                Vec2::new(r * t.cos() + 7.0, r * t.sin() - 52.5)
            }
            Self::Trine => Vec2::new(
                TRINE_RADIUS_MM * t.sin() + TRINE_APEX.0,
                TRINE_RADIUS_MM * t.cos() + TRINE_APEX.1,
            ),
            Self::Teardrop => {
                let half = (t / 2.0).sin().max(0.0);
                Vec2::new(
                    -62.0 * t.cos() - 2.0,
                    51.0 * t.sin() * half.powf(0.9) - 38.0,
                )
            }
        }
    }
    /// Parameter range of the curved part (closed curves: [0, 2 pi)).
    pub fn parameter_range(self) -> (f64, f64) {
        match self {
            Self::Trine => TRINE_ARC_T,
            _ => (0.0, TAU),
        }
    }
}

/// What a `--shape` argument names: a built-in object, a parametric
/// contour (`square:70`, `star:35,7,5`) or a CSV file.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum ShapeSpec {
    Builtin(BuiltinShape),
    Parametric(ParametricShape),
    File(PathBuf),
}

impl ShapeSpec {
    /// Parse a built-in name (case-insensitive), else a parametric spec,
    /// else treat as a path. A malformed parametric spec becomes a path
    /// (that does not exist); [`ShapeSpec::parse_checked`] reports it.
    pub fn parse(s: &str) -> ShapeSpec {
        Self::parse_checked(s).unwrap_or_else(|_| ShapeSpec::File(PathBuf::from(s)))
    }
    /// [`ShapeSpec::parse`] that refuses a malformed parametric spec
    /// (`star:35,7`) with what is wrong.
    pub fn parse_checked(s: &str) -> Result<ShapeSpec, GeometryError> {
        if let Some(shape) = BuiltinShape::from_name(s) {
            return Ok(ShapeSpec::Builtin(shape));
        }
        match ParametricShape::parse(s) {
            Some(shape) => Ok(ShapeSpec::Parametric(shape?)),
            None => Ok(ShapeSpec::File(PathBuf::from(s))),
        }
    }
    /// Display name: the built-in name, the parametric shape's name or the
    /// file stem.
    pub fn name(&self) -> String {
        match self {
            ShapeSpec::Builtin(shape) => shape.name().to_string(),
            ShapeSpec::Parametric(shape) => shape.name(),
            ShapeSpec::File(path) => match path.file_stem() {
                Some(stem) => stem.to_string_lossy().into_owned(),
                None => path.display().to_string(),
            },
        }
    }
}

/// The dense polygon of a built-in shape (appendix formulas).
///
/// Closed curves start at t = 0 (the teardrop's point is vertex 0). The
/// trine starts at its apex, then runs along the arc and back.
pub fn builtin_shape(shape: BuiltinShape) -> Contour {
    let (t0, t1) = shape.parameter_range();
    let f = |t: f64| shape.curve_point(t);
    let mut points = Vec::new();
    if shape == BuiltinShape::Trine {
        points.push(Vec2::new(TRINE_APEX.0, TRINE_APEX.1));
        sample_curve(&f, t0, t1, &mut points);
        points.push(f(t1));
    } else {
        sample_curve(&f, t0, t1, &mut points);
    }
    Contour::from_trusted(points)
}

/// Push points of `f` on [t0, t1) (t0 included, t1 not), refined until
/// chords and sagittas are within bounds.
pub(crate) fn sample_curve(f: &impl Fn(f64) -> Vec2, t0: f64, t1: f64, out: &mut Vec<Vec2>) {
    const PIECES: usize = 256;
    let dt = (t1 - t0) / PIECES as f64;
    for k in 0..PIECES {
        let (a, b) = (
            t0 + k as f64 * dt,
            if k + 1 == PIECES {
                t1
            } else {
                t0 + (k + 1) as f64 * dt
            },
        );
        refine(f, (a, f(a)), (b, f(b)), 0, out);
    }
}

fn refine(
    f: &impl Fn(f64) -> Vec2,
    (a, pa): (f64, Vec2),
    (b, pb): (f64, Vec2),
    depth: u32,
    out: &mut Vec<Vec2>,
) {
    const MAX_DEPTH: u32 = 30;
    let m = 0.5 * (a + b);
    let pm = f(m);
    let chord = (pb - pa).norm();
    let sagitta = (pm - 0.5 * (pa + pb)).norm();
    if depth < MAX_DEPTH && (chord > MAX_CHORD_MM || sagitta > MAX_SAGITTA_MM) {
        refine(f, (a, pa), (m, pm), depth + 1, out);
        refine(f, (m, pm), (b, pb), depth + 1, out);
    } else {
        out.push(pa);
    }
}
