//! A set of displacement fields: N taps, each a 2P-vector of pin
//! displacements in pixels laid out as all x, then all y (the dataset
//! format's `inputs.npy` rows). Held in f64 for the linear algebra; the
//! boundary is f32 like the datasets.
use crate::error::{CalibError, Result};
use nalgebra::DMatrix;

/// N taps x D coordinates (D = 2P), one tap a row.
#[derive(Debug, Clone, PartialEq)]
pub struct Fields {
    m: DMatrix<f64>,
}

impl Fields {
    /// From row-major N x `dim` values (a dataset's `inputs`). Errors when
    /// the length is not a multiple of `dim`, or on any non-finite value
    /// (`what` names the set in the message).
    pub fn from_flat(flat: &[f32], dim: usize, what: &str) -> Result<Self> {
        if dim == 0 || !flat.len().is_multiple_of(dim) {
            return Err(CalibError::Dimension {
                what: format!("{what}: values a tap"),
                expected: dim,
                found: flat.len(),
            });
        }
        if let Some(k) = flat.iter().position(|v| !v.is_finite()) {
            return Err(CalibError::BadField {
                what: what.into(),
                index: k / dim,
                coord: k % dim,
            });
        }
        let n = flat.len() / dim;
        Ok(Fields {
            m: DMatrix::from_row_iterator(n, dim, flat.iter().map(|&v| v as f64)),
        })
    }

    /// From one vector per tap; all must have the same length.
    pub fn from_rows(rows: &[Vec<f32>], what: &str) -> Result<Self> {
        let dim = rows.first().map_or(0, Vec::len);
        if let Some((i, r)) = rows.iter().enumerate().find(|(_, r)| r.len() != dim) {
            return Err(CalibError::Dimension {
                what: format!("{what}: tap {i} length"),
                expected: dim,
                found: r.len(),
            });
        }
        let flat: Vec<f32> = rows.iter().flatten().copied().collect();
        Self::from_flat(&flat, dim.max(1), what)
    }

    /// Wrap a matrix (taps as rows); errors on non-finite values.
    pub fn from_matrix(m: DMatrix<f64>, what: &str) -> Result<Self> {
        if let Some(k) = m.iter().position(|v| !v.is_finite()) {
            // nalgebra is column-major: k = coord * n + index.
            let n = m.nrows();
            return Err(CalibError::BadField {
                what: what.into(),
                index: k % n,
                coord: k / n,
            });
        }
        Ok(Fields { m })
    }

    /// Number of taps.
    pub fn len(&self) -> usize {
        self.m.nrows()
    }

    /// True when there is no tap.
    pub fn is_empty(&self) -> bool {
        self.m.nrows() == 0
    }

    /// Coordinates a tap (2P).
    pub fn dim(&self) -> usize {
        self.m.ncols()
    }

    /// The matrix, taps as rows.
    pub fn matrix(&self) -> &DMatrix<f64> {
        &self.m
    }

    /// Tap `i` as f32.
    pub fn row(&self, i: usize) -> Vec<f32> {
        self.m.row(i).iter().map(|&v| v as f32).collect()
    }

    /// Row-major f32 values (a dataset's `inputs`).
    pub fn to_flat(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.m.len());
        for i in 0..self.len() {
            out.extend(self.m.row(i).iter().map(|&v| v as f32));
        }
        out
    }

    /// The taps at `rows`, in that order (panics on an index out of range).
    pub fn subset(&self, rows: &[usize]) -> Fields {
        Fields {
            m: self.m.select_rows(rows),
        }
    }
}

/// Errors unless `a` and `b` hold the same number of taps of the same size.
pub(crate) fn check_paired(a: &Fields, b: &Fields) -> Result<()> {
    if a.dim() != b.dim() {
        return Err(CalibError::Dimension {
            what: "coordinates a tap (2 x pins), simulated vs real".into(),
            expected: a.dim(),
            found: b.dim(),
        });
    }
    if a.len() != b.len() {
        return Err(CalibError::Dimension {
            what: "paired taps, simulated vs real".into(),
            expected: a.len(),
            found: b.len(),
        });
    }
    Ok(())
}
