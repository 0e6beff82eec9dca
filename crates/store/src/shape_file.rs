//! Turning a `--shape` argument (built-in name or CSV path) into a contour.
use crate::error::{Result, StoreError};
use tactrace_geometry::{builtin_shape, parse_contour_csv, Contour, ShapeSpec};

/// Load the contour a `--shape` value names, with errors naming the file.
pub fn load_shape(spec: &ShapeSpec) -> Result<Contour> {
    match spec {
        ShapeSpec::Builtin(b) => Ok(builtin_shape(*b)),
        ShapeSpec::Parametric(p) => p.contour().map_err(|e| StoreError::Format {
            path: p.to_string().into(),
            reason: e.to_string(),
        }),
        ShapeSpec::File(path) => {
            let looks_like_a_name = path.extension().is_none() && path.components().count() == 1;
            if looks_like_a_name && !path.exists() {
                return Err(StoreError::Format {
                    path: path.clone(),
                    reason: format!(
                        "unknown shape `{}`: not a built-in shape (disk, flower, trine, \
                         teardrop), a parametric one (square:S, rect:W,H, star:R,A,K, each \
                         with an optional rotation in degrees) nor an existing contour file",
                        path.display()
                    ),
                });
            }
            let text = crate::fsutil::read_text(path)?;
            parse_contour_csv(&text).map_err(|e| StoreError::Format {
                path: path.clone(),
                reason: e.to_string(),
            })
        }
    }
}
