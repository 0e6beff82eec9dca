//! How a labelled collection's sensor is seen when its taps are simulated
//! (`twin`, `calibrate`, `sim-fit`): the rest pins that order every tap,
//! the detector that reads the rendered frames, and the size of the frame
//! they are rendered in, whatever the collection's reference is: an
//! undeformed frame, or a rest layout estimated from the taps (recorded by
//! `import` in a dataset, or estimated here from the collection's frames).
//!
//! Rendered frames are drawn in the preprocessed frame's pixels (where the
//! rest pins are), so they are read by the detector alone, as the
//! preprocessing stage would leave a real frame. The simulator is laid out
//! like the rest pins by [`lay_out`] (`tactrace_sensor::fit_layouts`: a
//! hexagonal lattice and concentric rings both fitted, the better kept).
use crate::error::{LabError, Result};
use crate::import_reader::{self, frame_detector, frame_pins};
use std::path::{Path, PathBuf};
use tactrace_sensor::{fit_layouts, PinLayout, TacTipConfig};
use tactrace_store::collection::{EstimatedRest, Reference};
use tactrace_store::{LabelledCollection, TapFields};
use tactrace_vision::{DetectorParams, FrameDetector, PinReader};

/// The reader of a collection's simulated taps.
pub struct SimSight {
    /// Detector and tracker of the rest pins (their order is every
    /// simulated tap's).
    pub reader: PinReader,
    /// Width and height of the preprocessed frame, px.
    pub frame: (u32, u32),
    /// What the rest pins came from (a frame, a frames folder), for errors.
    pub origin: PathBuf,
}

impl SimSight {
    /// The rest pins, px in the preprocessed frame, in their order.
    pub fn rest(&self) -> &[[f64; 2]] {
        self.reader.tracker().reference()
    }
}

/// Both layouts' fits to a collection's rest pins and the one kept (what
/// `calibrate` and `twin` print).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LayoutReport {
    /// The layout kept.
    pub kept: PinLayout,
    /// The hexagonal lattice: RMS nearest-pin residual (px), every pin paired.
    pub hex: (f64, bool),
    /// The concentric rings: RMS nearest-pin residual (px), every pin paired.
    pub rings: (f64, bool),
}

impl LayoutReport {
    /// One line: both layouts' residuals and the one kept.
    pub fn describe(&self) -> String {
        let kind = |k: PinLayout| match k {
            PinLayout::Hex => "hexagonal lattice",
            PinLayout::Rings => "concentric rings",
        };
        let fit = |(px, paired): (f64, bool)| {
            format!(
                "{px:.2} px{}",
                if paired {
                    ", every pin paired"
                } else {
                    ", not paired"
                }
            )
        };
        format!(
            "pin layout: {} kept (hexagonal lattice {}; concentric rings {})",
            kind(self.kept),
            fit(self.hex),
            fit(self.rings)
        )
    }
}

/// The simulated taps' reader of `collection`: its reference frame's pins
/// or its estimated rest layout, its sensor settings or blob detector. A
/// reference still to be estimated is estimated here from the
/// collection's frames (see [`resolve_reference`] to do it once).
pub fn sim_sight(collection: &LabelledCollection) -> Result<SimSight> {
    let sight = collection.sight();
    let (detector, rest, origin) = match collection.reference() {
        Reference::Frame(path) => {
            let detector = frame_detector(sight, collection.blob(), path)?;
            let rest = frame_pins(&detector, sight.is_some(), path)?;
            (detector, rest, path.clone())
        }
        Reference::Estimated(e) => {
            let first = first_frame(collection.frames())?;
            let detector = frame_detector(sight, collection.blob(), &first)?;
            (detector, e.pins.clone(), collection.frames().to_path_buf())
        }
        Reference::Estimate { .. } => {
            let (resolved, _) = resolve_reference(collection.clone())?;
            return sim_sight(&resolved);
        }
    };
    let [w, h] = detector.stage().output_size();
    Ok(SimSight {
        reader: reader_of(detector, rest, &origin)?,
        frame: (w, h),
        origin,
    })
}

fn reader_of(detector: FrameDetector, rest: Vec<[f64; 2]>, origin: &Path) -> Result<PinReader> {
    PinReader::new(detector, rest).map_err(|e| LabError::Format {
        path: origin.to_path_buf(),
        reason: format!("the reference pins: {e}"),
    })
}

/// `collection` with a reference to be estimated ([`Reference::Estimate`])
/// replaced by the rest layout estimated from its rows' frames (up to
/// [`import_reader::REST_FRAMES`], spread evenly), and that estimate;
/// any other reference is kept.
pub fn resolve_reference(
    collection: LabelledCollection,
) -> Result<(LabelledCollection, Option<EstimatedRest>)> {
    if !matches!(collection.reference(), Reference::Estimate { .. }) {
        return Ok((collection, None));
    }
    let rows = collection.read_rows(TapFields::NONE)?;
    let frames = collection.frames();
    if let Some(err) = rows
        .first()
        .and_then(|r| crate::import_checks::frames_folder(frames, &r.image))
    {
        return Err(err);
    }
    let paths: Vec<PathBuf> = rows.iter().map(|r| frames.join(&r.image)).collect();
    let opened = import_reader::open(&collection, &paths)?;
    let estimated = opened.estimated.clone();
    Ok((collection.with_reference(opened.reference), estimated))
}

/// The first image file (by name) in the folder `dir`: the frames' size.
fn first_frame(dir: &Path) -> Result<PathBuf> {
    let bad = |reason: String| LabError::Format {
        path: dir.to_path_buf(),
        reason,
    };
    let entries = std::fs::read_dir(dir).map_err(|e| {
        bad(format!(
            "cannot list the frames the rest layout was estimated from ({e}); they give the \
             frame size"
        ))
    })?;
    let mut images: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension().and_then(|x| x.to_str()).is_some_and(|x| {
                ["png", "jpg", "jpeg", "bmp", "tif", "tiff"]
                    .contains(&x.to_ascii_lowercase().as_str())
            })
        })
        .collect();
    images.sort();
    images
        .into_iter()
        .next()
        .ok_or_else(|| bad("no frame in the folder: one gives the frame size".into()))
}

/// `sensor` laid out like the rest pins of `sight` (`fit_layouts`: the
/// ring count from the pin count, the frame size, a hexagonal lattice and
/// concentric rings both fitted, the better kept), with both fits.
pub fn lay_out(sensor: &TacTipConfig, sight: &SimSight) -> Result<(TacTipConfig, LayoutReport)> {
    let rest = sight.rest();
    let what = if sight.origin.is_file() {
        "not an undeformed frame of a TacTip"
    } else {
        "not the rest layout of a TacTip"
    };
    let fit = fit_layouts(sensor, rest, sight.frame).map_err(|e| LabError::Reference {
        path: sight.origin.clone(),
        reason: format!(
            "{what}: its {} pins cannot be laid out as a hexagonal lattice or concentric \
             rings; give the sensor's frame taken without contact or an imported dataset as \
             --reference, or settings that find its pins (--params, --sensor)",
            rest.len()
        ),
        source: Box::new(e),
    })?;
    let report = LayoutReport {
        kept: fit.layout(),
        hex: (fit.hex.residual_px, fit.hex.matched),
        rings: (fit.rings.residual_px, fit.rings.matched),
    };
    Ok((fit.config, report))
}

/// A calibrated sensor's detector: its sensor settings' (the blob detector
/// or the small-pin one), else its blob detector.
pub fn sensor_detect(spec: &tactrace_store::sensor_file::SensorSpec) -> DetectorParams {
    match &spec.sight {
        Some(s) => s.detect.clone(),
        None => DetectorParams::Blobs(spec.blob.clone()),
    }
}

/// A calibrated sensor's detector on frames of its simulator's size, over
/// the rest pins `rest` (from `origin`).
pub fn sensor_sight(
    spec: &tactrace_store::sensor_file::SensorSpec,
    rest: Vec<[f64; 2]>,
    origin: &Path,
) -> Result<SimSight> {
    let camera = &spec.sensor.camera;
    let params = tactrace_vision::SightParams {
        preprocess: Default::default(),
        detect: sensor_detect(spec),
    };
    let detector = params
        .check(camera.width, camera.height)
        .map_err(|e| LabError::Format {
            path: origin.to_path_buf(),
            reason: format!("the sensor's detector: {e}"),
        })?;
    let reader = PinReader::new(detector, rest).map_err(|e| LabError::Format {
        path: origin.to_path_buf(),
        reason: format!("the reference pins: {e}"),
    })?;
    Ok(SimSight {
        reader,
        frame: (camera.width, camera.height),
        origin: origin.to_path_buf(),
    })
}

/// The reader of a calibrated sensor's simulated taps (`collect`,
/// `follow`, `bench`, `reproduce` with `--sensor`): its detector (its
/// sensor settings' or its blob detector) over its own reference pins,
/// whether they came from an undeformed frame or were estimated from the
/// taps (its `reference.png` is then the simulator's rest frame, which is
/// not read).
pub fn of_sensor(sensor: &tactrace_store::SensorFolder) -> Result<SimSight> {
    let spec = &sensor.spec;
    sensor_sight(spec, spec.reference_pins.clone(), &sensor.source)
}
