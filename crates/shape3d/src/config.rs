//! The serde configuration of a 3D object (millimetres and degrees) and
//! the object it builds.
use crate::{Bowl, Extruded, Foil, HeightField, Object3d, Shape3dError, TriangleMesh};
use std::path::PathBuf;
use std::sync::Arc;
use tactrace_geometry::{builtin_shape, BuiltinShape};

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
            Self::Mesh { path } => Arc::new(TriangleMesh::read(path)?),
        })
    }
}

/// The names [`ObjectConfig::named`] knows, for help and error messages.
pub const OBJECT_NAMES: &str =
    "plane, ramp, saddle, bowl, wave, foil, disk, flower, trine, teardrop";

impl ObjectConfig {
    /// A built-in object by name (case-insensitive): `plane` (a flat floor
    /// at z = 0), `ramp` (20 deg towards +x), `saddle` (radius 60 mm),
    /// `bowl` (sphere 80 mm, rim 60 mm), `wave` (4 mm high, 60 mm long,
    /// along x), `foil` (outline 40 mm, bent to 80 mm, 3 mm thick) or one
    /// of the report's shapes extruded 20 mm high; `None` for any other.
    /// The surfaces are gentle enough for the 40 mm dome to follow them
    /// (slopes of at most about 35 deg over their middle 80 mm).
    pub fn named(name: &str) -> Option<Self> {
        let name = name.trim().to_ascii_lowercase();
        Some(match name.as_str() {
            "plane" => Self::Ramp {
                height_mm: 0.0,
                slope_deg: 0.0,
                azimuth_deg: 0.0,
            },
            "ramp" => Self::Ramp {
                height_mm: 0.0,
                slope_deg: 20.0,
                azimuth_deg: 0.0,
            },
            "saddle" => Self::Saddle { radius_mm: 60.0 },
            "bowl" => Self::Bowl {
                sphere_radius_mm: 80.0,
                rim_radius_mm: 60.0,
            },
            "wave" => Self::Wave {
                amplitude_mm: 4.0,
                wavelength_mm: 60.0,
                azimuth_deg: 0.0,
            },
            "foil" => Self::Foil {
                outline_radius_mm: 40.0,
                bend_radius_mm: 80.0,
                thickness_mm: 3.0,
            },
            other => Self::Extruded {
                shape: BuiltinShape::from_name(other)?,
                height_mm: 20.0,
            },
        })
    }

    /// A command line's object: a built-in name ([`ObjectConfig::named`])
    /// or a mesh file (`.stl`, `.obj`); `None` when it is neither.
    pub fn from_arg(arg: &str) -> Option<Self> {
        if let Some(named) = Self::named(arg) {
            return Some(named);
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
        for name in OBJECT_NAMES.split(", ") {
            let cfg = ObjectConfig::named(name).unwrap_or_else(|| panic!("{name}"));
            cfg.build().unwrap_or_else(|e| panic!("{name}: {e}"));
        }
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
