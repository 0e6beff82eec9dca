//! Any TacTip's frames from Python: `preprocess` (a camera image through
//! a sensor file's preprocessing stage), `inspect_sensor` (what
//! `tactrace sensor inspect` proposes) and `PinReader` (a sensor file's
//! preprocessing and detector with rest pins: frames in, ordered pins and
//! displacement vectors out, as `import` reads every frame).
use crate::arrays::{contiguous, json_to_py, points, points_array, py_to_json, shape_text};
use crate::errors::{core, input, lab, store};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use tactrace_lab::import_reader;
use tactrace_lab::sensor_inspect::{frame_files, inspect_frames};
use tactrace_store::{fsutil, SightFile};
use tactrace_vision::{PinReader as Reader, PreprocessParams, SightParams};

/// A camera image from a path (any image file) or an array: (H, W) grey,
/// (H, W, 3) RGB or (H, W, 4) RGBA, any dtype (used as uint8).
fn to_image(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<image::DynamicImage> {
    if let Ok(path) = obj.extract::<PathBuf>() {
        return obj
            .py()
            .detach(|| tactrace_sensor::read_image(&path))
            .map_err(core);
    }
    let a = contiguous::<u8>(obj, "uint8", name)?;
    let shape = a.shape().to_vec();
    let raw = a.readonly().as_slice()?.to_vec();
    let bad = || {
        input(format!(
            "{name}: {} is not an image size",
            shape_text(&shape)
        ))
    };
    let (h, w) = (shape.first().copied(), shape.get(1).copied());
    let (Some(h), Some(w)) = (h, w) else {
        return Err(wrong_shape(name, &shape));
    };
    let (w, h) = (
        u32::try_from(w).map_err(|_| bad())?,
        u32::try_from(h).map_err(|_| bad())?,
    );
    match shape[..] {
        [_, _] => image::GrayImage::from_raw(w, h, raw).map(image::DynamicImage::ImageLuma8),
        [_, _, 3] => image::RgbImage::from_raw(w, h, raw).map(image::DynamicImage::ImageRgb8),
        [_, _, 4] => image::RgbaImage::from_raw(w, h, raw).map(image::DynamicImage::ImageRgba8),
        _ => return Err(wrong_shape(name, &shape)),
    }
    .ok_or_else(bad)
}

fn wrong_shape(name: &str, shape: &[usize]) -> PyErr {
    input(format!(
        "{name} must be a (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA image, got shape {}",
        shape_text(shape)
    ))
}

/// A sensor file's path, or a dict: a whole sensor file's tables, or only
/// its `preprocess` table's keys.
enum SensorArg {
    File(SightFile),
    Preprocess(PreprocessParams),
}

fn sensor_arg(obj: &Bound<'_, PyAny>) -> PyResult<SensorArg> {
    if obj.is_instance_of::<PyDict>() {
        let v = py_to_json(obj, "sensor")?;
        if v.get("sensor").is_some() {
            let text = toml::to_string(&v).map_err(|e| input(format!("sensor: {e}")))?;
            let file = SightFile::from_toml(&text, std::path::Path::new("sensor"));
            return file.map(SensorArg::File).map_err(store);
        }
        let params: PreprocessParams = serde_json::from_value(v)
            .map_err(|e| input(format!("sensor: the preprocess settings: {e}")))?;
        return Ok(SensorArg::Preprocess(params));
    }
    let path: PathBuf = obj
        .extract()
        .map_err(|_| input("sensor must be the path of a sensor file or a dict"))?;
    SightFile::read(&path).map(SensorArg::File).map_err(store)
}

/// ``frame`` through the preprocessing of ``sensor``, as ``import`` and
/// ``predict --image --sensor`` read every frame.
///
/// ``frame`` is a camera image: a (H, W) grey, (H, W, 3) RGB or (H, W, 4)
/// RGBA array (any dtype, used as uint8) or an image file. ``sensor`` is
/// the path of a sensor file (``tactrace sensor inspect --out``; frames
/// of another size than it records are refused), its tables as a dict, or
/// a dict of the ``preprocess`` table's keys alone (``crop``, ``mask``,
/// ``median_blur``, ``threshold``, ``resize``). Returns the (h, w) uint8
/// frame the detector sees.
#[pyfunction]
pub fn preprocess<'py>(
    py: Python<'py>,
    frame: &Bound<'py, PyAny>,
    sensor: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
    let image = to_image(frame, "frame")?;
    let (params, size) = match sensor_arg(sensor)? {
        SensorArg::File(f) => (f.preprocess, Some(f.sensor.frame_size)),
        SensorArg::Preprocess(p) => (p, None),
    };
    let [w, h] = size.unwrap_or([image.width(), image.height()]);
    let stage = params.check().and_then(|p| p.stage(w, h)).map_err(core)?;
    let out = py.detach(|| stage.apply(&image)).map_err(core)?;
    crate::vision::frame_array(py, out)
}

/// What ``tactrace sensor inspect`` proposes for an unknown TacTip.
///
/// ``frames`` is a folder of frames (PNG, JPEG, BMP), an image file, or a
/// list of them; up to 20, spread evenly, are looked at (all one size,
/// grey or colour). ``crop`` ``(x0, y0, x1, y1)`` crops them first. Returns
/// a dict: the sensor file's tables (``sensor``: ``pins``, ``layout``,
/// ``spacing_px``, ``pin_pixels``, ``frame_size``; ``preprocess``;
/// ``detect``), ``rings`` (pins per ring, innermost first, for a
/// ringed layout), ``binary``, ``frames`` (the files inspected) and
/// ``picture`` (what was found over one frame, (H, W, 3) uint8: mask
/// blue, rim yellow, pins green, touching pins orange, left out red).
/// With ``out`` the sensor file is written there (and with ``picture`` the
/// picture as PNG); an existing file is replaced only with ``force=True``.
#[pyfunction]
#[pyo3(signature = (frames, *, crop = None, out = None, picture = None, force = false))]
pub fn inspect_sensor<'py>(
    py: Python<'py>,
    frames: &Bound<'py, PyAny>,
    crop: Option<[u32; 4]>,
    out: Option<PathBuf>,
    picture: Option<PathBuf>,
    force: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let inputs: Vec<PathBuf> = match frames.extract::<PathBuf>() {
        Ok(p) => vec![p],
        Err(_) => frames
            .extract()
            .map_err(|_| input("frames must be a path or a list of paths"))?,
    };
    for (path, flag) in [(&out, "out"), (&picture, "picture")] {
        if let Some(p) = path {
            fsutil::check_output_file(p, force, flag).map_err(store)?;
        }
    }
    let got = py
        .detach(|| frame_files(&inputs).and_then(|f| inspect_frames(&f, crop)))
        .map_err(lab)?;
    let text = got.file.to_toml();
    if let Some(p) = &out {
        fsutil::write_output_file(p, text.as_bytes(), force, "out").map_err(store)?;
    }
    if let Some(p) = &picture {
        let mut bytes = Vec::new();
        image::DynamicImage::ImageRgb8(got.picture.clone())
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .map_err(|e| input(format!("cannot encode the picture: {e}")))?;
        fsutil::write_output_file(p, &bytes, force, "picture").map_err(store)?;
    }
    let mut doc = serde_json::to_value(&got.file).map_err(|e| input(e.to_string()))?;
    if let Some(map) = doc.as_object_mut() {
        let rings = match got.file.sensor.layout {
            tactrace_vision::LayoutKind::Rings => got.inspection.layout.rings.clone(),
            tactrace_vision::LayoutKind::Hexagonal => Vec::new(),
        };
        map.insert("rings".into(), rings.into());
        map.insert("binary".into(), got.inspection.binary.into());
        let names: Vec<String> = got.frames.iter().map(|p| p.display().to_string()).collect();
        map.insert("frames".into(), names.into());
    }
    let dict = json_to_py(py, &doc)?;
    let (w, h) = got.picture.dimensions();
    let pic =
        PyArray1::from_vec(py, got.picture.into_raw()).reshape(vec![h as usize, w as usize, 3])?;
    dict.set_item("picture", pic)?;
    Ok(dict)
}

/// A sensor's frames read into ordered pins: its sensor file's
/// preprocessing and detector, the pins ordered by ``reference_pins``
/// (P x 2 px in the preprocessed frame: a dataset's
/// ``meta["reference_pins"]``, ``Model.reference_pins``), as ``import``
/// reads every frame of a collection and ``predict --image --sensor`` its
/// frame. ``sensor`` is a sensor file's path or its tables as a dict.
#[pyclass(module = "tactrace", frozen)]
pub struct PinReader {
    inner: Reader,
}

#[pymethods]
impl PinReader {
    #[new]
    fn new(sensor: &Bound<'_, PyAny>, reference_pins: &Bound<'_, PyAny>) -> PyResult<Self> {
        let SensorArg::File(file) = sensor_arg(sensor)? else {
            return Err(input(
                "sensor must be a sensor file (its path, or its tables as a dict with \
                 `sensor`, `preprocess` and `detect`)",
            ));
        };
        let rest = points(reference_pins, "reference_pins")?;
        let [w, h] = file.sensor.frame_size;
        let sight: SightParams = file.sight();
        let frames = sight.check(w, h).map_err(core)?;
        Ok(Self {
            inner: Reader::new(frames, rest).map_err(core)?,
        })
    }

    /// The rest pins (P x 2 float64, px), in their order.
    #[getter]
    fn reference_pins<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        points_array(py, self.inner.tracker().reference())
    }

    /// The pins of ``frame`` (a camera image as ``preprocess`` takes it)
    /// in reference order (P x 2 float64, px; a pin not found holds where
    /// its neighbours put it) and how they were found: a dict with
    /// ``matched``, ``split`` (from touching pins) and ``filled``. Raises
    /// ``InputError`` when too few pins are found.
    fn read<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyArrayDyn<f64>>, Bound<'py, PyAny>)> {
        let image = to_image(frame, "frame")?;
        let reading = py
            .detach(|| import_reader::reading_of(&self.inner, &image))
            .map_err(lab)?;
        let counts = serde_json::to_value(reading.counts).map_err(|e| input(e.to_string()))?;
        Ok((
            points_array(py, &reading.tracked.pins)?,
            json_to_py(py, &counts)?,
        ))
    }

    /// The displacement vector of ``frame`` (2P float32, px: the P
    /// x-displacements, then the P y-displacements from the rest pins), as
    /// ``import`` writes it into ``inputs.npy``.
    fn displacement<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let image = to_image(frame, "frame")?;
        let reader = &self.inner;
        let d = py
            .detach(|| {
                import_reader::reading_of(reader, &image)
                    .map(|r| r.tracked.displacement(reader.tracker().reference()))
            })
            .map_err(lab)?;
        Ok(PyArray1::from_vec(py, d))
    }
}
