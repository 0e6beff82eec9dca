//! The serde configuration of a 3D object (millimetres and degrees) and
//! the object it builds.
use crate::{
    Bowl, Cylinder, Dome, Extruded, Foil, HeightField, Object3d, Shape3dError, TriangleMesh,
};
use std::path::PathBuf;
use std::sync::Arc;
use tactrace_geometry::{builtin_shape, BuiltinShape, ParametricShape};

/// A 3D object, as a configuration file or an argument names it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ObjectConfig {
    /// One of the report's four shapes extruded from z = 0 to `height_mm`.
    Extruded { shape: BuiltinShape, height_mm: f64 },
    /// A plane through (0, 0, `height_mm`) rising by `slope_deg` towards
    /// `azimuth_deg` (0: +x).
    Ramp {
        height_mm: f64,
        slope_deg: f64,
        azimuth_deg: f64,
    },
    /// The saddle z = (x^2 - y^2) / (2 `radius_mm`).
    Saddle { radius_mm: f64 },
    /// A spherical cavity in a block's top face z = 0.
    Bowl {
        sphere_radius_mm: f64,
        rim_radius_mm: f64,
    },
    /// The wave z = `amplitude_mm` sin(2 pi s / `wavelength_mm`), s along
    /// `azimuth_deg`.
    Wave {
        amplitude_mm: f64,
        wavelength_mm: f64,
        azimuth_deg: f64,
    },
    /// A thin disk-shaped plate bent into a cylinder (its edge leaves
    /// every plane).
    Foil {
        outline_radius_mm: f64,
        bend_radius_mm: f64,
        thickness_mm: f64,
    },
    /// A parametric outline (`square:60`, `star:35,3,5`) extruded from
    /// z = 0 to `height_mm`.
    Prism {
        outline: ParametricShape,
        height_mm: f64,
    },
    /// A ball of `radius_mm` whose top is at the origin.
    Dome { radius_mm: f64 },
    /// A cylinder of `radius_mm` lying along `azimuth_deg`, its top line
    /// through the origin.
    Cylinder { radius_mm: f64, azimuth_deg: f64 },
    /// The patch z = -(k1 u^2 + k2 v^2) / 2, u along `azimuth_deg`:
    /// principal curvatures `curvatures_per_mm` at the origin (positive
    /// convex, each within +-1/20 per mm).
    Quadric {
        curvatures_per_mm: [f64; 2],
        azimuth_deg: f64,
    },
    /// A triangle mesh read from an STL or OBJ file (mm).
    Mesh { path: PathBuf },
}

/// A built 3D object (shared, thread-safe).
pub type Surface = Arc<dyn Object3d>;

impl ObjectConfig {
    /// Check the values and build the object; a mesh is read from its file
    /// (the only I/O).
    pub fn build(&self) -> Result<Surface, Shape3dError> {
        Ok(match self {
            Self::Extruded { shape, height_mm } => {
                Arc::new(Extruded::new(builtin_shape(*shape), *height_mm)?)
            }
            Self::Ramp {
                height_mm,
                slope_deg,
                azimuth_deg,
            } => Arc::new(HeightField::ramp(*height_mm, *slope_deg, *azimuth_deg)?),
            Self::Saddle { radius_mm } => Arc::new(HeightField::saddle(*radius_mm)?),
            Self::Bowl {
                sphere_radius_mm,
                rim_radius_mm,
            } => Arc::new(Bowl::new(*sphere_radius_mm, *rim_radius_mm)?),
            Self::Wave {
                amplitude_mm,
                wavelength_mm,
                azimuth_deg,
            } => Arc::new(HeightField::wave(
                *amplitude_mm,
                *wavelength_mm,
                *azimuth_deg,
            )?),
            Self::Foil {
                outline_radius_mm,
                bend_radius_mm,
                thickness_mm,
            } => Arc::new(Foil::new(
                *outline_radius_mm,
                *bend_radius_mm,
                *thickness_mm,
            )?),
            Self::Prism { outline, height_mm } => {
                let contour = outline.contour().map_err(|source| Shape3dError::Outline {
                    outline: outline.to_string(),
                    source,
                })?;
                Arc::new(Extruded::new(contour, *height_mm)?)
            }
            Self::Dome { radius_mm } => Arc::new(Dome::new(*radius_mm)?),
            Self::Cylinder {
                radius_mm,
                azimuth_deg,
            } => Arc::new(Cylinder::new(*radius_mm, *azimuth_deg)?),
            Self::Quadric {
                curvatures_per_mm,
                azimuth_deg,
            } => Arc::new(HeightField::quadric(*curvatures_per_mm, *azimuth_deg)?),
            Self::Mesh { path } => Arc::new(TriangleMesh::read(path)?),
        })
    }
}

/// The names [`ObjectConfig::named`] knows, for help and error messages.
pub const OBJECT_NAMES: &str = "plane, ramp, saddle, bowl, wave, foil, disk, flower, trine, \
     teardrop, dome, cylinder, bowl-50, ramp-32, foil-65, an extruded square:S or star:R,A,K";

/// The held-out surfaces (surface_3d): never used to choose a setting
/// (docs/3d.md, "Objects never seen").
pub const HELD_OUT_SURFACES: [&str; 4] = ["dome", "cylinder", "bowl-50", "ramp-32"];

/// The held-out edges (edge_5d): never used to choose a setting.
pub const HELD_OUT_EDGES: [&str; 4] = ["foil-65", "star:35,3,5", "square:60", "bowl-50"];

/// Height of an extruded outline named on the command line, mm (as the
/// report's shapes').
const EXTRUDED_HEIGHT_MM: f64 = 20.0;

impl ObjectConfig {
    /// A built-in object by name (case-insensitive): `plane` (a flat floor
    /// at z = 0), `ramp` (20 deg towards +x), `saddle` (radius 60 mm),
    /// `bowl` (sphere 80 mm, rim 60 mm), `wave` (4 mm high, 60 mm long,
    /// along x), `foil` (outline 40 mm, bent to 80 mm, 3 mm thick) or one
    /// of the report's shapes extruded 20 mm high; the held-out objects
    /// `dome` (radius 60 mm), `cylinder` (radius 40 mm, along y),
    /// `bowl-50` (sphere 50 mm, rim 40 mm), `ramp-32` (32 deg towards
    /// 135 deg), `foil-65` (the foil bent to 65 mm); `None` for any other.
    /// The surfaces are gentle enough for the 40 mm dome to follow them
    /// (slopes of at most about 35 deg over their middle 80 mm; the
    /// held-out ones over their paths).
    pub fn named(name: &str) -> Option<Self> {
        let name = name.trim().to_ascii_lowercase();
        Some(match name.as_str() {
            "plane" => Self::ramp(0.0, 0.0),
            "ramp" => Self::ramp(20.0, 0.0),
            "saddle" => Self::Saddle { radius_mm: 60.0 },
            "bowl" => Self::bowl(80.0, 60.0),
            "wave" => Self::Wave {
                amplitude_mm: 4.0,
                wavelength_mm: 60.0,
                azimuth_deg: 0.0,
            },
            "foil" => Self::foil(80.0),
            "dome" => Self::Dome { radius_mm: 60.0 },
            "cylinder" => Self::Cylinder {
                radius_mm: 40.0,
                azimuth_deg: 90.0,
            },
            "bowl-50" => Self::bowl(50.0, 40.0),
            "ramp-32" => Self::ramp(32.0, 135.0),
            "foil-65" => Self::foil(65.0),
            other => Self::Extruded {
                shape: BuiltinShape::from_name(other)?,
                height_mm: EXTRUDED_HEIGHT_MM,
            },
        })
    }

    /// A ramp through the origin.
    fn ramp(slope_deg: f64, azimuth_deg: f64) -> Self {
        Self::Ramp {
            height_mm: 0.0,
            slope_deg,
            azimuth_deg,
        }
    }

    /// A bowl of sphere and rim radii, mm.
    fn bowl(sphere_radius_mm: f64, rim_radius_mm: f64) -> Self {
        Self::Bowl {
            sphere_radius_mm,
            rim_radius_mm,
        }
    }

    /// The 40 mm, 3 mm thick foil bent to `bend_radius_mm`.
    fn foil(bend_radius_mm: f64) -> Self {
        Self::Foil {
            outline_radius_mm: 40.0,
            bend_radius_mm,
            thickness_mm: 3.0,
        }
    }

    /// A command line's object: a built-in name ([`ObjectConfig::named`]),
    /// a parametric outline extruded 20 mm (`square:60`, `star:35,3,5`;
    /// a malformed one is `None`) or a mesh file (`.stl`, `.obj`); `None`
    /// when it is none of these.
    pub fn from_arg(arg: &str) -> Option<Self> {
        if let Some(named) = Self::named(arg) {
            return Some(named);
        }
        if let Some(outline) = ParametricShape::parse(arg) {
            return Some(Self::Prism {
                outline: outline.ok()?,
                height_mm: EXTRUDED_HEIGHT_MM,
            });
        }
        let path = PathBuf::from(arg);
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        matches!(ext.as_str(), "stl" | "obj").then_some(Self::Mesh { path })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every built-in name builds; a mesh file is known by its extension;
    /// anything else is no object.
    #[test]
    fn named_objects_and_mesh_files() {
        let names = OBJECT_NAMES.split(", ").filter(|n| !n.starts_with("an "));
        for name in names.chain(HELD_OUT_SURFACES).chain(HELD_OUT_EDGES) {
            let cfg = ObjectConfig::from_arg(name).unwrap_or_else(|| panic!("{name}"));
            cfg.build().unwrap_or_else(|e| panic!("{name}: {e}"));
        }
        for edged in HELD_OUT_EDGES {
            let object = ObjectConfig::from_arg(edged).unwrap().build().unwrap();
            assert!(object.edge().is_some(), "{edged} has an edge");
        }
        assert!(matches!(
            ObjectConfig::from_arg("star:35,3,5"),
            Some(ObjectConfig::Prism { height_mm, .. }) if height_mm == EXTRUDED_HEIGHT_MM
        ));
        assert_eq!(ObjectConfig::from_arg("star:35,3"), None);
        assert!(ObjectConfig::named(" Saddle ").is_some());
        assert_eq!(
            ObjectConfig::from_arg("part.STL"),
            Some(ObjectConfig::Mesh {
                path: "part.STL".into()
            })
        );
        assert_eq!(ObjectConfig::from_arg("teapot"), None);
        assert_eq!(ObjectConfig::from_arg("part.ply"), None);
    }
}
