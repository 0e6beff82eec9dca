//! What can go wrong building a 3D object: a bad configuration value or a
//! mesh file that cannot be read.
use std::path::PathBuf;

/// Errors of `tactrace-shape3d`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Shape3dError {
    /// A configuration value out of its range.
    #[error("{field} = {value} is out of range: {reason}")]
    Config {
        field: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// A parametric outline that gives no contour.
    #[error("the outline {outline} gives no contour")]
    Outline {
        outline: String,
        #[source]
        source: tactrace_geometry::GeometryError,
    },
    /// A mesh file could not be opened.
    #[error("cannot read the mesh {path}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A mesh file's extension names no format this crate reads.
    #[error("{path}: unknown mesh format (expected .stl or .obj)")]
    UnknownFormat { path: PathBuf },
    /// Mesh bytes that do not parse, or a mesh without triangles or with a
    /// non-finite vertex.
    #[error("bad {format} mesh: {reason}")]
    Mesh {
        format: &'static str,
        reason: String,
    },
}

impl Shape3dError {
    /// True when the error is bad input (every kind is: nothing here runs).
    pub fn is_bad_input(&self) -> bool {
        true
    }
}
