//! Turning a `--shape` argument (built-in name or CSV path) into a contour.
use crate::error::{LabError, Result};
use tactrace_geometry::{builtin_shape, parse_contour_csv, Contour, GeometryError, ShapeSpec};

/// Load the contour a `--shape` value names, with errors naming the file.
pub fn load_shape(spec: &ShapeSpec) -> Result<Contour> {
    match spec {
        ShapeSpec::Builtin(b) => Ok(builtin_shape(*b)),
        ShapeSpec::File(path) => {
            if !path.exists() {
                return Err(GeometryError::UnknownShape {
                    name: path.display().to_string(),
                }
                .into());
            }
            let text = crate::fsutil::read_text(path)?;
            parse_contour_csv(&text).map_err(|e| LabError::Format {
                path: path.clone(),
                reason: e.to_string(),
            })
        }
    }
}
