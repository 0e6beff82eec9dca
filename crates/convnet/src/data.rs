//! Borrowed views of what a model learns from: grey frames (u8, `count x
//! height x width`, the layout of a dataset's `frames.npy`) and their
//! targets (f64, `count x dim`, frame by frame, in millimetres and
//! degrees as the caller's labels are). Frames may carry each tap's pin
//! displacement vector beside them (f32, `count x dim`, px), which a
//! pins-and-pixels model reads too.
use crate::error::ConvError;
use crate::turns::{TurnedColumns, VectorColumns};

/// `count` grey frames of `height x width` px, row-major, frame after frame.
#[derive(Debug, Clone, Copy)]
pub struct Frames<'a> {
    pixels: &'a [u8],
    count: usize,
    height: usize,
    width: usize,
    /// Each frame's pin displacement vector (`count x dim`), if given.
    pins: Option<(&'a [f32], usize)>,
}

impl<'a> Frames<'a> {
    /// A view of `pixels`, which must hold exactly `count * height * width`
    /// values; frames of zero size are refused.
    pub fn new(
        pixels: &'a [u8],
        count: usize,
        height: usize,
        width: usize,
    ) -> Result<Self, ConvError> {
        if height == 0 || width == 0 {
            return Err(ConvError::FrameSize {
                height: 1,
                width: 1,
                got_height: height,
                got_width: width,
            });
        }
        let expected = count.checked_mul(height * width).ok_or(ConvError::Shape {
            what: "frame pixels",
            expected: usize::MAX,
            got: pixels.len(),
        })?;
        if pixels.len() != expected {
            return Err(ConvError::Shape {
                what: "frame pixels",
                expected,
                got: pixels.len(),
            });
        }
        Ok(Frames {
            pixels,
            count,
            height,
            width,
            pins: None,
        })
    }

    /// The same frames with each one's pin displacement vector: `values`
    /// holds `count x dim` finite numbers, frame by frame (`dim >= 1`).
    pub fn with_pins(self, values: &'a [f32], dim: usize) -> Result<Self, ConvError> {
        if dim == 0 || values.len() != self.count * dim {
            return Err(ConvError::Shape {
                what: "pin values (one row a frame)",
                expected: self.count * dim.max(1),
                got: values.len(),
            });
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(ConvError::PinNonFinite {
                row: i / dim,
                column: i % dim,
                value: values[i] as f64,
            });
        }
        Ok(Frames {
            pins: Some((values, dim)),
            ..self
        })
    }

    /// Values of each frame's pin vector, 0 when the frames carry none.
    pub fn pin_dim(&self) -> usize {
        self.pins.map_or(0, |(_, d)| d)
    }

    /// Frame `i`'s pin displacement vector, if the frames carry them
    /// (panics when `i >= count`).
    pub fn pins(&self, i: usize) -> Option<&'a [f32]> {
        self.pins.map(|(v, d)| &v[i * d..(i + 1) * d])
    }

    /// Number of frames.
    pub fn count(&self) -> usize {
        self.count
    }

    /// `(height, width)` of a frame, px.
    pub fn size(&self) -> (usize, usize) {
        (self.height, self.width)
    }

    /// Frame `i`'s pixels (panics when `i >= count`).
    pub fn frame(&self, i: usize) -> &'a [u8] {
        let len = self.height * self.width;
        &self.pixels[i * len..(i + 1) * len]
    }

    /// Every pixel of every frame.
    pub fn pixels(&self) -> &'a [u8] {
        self.pixels
    }
}

/// `count` rows of `dim` targets, row-major.
#[derive(Debug, Clone, Copy)]
pub struct Targets<'a> {
    values: &'a [f64],
    count: usize,
    dim: usize,
    /// The columns holding an angle's sine, its cosine in the next one
    /// (what a turned frame turns, [`crate::FrameTurns`]); none by default.
    angles: &'a [usize],
    /// Pairs of columns that turn as a vector with the frame; none by default.
    vectors: &'a [VectorColumns],
}

impl<'a> Targets<'a> {
    /// A view of `values` (`count * dim` finite numbers, `dim >= 1`).
    pub fn new(values: &'a [f64], count: usize, dim: usize) -> Result<Self, ConvError> {
        if dim == 0 || values.len() != count * dim {
            return Err(ConvError::Shape {
                what: "target values",
                expected: count * dim.max(1),
                got: values.len(),
            });
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(ConvError::NonFinite {
                row: i / dim,
                column: i % dim,
                value: values[i],
            });
        }
        Ok(Targets {
            values,
            count,
            dim,
            angles: &[],
            vectors: &[],
        })
    }

    /// The same rows, columns `j` and `j + 1` of each `j` in `angles`
    /// an angle's sine and cosine (pairs apart and inside a row).
    pub fn with_angles(self, angles: &'a [usize]) -> Result<Self, ConvError> {
        let mut used = vec![false; self.dim];
        for &j in angles {
            if j + 1 >= self.dim || used[j] || used[j + 1] {
                return Err(ConvError::AngleColumns {
                    column: j,
                    dim: self.dim,
                });
            }
            used[j] = true;
            used[j + 1] = true;
        }
        Ok(Targets { angles, ..self })
    }

    /// The same rows, the columns of each of `vectors` a vector that
    /// turns with the frame (inside a row, apart from each other and from
    /// the angles' columns).
    pub fn with_vectors(self, vectors: &'a [VectorColumns]) -> Result<Self, ConvError> {
        let mut used = vec![false; self.dim];
        for &j in self.angles {
            used[j] = true;
            used[j + 1] = true;
        }
        for v in vectors {
            for j in v.columns {
                if j >= self.dim || used[j] {
                    return Err(ConvError::VectorColumns {
                        column: j,
                        dim: self.dim,
                    });
                }
                used[j] = true;
            }
        }
        Ok(Targets { vectors, ..self })
    }

    /// The columns holding an angle's sine (its cosine next).
    pub fn angles(&self) -> &'a [usize] {
        self.angles
    }

    /// The columns a turn of the frame moves: angles and vectors.
    pub fn columns(&self) -> TurnedColumns<'a> {
        TurnedColumns {
            angles: self.angles,
            vectors: self.vectors,
        }
    }

    /// Number of rows.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Targets a row.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Row `i` (panics when `i >= count`).
    pub fn row(&self, i: usize) -> &'a [f64] {
        &self.values[i * self.dim..(i + 1) * self.dim]
    }
}
