//! A simulated twin of a real labelled data set: every real tap's labels
//! (edge position, angle and, when given, vertical offset and shear) are
//! replayed on the simulated TacTip over a straight edge (the labels mapped
//! onto the model by its calibration, docs/sensor-model.md), and the
//! rendered frames go through the same detection and ordering as the real
//! ones, against the real reference frame. Twin and real set then share
//! labels, pin order and rest layout, so a model trained on one can be
//! validated on the other: the simulator judged by what it predicts about
//! real frames (docs/results.md, "Simulated to real").
use crate::error::{LabError, Result};
use crate::import::{gather, images_of, keep_rows, FrameOutcome, Imported, TwinComposition};
use crate::import_reader::SmallFrame;
use crate::sim_sight::{lay_out, sensor_sight, sim_sight, LayoutReport, SimSight};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::collections::HashSet;
use std::path::Path;
use tactrace_calib::{real_tap_repeats, PositionMap};
use tactrace_sensor::{EdgeTap, Shear, TacTipConfig, TacTipModel};
use tactrace_servo::ImageInput;
use tactrace_store::collection::Reference;
use tactrace_store::training_record::row_hash;
use tactrace_store::{
    pin_order_mismatch, DatasetMeta, LabelledCollection, LabelledRow, SensorFolder, StoreError,
    StoredModel, TapData, TapFields, TargetColumns,
};
use tactrace_vision::PinReader;

/// Simulate every labelled row of `collection` (its labels, depth and
/// shear columns, rows, reference and sensor settings or blob detector)
/// with the sensor `sensor`, laid out like the reference's pins (see
/// [`crate::sim_sight::lay_out`]); `seed` draws the pin jitter and image
/// noise (row `k` of the labels file from stream `k`). `progress` is
/// called once per frame.
pub fn simulate_twin(
    collection: &LabelledCollection,
    sensor: &TacTipConfig,
    seed: u64,
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    let rows = twin_rows(collection)?;
    let sight = sim_sight(collection)?;
    simulate_read_rows(collection, rows, &sight, sensor, (seed, None, progress))
}

/// As [`simulate_twin`] with `sensor` first laid out like the
/// collection's rest pins ([`crate::sim_sight::lay_out`]: a hexagonal
/// lattice and concentric rings fitted, the better kept; a sensor that
/// already fits is kept as it is): what `tactrace twin` runs. With
/// `frames_size`, every kept tap's frame is also kept as an image
/// ([`Imported::images`], made as `import --frames-size` makes a real
/// frame's from the frame the detector reads).
pub fn simulate_twin_laid_out(
    collection: &LabelledCollection,
    sensor: &TacTipConfig,
    seed: u64,
    frames_size: Option<usize>,
    progress: &(dyn Fn() + Sync),
) -> Result<(Imported, LayoutReport)> {
    // The labels are read (and checked) before the reference.
    let rows = twin_rows(collection)?;
    let sight = sim_sight(collection)?;
    let (laid_out, layout) = lay_out(sensor, &sight)?;
    let input = twin_input(&sight, frames_size)?;
    let how = (seed, input.as_ref(), progress);
    let got = simulate_read_rows(collection, rows, &sight, &laid_out, how)?;
    Ok((got, layout))
}

/// As [`simulate_twin`] with the collection's simulated-tap reader
/// `sight` made once, only the label rows at `keep` when given.
pub(crate) fn simulate_twin_rows(
    collection: &LabelledCollection,
    sight: &SimSight,
    sensor: &TacTipConfig,
    seed: u64,
    (keep, progress): (Option<&[usize]>, &(dyn Fn() + Sync)),
) -> Result<Imported> {
    let rows = keep_rows(twin_rows(collection)?, keep);
    simulate_read_rows(collection, rows, sight, sensor, (seed, None, progress))
}

/// The image input of a twin's taps (`frames_size`): the collection's
/// preprocessing recorded, as its real frames are imported.
fn twin_input(sight: &SimSight, frames_size: Option<usize>) -> Result<Option<ImageInput>> {
    let preprocess = sight.reader.frames().stage().params();
    frames_size
        .map(|s| crate::tap_images::input_of(Some(preprocess), s))
        .transpose()
}

/// The twin of the labelled `rows` of `collection`, read already.
fn simulate_read_rows(
    collection: &LabelledCollection,
    rows: Vec<LabelledRow>,
    sight: &SimSight,
    sensor: &TacTipConfig,
    (seed, input, progress): (u64, Option<&ImageInput>, &(dyn Fn() + Sync)),
) -> Result<Imported> {
    let names = edge_names(collection)?;
    let rest = sight.rest().to_vec();
    let model = twin_model(&sight.origin, sensor, &rest)?;
    let (outcomes, small) = simulate_rows(&model, &sight.reader, &rows, (seed, input), progress);
    let settings = serde_json::json!({
        "twin": collection, "seed": seed, "sensor": sensor,
    });
    let meta = twin_meta(collection, (seed, names), rest, settings);
    let mut got = gather(&rows, outcomes, meta, collection.targets())?;
    got.images = input.and_then(|i| images_of(i, small));
    Ok(got)
}

/// As [`simulate_twin`] with a calibrated sensor (`tactrace calibrate`):
/// its parameters, detector, field correction and training recipe
/// (several renders of every row, seeds `seed`, `seed + 1`, ..., and the
/// real calibration taps repeated to about a third of the set, unless
/// `real_taps` is false). The collection's reference, when it has one (a
/// frame, or a dataset's recorded rest pins), must list its pins like the
/// sensor's; without one ([`Reference::Estimate`]) the sensor's own rest
/// pins order the taps. With `frames_size`, the rendered taps are also
/// kept as images (refused with the real calibration taps, which have no
/// frames).
pub fn simulate_twin_calibrated(
    collection: &LabelledCollection,
    sensor: &SensorFolder,
    seed: u64,
    (real_taps, frames_size): (bool, Option<usize>),
    progress: &(dyn Fn() + Sync),
) -> Result<Imported> {
    let spec = &sensor.spec;
    let names = edge_names(collection)?;
    let rows = twin_rows(collection)?;
    let sight = calibrated_sight(collection, sensor)?;
    let rest = sight.rest().to_vec();
    if let Some(source) = pin_order_mismatch(&spec.reference_pins, &rest) {
        return Err(StoreError::PinOrder {
            path: sight.origin.clone(),
            source,
        }
        .into());
    }
    let model = twin_model(&sight.origin, &spec.sensor, &rest)?
        .with_correction(sensor.field_correction()?)?;
    let renders = spec.training.renders.max(1);
    let repeats = if real_taps && spec.training.add_real_taps {
        real_tap_repeats(rows.len(), sensor.real_labels.len())
    } else {
        0
    };
    if frames_size.is_some() && repeats > 0 {
        return Err(LabError::Config(
            "--frames-size keeps the rendered taps as images, and the sensor's real \
             calibration taps have none: give --no-real-taps with --frames-size"
                .into(),
        ));
    }
    let input = twin_input(&sight, frames_size)?;
    let settings = serde_json::json!({
        "twin": collection, "seed": seed, "sensor": sensor.source, "recipe": spec.training,
        "renders": renders, "real_tap_repeats": repeats,
    });
    let settings = with_nuisance(settings, &spec.sensor);
    let mut all = Vec::new();
    for r in 0..renders as u64 {
        let how = (seed + r, input.as_ref());
        let (outcomes, small) = simulate_rows(&model, &sight.reader, &rows, how, progress);
        let meta = twin_meta(
            collection,
            (seed, names.clone()),
            rest.clone(),
            settings.clone(),
        );
        let mut got = gather(&rows, outcomes, meta, collection.targets())?;
        got.images = input.as_ref().and_then(|i| images_of(i, small));
        all.push(got);
    }
    let mut out = concatenate(all);
    out.data.meta.source = "simulated twin (calibrated sensor)".into();
    for k in 0..repeats {
        append_real_taps(&mut out.data, sensor, k);
    }
    out.data.meta.samples = out.data.targets.len() / names.len();
    out.composition = Some(TwinComposition {
        rows: rows.len(),
        renders,
        real_taps: sensor.real_labels.len(),
        real_tap_repeats: repeats,
    });
    Ok(out)
}

/// Whether two renders of one labelled tap by `sensor` can differ: its pin
/// jitter or image noise is above 0 (they are drawn from the render's
/// seed; nothing else in a render is random).
pub fn renders_differ(sensor: &TacTipConfig) -> bool {
    let n = &sensor.nuisance;
    n.pin_jitter_px > 0.0 || n.image_noise_std > 0.0
}

/// The position map of `sensor` (calib's [`PositionMap`],
/// docs/calibration.md "The position map"): the edge positions `model`
/// reads off the sensor's real calibration taps, fitted to their labels.
/// `model` must be trained on the sensor's twin without those taps
/// (`twin --no-real-taps`): one trained on any of them, which reads them
/// as labelled, is refused.
pub fn fit_position_map(sensor: &SensorFolder, model: &StoredModel) -> Result<PositionMap> {
    let net = model.for_pins(&sensor.spec.reference_pins, &sensor.source)?;
    let d = sensor.spec.reference_pins.len() * 2;
    if let Some(record) = model.training() {
        let seen: HashSet<&str> = record.row_hashes.iter().map(String::as_str).collect();
        let trained_on = sensor
            .real_fields
            .chunks(d)
            .zip(&sensor.real_labels)
            .filter(|(x, l)| seen.contains(row_hash(x, &l[..]).as_str()))
            .count();
        if trained_on > 0 {
            return Err(LabError::Config(format!(
                "the model {} was trained on {trained_on} of the sensor's {} real calibration \
                 taps: the position map needs a model trained on its twin without them \
                 (twin --no-real-taps)",
                model.source().display(),
                sensor.real_labels.len()
            )));
        }
    }
    let read: Vec<f64> = net
        .predict_rows(&sensor.real_fields)?
        .iter()
        .map(|p| p[0])
        .collect();
    let labelled: Vec<f64> = sensor.real_labels.iter().map(|l| f64::from(l[0])).collect();
    Ok(PositionMap::fit(&read, &labelled)?)
}

/// Relabel the simulated taps of a calibrated sensor's twin `got`
/// ([`simulate_twin_calibrated`]): each one's edge position `s` becomes
/// `map(s)`; the real calibration taps appended after them keep their
/// labels. The map is recorded in the dataset's settings.
pub fn relabel_positions(got: &mut Imported, map: &PositionMap) {
    let data = &mut got.data;
    let width = data.meta.targets.len().max(1);
    let real = got
        .composition
        .as_ref()
        .map_or(0, |c| c.real_taps * c.real_tap_repeats);
    let simulated = (data.targets.len() / width).saturating_sub(real);
    for row in data.targets.chunks_mut(width).take(simulated) {
        row[0] = map.apply(f64::from(row[0])) as f32;
    }
    if let serde_json::Value::Object(settings) = &mut data.meta.settings {
        settings.insert(
            "position_map".into(),
            serde_json::to_value(map).unwrap_or_default(),
        );
    }
}

/// `settings` with the sensor's pin jitter and image noise when either is
/// above 0 (a twin's renders then differ: [`renders_differ`]); a sensor
/// without them records nothing more, as before they were recorded.
fn with_nuisance(mut settings: serde_json::Value, sensor: &TacTipConfig) -> serde_json::Value {
    if let (true, serde_json::Value::Object(map)) = (renders_differ(sensor), &mut settings) {
        let n = &sensor.nuisance;
        map.insert("pin_jitter_px".into(), n.pin_jitter_px.into());
        map.insert("image_noise_std".into(), n.image_noise_std.into());
    }
    settings
}

/// The reader of a calibrated sensor's simulated taps: its detector, and
/// the collection's reference pins when it has a reference (checked
/// against the sensor's by the caller), else the sensor's own rest pins.
fn calibrated_sight(collection: &LabelledCollection, sensor: &SensorFolder) -> Result<SimSight> {
    let spec = &sensor.spec;
    let folder = collection
        .clone()
        .with_blob(spec.blob.clone())
        .map_err(StoreError::from)?
        .with_sight(spec.sight.clone());
    match collection.reference() {
        Reference::Frame(_) => sim_sight(&folder),
        Reference::Estimated(e) => sensor_sight(spec, e.pins.clone(), collection.frames()),
        Reference::Estimate { .. } => {
            sensor_sight(spec, spec.reference_pins.clone(), &sensor.source)
        }
    }
}

/// The dataset's target names: the twin makes an edge task's dataset.
fn edge_names(collection: &LabelledCollection) -> Result<[String; 2]> {
    Ok(collection.spec().edge_names().map_err(StoreError::from)?)
}

/// The simulated sensor `sensor` with the reference's pins `rest` as its
/// rest layout; a reference (from `reference`) that does not fit the
/// layout is named.
fn twin_model(reference: &Path, sensor: &TacTipConfig, rest: &[[f64; 2]]) -> Result<TacTipModel> {
    TacTipModel::with_rest_pins(sensor.clone(), rest.to_vec()).map_err(|e| LabError::Reference {
        path: reference.to_path_buf(),
        reason: "not an undeformed frame (or rest layout) of the simulated sensor's layout; \
                 give the sensor's frame taken without contact (or an imported dataset) as \
                 --reference, or settings that find its pins (--params, --sensor)"
            .into(),
        source: Box::new(e),
    })
}

/// The labelled rows of `collection` with its depth and shear columns.
pub(crate) fn twin_rows(collection: &LabelledCollection) -> Result<Vec<LabelledRow>> {
    Ok(collection.read_rows(TapFields::ALL)?)
}

fn twin_meta(
    collection: &LabelledCollection,
    (seed, targets): (u64, [String; 2]),
    rest: Vec<[f64; 2]>,
    settings: serde_json::Value,
) -> DatasetMeta {
    DatasetMeta {
        source: "simulated twin".into(),
        origin: collection.targets().display().to_string(),
        seed: Some(seed),
        samples: 0,
        pins: rest.len(),
        targets: targets.into(),
        // The targets' units and circular flags, as the real set's import
        // records them (a full-circle angle stays circular).
        target_columns: TargetColumns::of(&collection.spec().model_targets()),
        frames_with_missing_pins: 0,
        reference_pins: rest,
        settings,
        tactrace_version: crate::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
        tracking: tactrace_store::TrackTotals::default(),
    }
}

/// Render, detect and order every row with the rendering seed `seed`
/// (row `k` of the labels file draws from stream `k`, whichever rows are
/// simulated); with `input`, also the small frames of the rows kept, in
/// row order.
fn simulate_rows(
    model: &TacTipModel,
    reader: &PinReader,
    rows: &[LabelledRow],
    (seed, input): (u64, Option<&ImageInput>),
    progress: &(dyn Fn() + Sync),
) -> (Vec<FrameOutcome>, Vec<SmallFrame>) {
    let all: Vec<(FrameOutcome, Option<SmallFrame>)> = rows
        .par_iter()
        .map(|row| {
            let out = simulate_row(model, reader, row, (seed, row.index as u64), input);
            progress();
            out
        })
        .collect();
    let mut small = Vec::new();
    let outcomes = all
        .into_iter()
        .map(|(outcome, frame)| {
            if outcome.is_ok() {
                small.extend(frame);
            }
            outcome
        })
        .collect();
    (outcomes, small)
}

/// The imports of several renders as one set (rows in render order).
fn concatenate(parts: Vec<Imported>) -> Imported {
    let mut parts = parts.into_iter();
    let mut first = parts.next().expect("at least one render");
    for p in parts {
        first.data.inputs.extend(p.data.inputs);
        first.data.targets.extend(p.data.targets);
        first.data.meta.images.extend(p.data.meta.images);
        first.data.meta.frames_with_missing_pins += p.data.meta.frames_with_missing_pins;
        first.frames_with_missing_pins += p.frames_with_missing_pins;
        if let (Some(a), Some(b)) = (&mut first.images, p.images) {
            a.pixels.extend(b.pixels);
        }
        let (t, u) = (&mut first.data.meta.tracking, p.data.meta.tracking);
        t.frames_total += u.frames_total;
        t.frames_fully_tracked += u.frames_fully_tracked;
        first.rejected.extend(p.rejected);
    }
    first
}

/// The sensor's real calibration taps, once more (round `k`).
fn append_real_taps(data: &mut TapData, sensor: &SensorFolder, k: usize) {
    data.inputs.extend_from_slice(&sensor.real_fields);
    for (i, l) in sensor.real_labels.iter().enumerate() {
        data.targets.extend(l);
        data.meta.images.push(format!("calibration-tap-{i}#{k}"));
    }
}

/// The labelled tap of one row (its depth and shear when read).
pub(crate) fn edge_tap(row: &LabelledRow) -> EdgeTap {
    EdgeTap {
        r_mm: f64::from(row.targets[0]),
        theta_deg: f64::from(row.targets[1]),
        dz_mm: row.depth_mm.map_or(0.0, f64::from),
        shear: row.shear.map(|[x, y, rz]| Shear {
            dx_mm: f64::from(x),
            dy_mm: f64::from(y),
            drz_deg: f64::from(rz),
        }),
    }
}

/// Render, detect and order one row's tap: its displacement vector and
/// whether pins were missing, or why the frame was rejected; with `input`,
/// the rendered frame (what the detector reads) as an image model's input.
fn simulate_row(
    model: &TacTipModel,
    reader: &PinReader,
    row: &LabelledRow,
    (seed, k): (u64, u64),
    input: Option<&ImageInput>,
) -> (FrameOutcome, Option<SmallFrame>) {
    let pins = model.seen_pins(model.edge_tap_pins(&edge_tap(row)));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(k);
    let frame = model.render(&pins, Some(&mut rng));
    let small = input.map(|i| crate::tap_images::small_of(i, &frame));
    let outcome = reader
        .read_preprocessed(&frame)
        .map_err(|e| e.to_string())
        .map(|read| {
            (
                read.tracked.displacement(reader.tracker().reference()),
                !read.counts.fully_tracked(),
            )
        });
    (outcome, small)
}
