//! How `import` reads a collection's frames into ordered pins: the
//! preprocessing and detector of its sensor file (or the blob detector on
//! frames taken as they are), checked against the first frame, and the
//! rest layout: the undeformed frame's pins, a layout recorded by an
//! earlier import, or one estimated here from the taps
//! ([`tactrace_vision::estimate_rest`]).
//!
//! A raw colour camera frame read with no sensor file fails here, before
//! any frame is imported, with the command that proposes the settings.
use crate::error::{LabError, Result};
use image::DynamicImage;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use tactrace_sensor::read_image;
use tactrace_servo::ImageInput;
use tactrace_store::collection::{EstimatedRest, Reference};
use tactrace_store::LabelledCollection;
use tactrace_vision::{
    estimate_rest, preprocess::grey_of, BlobParams, Detection, DetectorParams, Frame,
    FrameDetector, PinReader, PreprocessParams, Reading, RestParams, SightParams, TrackCounts,
    VisionError,
};

/// Most taps the rest layout is estimated from (spread over the rows).
pub const REST_FRAMES: usize = 1000;

/// The reader of a collection's frames and the reference it ended with
/// (an estimate made here is [`Reference::Estimated`]).
pub(crate) struct FrameReader {
    pub reader: PinReader,
    pub reference: Reference,
    /// The estimate, when one was made by this import.
    pub estimated: Option<EstimatedRest>,
}

/// The settings that read frames: a sensor file's, or the blob detector
/// `blob` on frames as they are.
fn sight_of(sight: Option<&SightParams>, blob: &BlobParams) -> SightParams {
    sight.cloned().unwrap_or_else(|| SightParams {
        preprocess: Default::default(),
        detect: DetectorParams::Blobs(blob.clone()),
    })
}

/// The error for a colour camera image read with no sensor settings.
pub fn raw_frame_error(path: &Path, image: &image::DynamicImage) -> LabError {
    LabError::Format {
        path: path.to_path_buf(),
        reason: format!(
            "a colour {} x {} camera image, and no sensor settings say how to read it \
             (grey, crop, dome mask, threshold): run `tactrace sensor inspect FRAMES... \
             --out SENSOR.toml` on some of these frames, then pass --sensor SENSOR.toml",
            image.width(),
            image.height()
        ),
    }
}

/// The frame detector for frames like `first` (read here): the sensor
/// settings `sight`, else the blob detector `blob` on frames as they are.
/// Fails early on a raw colour frame with no sensor settings, and on
/// settings made for another frame size.
pub fn frame_detector(
    sight: Option<&SightParams>,
    blob: &BlobParams,
    first: &Path,
) -> Result<FrameDetector> {
    let image = read_image(first)?;
    if sight.is_none() && image.color().has_color() {
        return Err(raw_frame_error(first, &image));
    }
    sight_of(sight, blob)
        .check(image.width(), image.height())
        .map_err(|e| LabError::Format {
            path: first.to_path_buf(),
            reason: format!(
                "the sensor settings cannot read this {} x {} frame: {e}",
                image.width(),
                image.height()
            ),
        })
}

/// The pins `detector` finds in the undeformed frame at `path` (a colour
/// one refused unless `sight_given`).
pub fn frame_pins(
    detector: &FrameDetector,
    sight_given: bool,
    path: &Path,
) -> Result<Vec<[f64; 2]>> {
    let image = read_image(path)?;
    if !sight_given && image.color().has_color() {
        return Err(raw_frame_error(path, &image));
    }
    let frame = seen(detector, &image).map_err(|e| LabError::Format {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    Ok(points(&detector.detector().detect(&frame)))
}

/// The frame the detector sees: through the sensor settings' stage, or,
/// with no preprocessing (no sensor file), the image in grey whatever its
/// size (as the blob detector always read frames).
fn seen(detector: &FrameDetector, image: &DynamicImage) -> std::result::Result<Frame, VisionError> {
    if *detector.stage().params() == PreprocessParams::default() {
        Ok(grey_of(image))
    } else {
        detector.preprocess(image)
    }
}

/// The reader of `collection`'s `frames` (every row's file, in order):
/// its detector and its rest layout, estimated from up to
/// [`REST_FRAMES`] of the frames when the reference says so.
pub(crate) fn open(collection: &LabelledCollection, frames: &[PathBuf]) -> Result<FrameReader> {
    let first = frames.first().ok_or_else(|| LabError::Format {
        path: collection.targets().to_path_buf(),
        reason: "no labelled rows".into(),
    })?;
    let sight = collection.sight();
    let detector = frame_detector(sight, collection.blob(), first)?;
    let (rest, reference, estimated) = match collection.reference() {
        Reference::Frame(path) => (
            frame_pins(&detector, sight.is_some(), path)?,
            collection.reference().clone(),
            None,
        ),
        Reference::Estimated(e) => (e.pins.clone(), collection.reference().clone(), None),
        Reference::Estimate { pins } => {
            let e = estimate(&detector, frames, *pins)?;
            (e.pins.clone(), Reference::Estimated(e.clone()), Some(e))
        }
    };
    let reader = PinReader::new(detector, rest).map_err(|e| LabError::Format {
        path: collection.frames().to_path_buf(),
        reason: format!("the reference pins: {e}"),
    })?;
    Ok(FrameReader {
        reader,
        reference,
        estimated,
    })
}

fn points(d: &Detection) -> Vec<[f64; 2]> {
    d.points.iter().map(|k| [k.x, k.y]).collect()
}

/// The rest layout of `pins` pins (default: the count most frames show)
/// from up to [`REST_FRAMES`] of `frames`, spread evenly.
fn estimate(
    detector: &FrameDetector,
    frames: &[PathBuf],
    pins: Option<usize>,
) -> Result<EstimatedRest> {
    let step = frames.len().div_ceil(REST_FRAMES).max(1);
    let chosen: Vec<&PathBuf> = frames.iter().step_by(step).collect();
    let detections: Vec<Detection> = chosen
        .par_iter()
        .map(|p| {
            let image = read_image(p)?;
            let bad = |e: VisionError| LabError::Format {
                path: p.to_path_buf(),
                reason: e.to_string(),
            };
            let frame = seen(detector, &image).map_err(bad)?;
            let mut d = detector.detector().detect(&frame);
            detector.detector().add_clusters(&frame, &mut d);
            Ok(d)
        })
        .collect::<Result<_>>()?;
    let pins = pins.unwrap_or_else(|| most_common(detections.iter().map(|d| d.points.len())));
    let est =
        estimate_rest(&detections, pins, &RestParams::default()).map_err(|e| LabError::Format {
            path: frames[0].parent().unwrap_or(Path::new(".")).to_path_buf(),
            reason: format!(
                "no rest layout of {pins} pins could be estimated from {} taps: {e}; give the \
                 sensor's undeformed frame as --reference, or a sensor file (--sensor) whose \
                 settings find the pins",
                detections.len()
            ),
        })?;
    Ok(EstimatedRest {
        pins: est.pins,
        residual_px: est.residual,
        frames: detections.len(),
    })
}

/// The most frequent value (the smallest among ties; 0 when none).
fn most_common(values: impl Iterator<Item = usize>) -> usize {
    let mut counts = std::collections::BTreeMap::new();
    for v in values {
        *counts.entry(v).or_insert(0usize) += 1;
    }
    counts
        .into_iter()
        .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
        .map_or(0, |(v, _)| v)
}

/// One frame read: its displacement from the rest pins and its counts.
pub fn read_one(reader: &PinReader, path: &Path) -> Result<(Vec<f32>, TrackCounts)> {
    let (disp, counts, _) = read_one_with_image(reader, path, None)?;
    Ok((disp, counts))
}

/// A frame as the image models see it ([`ImageInput::small`] of the frame
/// the detector sees), with that frame's `[height, width]`.
pub type SmallFrame = (Vec<u8>, [usize; 2]);

/// One frame read with its image: the displacement, the counts and the
/// small frame when asked for.
pub type FrameRead = (Vec<f32>, TrackCounts, Option<SmallFrame>);

/// [`read_one`], with the frame the detector saw made into an image
/// model's input by `input` (made by [`image_input_of`] for `reader`).
pub fn read_one_with_image(
    reader: &PinReader,
    path: &Path,
    input: Option<&ImageInput>,
) -> Result<FrameRead> {
    let image = read_image(path)?;
    let frame = seen(reader.frames(), &image)?;
    let small = input.map(|i| {
        (
            i.small(&frame),
            [frame.height(), frame.width()].map(|v| v as usize),
        )
    });
    let Reading { tracked, counts } = reader.read_preprocessed(&frame)?;
    Ok((
        tracked.displacement(reader.tracker().reference()),
        counts,
        small,
    ))
}

/// The image input of frames read by `reader`: its preprocessing, then
/// area-averaged to `size x size` px (what `frames.npy` holds).
pub fn image_input_of(reader: &PinReader, size: usize) -> Result<ImageInput> {
    Ok(ImageInput::new(
        Some(reader.frames().stage().params()),
        (size, size),
    )?)
}

/// The image in the file at `path` as `input` makes an image model's
/// frames: grey (refused in colour when `input` has no preprocessing: a
/// raw camera frame), preprocessed, area-averaged.
pub fn image_input(input: &ImageInput, path: &Path) -> Result<Vec<u8>> {
    let image = read_image(path)?;
    if input.preprocess().is_none() && image.color().has_color() {
        return Err(raw_frame_error(path, &image));
    }
    input
        .of_frame(&grey_of(&image))
        .map_err(|e| LabError::Format {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })
}

/// A camera image (decoded) read into ordered pins as [`read_one`] reads
/// a frame file (Python's `PinReader`).
pub fn reading_of(reader: &PinReader, image: &DynamicImage) -> Result<Reading> {
    Ok(reader.read_preprocessed(&seen(reader.frames(), image)?)?)
}

/// True for the error of a frame that was read but showed too few pins
/// (the frame is rejected; any other error stops the import).
pub(crate) fn too_few_pins(e: &LabError) -> bool {
    matches!(e, LabError::Vision(VisionError::TooFewPins { .. }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without a sensor file, import reads the 127-pin set as before the
    /// reader (the blob detector's `PinExtractor`), bit for bit.
    #[test]
    fn import_without_a_sensor_file_reads_frames_as_the_pin_extractor_did() {
        let Some(set) = tactrace_testdata::real_edge_set() else {
            return;
        };
        let reference = set.join("frames/init_0.png");
        let blob = BlobParams::preset("real256").unwrap();
        let detector = frame_detector(None, &blob, &reference).unwrap();
        let rest = frame_pins(&detector, false, &reference).unwrap();
        let reader = PinReader::new(detector, rest).unwrap();
        let frame = tactrace_sensor::read_frame(&reference).unwrap();
        let extractor = tactrace_vision::PinExtractor::from_reference_frame(&frame, blob).unwrap();
        assert_eq!(reader.tracker().reference(), extractor.tracker.reference());
        let mut frames: Vec<PathBuf> = std::fs::read_dir(set.join("frames"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.to_string_lossy().ends_with("_0.png"))
            .collect();
        frames.sort();
        assert!(frames.len() > 3000, "{}", frames.len());
        for path in frames.iter().step_by(150) {
            let n = path.display();
            let (got, counts) = read_one(&reader, path).unwrap();
            let tracked = extractor
                .extract(&tactrace_sensor::read_frame(path).unwrap())
                .unwrap();
            assert_eq!(
                got,
                tracked.displacement(extractor.tracker.reference()),
                "{n}"
            );
            assert_eq!(counts.filled, tracked.missing, "{n}");
        }
    }

    #[test]
    fn most_common_takes_the_smallest_of_ties() {
        assert_eq!(most_common([3, 5, 5, 3, 4].into_iter()), 3);
        assert_eq!(most_common([7, 5, 7].into_iter()), 7);
        assert_eq!(most_common(std::iter::empty()), 0);
    }
}
