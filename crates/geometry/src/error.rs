//! Typed errors of the geometry crate.

/// What can go wrong building or reading a contour.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    /// A name that is neither a built-in shape nor an existing file.
    #[error("unknown shape `{name}`: expected one of disk, flower, trine, teardrop, or a path to a CSV of x,y points in mm")]
    UnknownShape { name: String },
    /// A parametric shape spec (`star:R,A,K`) that cannot be built.
    #[error("bad shape `{spec}`: {reason}")]
    BadShapeSpec { spec: String, reason: String },
    /// A contour with fewer distinct points than a polygon needs.
    #[error("contour has {points} points; at least {min} are needed")]
    TooFewPoints { points: usize, min: usize },
    /// A CSV line that is not two finite numbers.
    #[error("line {line}: {reason}")]
    BadLine { line: usize, reason: String },
    /// The first and last points are far apart, so the outline is open.
    #[error("contour is not closed: first and last points are {gap_mm:.3} mm apart (max {tolerance_mm:.3} mm); repeat the first point at the end or close the outline")]
    NotClosed { gap_mm: f64, tolerance_mm: f64 },
    /// Two edges of the outline cross.
    #[error("contour intersects itself: edge {a} crosses edge {b}")]
    SelfIntersecting { a: usize, b: usize },
    /// A vertex with a NaN or infinite coordinate.
    #[error("vertex {index} is not finite")]
    NonFinite { index: usize },
    /// A vertex farther from the origin than any rig reaches.
    #[error("vertex {index} lies beyond +-{limit_mm} mm (coordinates are in mm)")]
    OutOfRange { index: usize, limit_mm: f64 },
    /// The contour encloses no area.
    #[error("contour encloses no area")]
    Degenerate,
}
