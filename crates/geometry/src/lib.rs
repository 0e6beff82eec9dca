//! Plane geometry and rigid poses for tactile contour following.
//!
//! Two things live here, both pure (no I/O beyond parsing text handed in):
//! - [`Contour`]: a closed planar outline in millimetres (the report's
//!   appendix shapes, or any CSV of points), with the queries the rest of the
//!   pipeline needs: inside test, signed distance, nearest edge point and its
//!   outward normal, arc-length resampling, perimeter.
//! - [`Pose`]: a 6-DoF pose in millimetres and degrees (x, y, z, then
//!   extrinsic roll/pitch/yaw about fixed x, y, z), with composition and
//!   frame changes done through unit quaternions (report eq. 5.7-5.8).

mod contour;
mod csv;
mod error;
mod parametric;
mod pose;
mod segtree;
mod shapes;
mod validate;

pub use contour::{Contour, EdgePoint, MAX_COORDINATE_MM};
pub use error::GeometryError;
pub use parametric::{shape_set, ParametricShape, HELD_OUT_SET, TRAINING_SET};
pub use pose::Pose;
pub use shapes::{
    builtin_shape, parse_contour_csv, BuiltinShape, ShapeSpec, MAX_CHORD_MM, MAX_SAGITTA_MM,
    TRINE_APEX, TRINE_ARC_T, TRINE_RADIUS_MM,
};

/// A point or vector in the plane, millimetres.
pub type Vec2 = nalgebra::Vector2<f64>;
