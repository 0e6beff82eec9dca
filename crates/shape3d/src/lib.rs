//! Objects in 3D for tactile surface and edge following.
//!
//! Every object is a solid in the world frame (millimetres; z up) behind
//! one trait, [`Object3d`]: signed distance (negative inside), closest
//! surface point, outward normal, the edge curve of an edged object, and
//! the two queries the simulated TacTip's 3D contact asks (the surface's
//! height along the sensor's axis, and the footprint of an edged top face).
//! The objects:
//! - analytic ([`Extruded`], [`HeightField`]: a tilted ramp, a saddle, a
//!   wave, a quadric patch; [`Bowl`], [`Foil`], [`Dome`], [`Cylinder`]; a
//!   parametric outline extruded), chosen by a serde configuration
//!   ([`ObjectConfig`], millimetres and degrees);
//! - triangle meshes ([`TriangleMesh`]) read from STL or OBJ bytes (the
//!   crate's only I/O is [`TriangleMesh::read`], which reads one file).
//!
//! Pure: no printing, no other files.

mod bowl;
mod bvh;
mod config;
mod edge;
mod error;
mod extruded;
mod feature_frame;
mod foil;
mod height_field;
mod mesh;
mod mesh_io;
mod object;
mod round;

pub use bowl::Bowl;
pub use config::{ObjectConfig, Surface, HELD_OUT_EDGES, HELD_OUT_SURFACES, OBJECT_NAMES};
pub use edge::{EdgeCurve, EdgeSample};
pub use error::Shape3dError;
pub use extruded::Extruded;
pub use feature_frame::{
    feature_frame, normal_error_deg, pose_of_label, surface_point, true_label,
};
pub use foil::Foil;
pub use height_field::{HeightField, MAX_QUADRIC_CURVATURE};
pub use mesh::TriangleMesh;
pub use mesh_io::MeshFormat;
pub use object::{numeric_gradient, Object3d};
pub use round::{Cylinder, Dome};

/// A point or vector in space, millimetres.
pub type Vec3 = nalgebra::Vector3<f64>;
