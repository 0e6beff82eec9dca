//! Frames and pin extraction: `read_frame` and `PinExtractor` over
//! `tactrace_sensor::read_frame` and `tactrace_vision::PinExtractor`.
use crate::arrays::{contiguous, points_array};
use crate::errors::{core, input};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;
use tactrace_sensor::Frame;
use tactrace_vision::BlobParams;

/// Read a frame file (PNG or any 8-bit image) as a uint8 (H, W) array.
#[pyfunction]
pub fn read_frame<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
    let frame = py
        .detach(|| tactrace_sensor::read_frame(&path))
        .map_err(core)?;
    frame_array(py, frame)
}

/// A frame as a uint8 (H, W) array.
pub fn frame_array(py: Python<'_>, frame: Frame) -> PyResult<Bound<'_, PyArrayDyn<u8>>> {
    let (w, h) = (frame.width() as usize, frame.height() as usize);
    PyArray1::from_vec(py, frame.into_raw()).reshape(vec![h, w])
}

/// A frame from a (H, W) array-like (any dtype, used as uint8) or a path.
pub fn to_frame(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Frame> {
    if let Ok(path) = obj.extract::<PathBuf>() {
        return obj
            .py()
            .detach(|| tactrace_sensor::read_frame(&path))
            .map_err(core);
    }
    let a = contiguous::<u8>(obj, "uint8", name)?;
    let [h, w] = a.shape()[..] else {
        return Err(input(format!(
            "{name} must be a 2-D (H, W) grey image, got shape {}",
            crate::arrays::shape_text(a.shape())
        )));
    };
    let ro = a.readonly();
    Frame::from_raw(w as u32, h as u32, ro.as_slice()?.to_vec())
        .ok_or_else(|| input(format!("{name}: {h} x {w} is not an image size")))
}

/// Blob parameters: a TOML file (OpenCV key names) or a named preset.
pub fn blob_params(params: Option<PathBuf>, preset: &str) -> PyResult<BlobParams> {
    match params {
        Some(p) => {
            let text = tactrace_store::read_text(&p).map_err(crate::errors::store)?;
            BlobParams::from_toml(&text).map_err(|e| {
                input(format!(
                    "{}: invalid blob parameters: {}",
                    p.display(),
                    crate::errors::chain_message(&e)
                ))
            })
        }
        None => BlobParams::preset(preset).map_err(core),
    }
}

/// Pin detection and ordering for one sensor, from its undeformed frame.
///
/// ``reference_frame`` is a (H, W) array or a frame file; its detected
/// pins, in detection order, define the pins and their order (as ``tactrace
/// predict --reference``). ``preset`` names the blob detector parameters
/// ("real256" for real 256 x 256 frames, "sim" for simulated ones, "report",
/// "opencv"); ``params`` a TOML file of them instead.
#[pyclass(module = "tactrace", frozen)]
pub struct PinExtractor {
    inner: tactrace_vision::PinExtractor,
}

#[pymethods]
impl PinExtractor {
    #[new]
    #[pyo3(signature = (reference_frame, *, preset = "real256", params = None))]
    fn new(
        reference_frame: &Bound<'_, PyAny>,
        preset: &str,
        params: Option<PathBuf>,
    ) -> PyResult<Self> {
        let frame = to_frame(reference_frame, "reference_frame")?;
        let blob = blob_params(params, preset)?;
        let inner =
            tactrace_vision::PinExtractor::from_reference_frame(&frame, blob).map_err(core)?;
        Ok(Self { inner })
    }

    /// The reference pins (P x 2 float64, px), in their order.
    #[getter]
    fn reference_pins<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        points_array(py, self.inner.tracker.reference())
    }

    /// The pins of ``frame`` (P x 2 float64, px) in reference order; a pin
    /// not found holds the position its neighbours predict. Raises
    /// ``InputError`` when too few pins are matched.
    fn extract<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let frame = to_frame(frame, "frame")?;
        let tracked = py.detach(|| self.inner.extract(&frame)).map_err(core)?;
        points_array(py, &tracked.pins)
    }

    /// The displacement vector of ``frame`` (2P float32, px): the P
    /// x-displacements, then the P y-displacements from the reference pins,
    /// the input of a model (as in a dataset's ``inputs.npy``).
    fn displacement<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let frame = to_frame(frame, "frame")?;
        let reference = self.inner.tracker.reference();
        let d = py
            .detach(|| {
                self.inner
                    .extract(&frame)
                    .map(|t| t.displacement(reference))
            })
            .map_err(core)?;
        Ok(PyArray1::from_vec(py, d))
    }
}
