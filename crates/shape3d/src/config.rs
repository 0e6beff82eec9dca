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
