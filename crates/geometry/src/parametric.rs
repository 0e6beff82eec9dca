//! Parametric test contours for corners and concavities (issue 12): sharp
//! rectangles and polar stars r = R + A cos(k phi), named by a short spec
//! (`square:70`, `rect:80,45,20`, `star:35,7,5`), and the training and
//! held-out sets the controller is tuned and judged on.
//!
//! A star's tightest concave radius of curvature, at its valleys, follows
//! from the polar curvature kappa = (r^2 + 2 r'^2 - r r'') / (r^2 + r'^2)^(3/2):
//! in a valley r = R - A, r' = 0 and r'' = A k^2, so
//! kappa = (R - A - A k^2) / (R - A)^2, concave (negative) when
//! A k^2 > R - A, with radius (R - A)^2 / (A (k^2 + 1) - R)
//! ([`ParametricShape::concave_radius_mm`]).
use crate::shapes::sample_curve;
use crate::{Contour, GeometryError, Vec2};
use std::f64::consts::TAU;

/// A contour given by a few numbers, centred on the origin, mm and degrees;
/// written in files as its spec text (`star:35,7,5,0`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum ParametricShape {
    /// A `width_mm` x `height_mm` rectangle with sharp 90-degree corners,
    /// turned counter-clockwise by `rotation_deg`.
    Rect {
        width_mm: f64,
        height_mm: f64,
        rotation_deg: f64,
    },
    /// The polar star r = R + A cos(k (phi - rotation)).
    Star {
        radius_mm: f64,
        amplitude_mm: f64,
        lobes: u32,
        rotation_deg: f64,
    },
}

/// The training set of `tactrace tune`: sharp corners and concave radii
/// of 3.6-20 mm, sizes, lobe counts and rotations unlike the held-out set's.
pub const TRAINING_SET: [&str; 6] = [
    "square:50,15",
    "rect:80,45",
    "star:40,6,5,20",
    "star:36,5,4",
    "star:32,6,6",
    "star:42,3,8,10",
];

/// The held-out set: the contours of issue 12 (a 70 mm square, the 5 mm,
/// 11 mm and 20 mm concave stars), two more, and the report's four
/// shapes; never used in tuning.
pub const HELD_OUT_SET: [&str; 10] = [
    "square:70",
    "rect:90,60,30",
    "star:35,7,5",
    "star:38,3,7",
    "star:40,4,5",
    "star:34,5,6,15",
    "disk",
    "flower",
    "trine",
    "teardrop",
];

impl ParametricShape {
    /// Parse `square:S[,ROT]`, `rect:W,H[,ROT]` or `star:R,A,K[,ROT]`;
    /// `None` when `text` does not start with one of those kinds.
    pub fn parse(text: &str) -> Option<Result<Self, GeometryError>> {
        let (kind, args) = text.trim().split_once(':')?;
        let kind = kind.trim().to_ascii_lowercase();
        if !matches!(kind.as_str(), "square" | "rect" | "star") {
            return None;
        }
        Some(Self::parse_args(&kind, args, text))
    }

    fn parse_args(kind: &str, args: &str, text: &str) -> Result<Self, GeometryError> {
        let bad = |reason: &str| GeometryError::BadShapeSpec {
            spec: text.trim().to_string(),
            reason: reason.to_string(),
        };
        let numbers: Vec<f64> = args
            .split(',')
            .map(|a| a.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad("the values must be numbers separated by commas"))?;
        if numbers.iter().any(|v| !v.is_finite()) {
            return Err(bad("the values must be finite"));
        }
        let shape = match (kind, numbers.as_slice()) {
            ("square", [s]) | ("square", [s, _]) => Self::Rect {
                width_mm: *s,
                height_mm: *s,
                rotation_deg: numbers.get(1).copied().unwrap_or(0.0),
            },
            ("rect", [w, h]) | ("rect", [w, h, _]) => Self::Rect {
                width_mm: *w,
                height_mm: *h,
                rotation_deg: numbers.get(2).copied().unwrap_or(0.0),
            },
            ("star", [r, a, k]) | ("star", [r, a, k, _]) => {
                if k.fract() != 0.0 || *k < 2.0 || *k > 64.0 {
                    return Err(bad("the lobe count K must be a whole number from 2 to 64"));
                }
                Self::Star {
                    radius_mm: *r,
                    amplitude_mm: *a,
                    lobes: *k as u32,
                    rotation_deg: numbers.get(3).copied().unwrap_or(0.0),
                }
            }
            ("square", _) => return Err(bad("expected square:SIDE[,ROTATION_DEG]")),
            ("rect", _) => return Err(bad("expected rect:WIDTH,HEIGHT[,ROTATION_DEG]")),
            _ => {
                return Err(bad(
                    "expected star:R,A,K[,ROTATION_DEG] for r = R + A cos(K phi)",
                ))
            }
        };
        shape.check().map_err(|reason| bad(&reason))?;
        Ok(shape)
    }

    fn check(&self) -> Result<(), String> {
        match *self {
            Self::Rect {
                width_mm,
                height_mm,
                ..
            } => {
                if !(width_mm > 0.0 && height_mm > 0.0) {
                    return Err("the sides must be positive (mm)".into());
                }
            }
            Self::Star {
                radius_mm,
                amplitude_mm,
                ..
            } => {
                if !(amplitude_mm >= 0.0 && radius_mm > amplitude_mm) {
                    return Err("need R > A >= 0 (mm)".into());
                }
            }
        }
        Ok(())
    }

    /// A name safe for folders: `square-70`, `rect-90x60-rot30`,
    /// `star-35-7-5`.
    pub fn name(&self) -> String {
        let (base, rotation) = match *self {
            Self::Rect {
                width_mm,
                height_mm,
                rotation_deg,
            } if width_mm == height_mm => (format!("square-{width_mm}"), rotation_deg),
            Self::Rect {
                width_mm,
                height_mm,
                rotation_deg,
            } => (format!("rect-{width_mm}x{height_mm}"), rotation_deg),
            Self::Star {
                radius_mm,
                amplitude_mm,
                lobes,
                rotation_deg,
            } => (
                format!("star-{radius_mm}-{amplitude_mm}-{lobes}"),
                rotation_deg,
            ),
        };
        if rotation == 0.0 {
            base
        } else {
            format!("{base}-rot{rotation}")
        }
    }

    /// The tightest concave radius of curvature, mm: `None` for a convex
    /// outline, 0 for a concave sharp corner (none here).
    pub fn concave_radius_mm(&self) -> Option<f64> {
        match *self {
            Self::Rect { .. } => None,
            Self::Star {
                radius_mm: r,
                amplitude_mm: a,
                lobes,
                ..
            } => {
                let k2 = f64::from(lobes).powi(2);
                let denominator = a * (k2 + 1.0) - r;
                (denominator > 0.0).then(|| (r - a).powi(2) / denominator)
            }
        }
    }

    /// The closed polygon (rectangles: the four corners; stars sampled as
    /// densely as the built-in shapes).
    pub fn contour(&self) -> Result<Contour, GeometryError> {
        let (points, rotation_deg) = match *self {
            Self::Rect {
                width_mm,
                height_mm,
                rotation_deg,
            } => {
                let (w, h) = (width_mm / 2.0, height_mm / 2.0);
                let corners = [(-w, -h), (w, -h), (w, h), (-w, h)];
                let points = corners.iter().map(|&(x, y)| Vec2::new(x, y)).collect();
                (points, rotation_deg)
            }
            Self::Star {
                radius_mm,
                amplitude_mm,
                lobes,
                rotation_deg,
            } => {
                let k = f64::from(lobes);
                let f = |t: f64| {
                    let r = radius_mm + amplitude_mm * (k * t).cos();
                    Vec2::new(r * t.cos(), r * t.sin())
                };
                let mut points = Vec::new();
                sample_curve(&f, 0.0, TAU, &mut points);
                (points, rotation_deg)
            }
        };
        let (s, c) = rotation_deg.to_radians().sin_cos();
        let turned = points
            .into_iter()
            .map(|p: Vec2| Vec2::new(c * p.x - s * p.y, s * p.x + c * p.y))
            .collect();
        Contour::new(turned)
    }
}

impl std::fmt::Display for ParametricShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Self::Rect {
                width_mm,
                height_mm,
                rotation_deg,
            } => write!(f, "rect:{width_mm},{height_mm},{rotation_deg}"),
            Self::Star {
                radius_mm,
                amplitude_mm,
                lobes,
                rotation_deg,
            } => write!(f, "star:{radius_mm},{amplitude_mm},{lobes},{rotation_deg}"),
        }
    }
}

impl From<ParametricShape> for String {
    fn from(shape: ParametricShape) -> String {
        shape.to_string()
    }
}

impl TryFrom<String> for ParametricShape {
    type Error = GeometryError;
    fn try_from(text: String) -> Result<Self, GeometryError> {
        Self::parse(&text).unwrap_or_else(|| {
            Err(GeometryError::BadShapeSpec {
                spec: text.clone(),
                reason: "expected square:, rect: or star:".into(),
            })
        })
    }
}

/// The named sets of `--shapes`: `training` or `held-out`.
pub fn shape_set(name: &str) -> Option<&'static [&'static str]> {
    match name.trim().to_ascii_lowercase().as_str() {
        "training" => Some(&TRAINING_SET),
        "held-out" | "heldout" => Some(&HELD_OUT_SET),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn star(r: f64, a: f64, k: u32) -> ParametricShape {
        ParametricShape::Star {
            radius_mm: r,
            amplitude_mm: a,
            lobes: k,
            rotation_deg: 0.0,
        }
    }

    #[test]
    fn the_concave_radius_matches_the_polygon() {
        // Fit a circle through three polygon points around a valley.
        for (r, a, k) in [(35.0, 7.0, 5), (38.0, 3.0, 7), (40.0, 4.0, 5)] {
            let shape = star(r, a, k);
            let expected = shape.concave_radius_mm().unwrap();
            let kf = f64::from(k);
            let valley = std::f64::consts::PI / kf;
            let point = |t: f64| {
                let rr = r + a * (kf * t).cos();
                Vec2::new(rr * t.cos(), rr * t.sin())
            };
            let h = 1e-3;
            let (p0, p1, p2) = (point(valley - h), point(valley), point(valley + h));
            let (d1, d2) = (p1 - p0, p2 - p1);
            let cross = d1.x * d2.y - d1.y * d2.x;
            let radius = d1.norm() * d2.norm() * (p2 - p0).norm() / (2.0 * cross.abs());
            assert!(cross < 0.0, "valley of {r},{a},{k} is not concave");
            assert!(
                (radius - expected).abs() < 1e-3 * expected,
                "{radius} vs {expected}"
            );
        }
        assert!((star(35.0, 7.0, 5).concave_radius_mm().unwrap() - 784.0 / 147.0).abs() < 1e-12);
        assert_eq!(star(50.0, 1.0, 3).concave_radius_mm(), None);
    }

    #[test]
    fn specs_parse_and_name_the_shapes() {
        let sq = ParametricShape::parse("square:70").unwrap().unwrap();
        assert_eq!(sq.name(), "square-70");
        let c = sq.contour().unwrap();
        assert!((c.perimeter() - 280.0).abs() < 1e-9);
        let rect = ParametricShape::parse("rect:90,60,30").unwrap().unwrap();
        assert_eq!(rect.name(), "rect-90x60-rot30");
        assert!((rect.contour().unwrap().area() - 5400.0).abs() < 1e-6);
        let st = ParametricShape::parse("Star: 35, 7, 5").unwrap().unwrap();
        assert_eq!(st, star(35.0, 7.0, 5));
        assert!(ParametricShape::parse("disk").is_none());
        assert!(ParametricShape::parse("shapes/a.csv").is_none());
        for bad in [
            "star:35,7",
            "star:7,35,5",
            "square:-3",
            "rect:1,x",
            "star:35,7,2.5",
        ] {
            let e = ParametricShape::parse(bad).unwrap().unwrap_err();
            assert!(e.to_string().contains(bad.trim()), "{e}");
        }
    }

    #[test]
    fn the_sets_are_disjoint_and_every_member_builds() {
        for spec in TRAINING_SET.iter().chain(&HELD_OUT_SET) {
            match crate::ShapeSpec::parse_checked(spec).unwrap() {
                crate::ShapeSpec::Parametric(shape) => drop(shape.contour().unwrap()),
                crate::ShapeSpec::Builtin(_) => {}
                crate::ShapeSpec::File(path) => panic!("{} is no shape", path.display()),
            }
        }
        for spec in TRAINING_SET {
            assert!(!HELD_OUT_SET.contains(&spec));
        }
        assert_eq!(shape_set("held-out").unwrap().len(), HELD_OUT_SET.len());
    }
}
