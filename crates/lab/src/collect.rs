//! Data collection on an edge, report ch. 4.1.
//!
//! 1. Align the sensor centre with the edge.
//! 2. Set r uniformly at random in [-r_range, r_range] mm along the outward
//!    edge normal and theta on a sweep from -theta_range to +theta_range deg
//!    over the run.
//! 3. Tap and capture.
//! 4. Extract the pins and their displacement from the undeformed frame.
//!
//! On the simulated rig the taps run on all cores: every tap has its own
//! generators, seeded from the collection's seed and the tap's number
//! (its label draws, the arm's repeatability noise, the camera's
//! nuisance), and starts from its own approach pose, so the dataset is the
//! same, bit for bit, whatever the number of threads
//! (`RAYON_NUM_THREADS`). A real rig ([`collect_on`]) taps in turn, each
//! tap drawing its labels from the same generator as here.
use crate::error::{LabError, Result};
use crate::import_reader::SmallFrame;
use rand::{Rng, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use tactrace_arm::{Arm, LimitMode, LimitedArm, PoseProbe, SimArm, SimArmConfig};
use tactrace_geometry::{Contour, Vec2};
use tactrace_sensor::{Frame, LabelConvention, SensorError, TacTipModel, TactileSensor};
use tactrace_servo::{pose_at_edge, tap, ImageInput, RigConfig, TapConfig};
use tactrace_store::frame_file::png_bytes;
use tactrace_store::{DatasetMeta, ImageFrames, SensorFolder, TapData};

/// Rows whose buffers are reserved up front; more grow as they come.
const PRESIZED_ROWS: usize = 1 << 16;
/// Taps handed to the threads at a time (progress is reported between).
const TAPS_PER_BATCH: usize = 256;
use tactrace_vision::{BlobParams, DetectorParams, PinExtractor, PinReader, SightParams};

/// What to collect.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CollectConfig {
    pub samples: usize,
    pub seed: u64,
    /// Edge positions are uniform in [-r_range_mm, r_range_mm].
    pub r_range_mm: f64,
    /// Angles sweep from -theta_range_deg to +theta_range_deg.
    pub theta_range_deg: f64,
    /// Arc length of the edge point the sensor is aligned with, mm.
    pub edge_arc_mm: f64,
    /// Keep the PNG of every tap.
    pub save_frames: bool,
    /// Also keep every simulated tap's frame area-averaged to this many px
    /// square, for the image models (the dataset's `frames.npy`, as
    /// `import --frames-size` writes it); `None`: pin vectors only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames_size: Option<usize>,
}

impl Default for CollectConfig {
    fn default() -> Self {
        Self {
            samples: 1000,
            seed: 1,
            r_range_mm: 5.0,
            theta_range_deg: 45.0,
            edge_arc_mm: 0.0,
            save_frames: false,
            frames_size: None,
        }
    }
}

/// One collected sample: the target and (optionally) the frame.
pub struct Collected {
    pub data: TapData,
    /// (file name, PNG bytes) when `save_frames`.
    pub frames: Vec<(String, Vec<u8>)>,
    /// Every tap's frame as an image model's input (`frames.npy`) when
    /// `frames_size` is given.
    pub images: Option<ImageFrames>,
}

/// Run the collection over `shape` with the simulated rig.
pub fn collect(
    rig_cfg: &RigConfig,
    shape: &Contour,
    cfg: &CollectConfig,
    origin: &str,
    progress: impl FnMut(usize),
) -> Result<Collected> {
    rig_cfg.validate()?;
    let model = TacTipModel::new(rig_cfg.sensor.clone())?;
    let reference = model.render(model.rest_pins(), None);
    let reader = blob_reader(&reference, &rig_cfg.blob)?;
    let world = SimWorld {
        rig: rig_cfg,
        model: &model,
        mount_yaw_deg: 0.0,
        shape,
        reference: &reference,
        reader: &reader,
        labels: None,
    };
    let settings = serde_json::json!({ "rig": rig_cfg, "collect": cfg });
    collect_simulated(world, cfg, "simulated", origin, settings, progress)
}

/// As [`collect`] with a calibrated sensor (`--sensor`): its taps, read
/// by its own detector (its sensor settings' or its blob detector) and
/// ordered by its reference pins (an undeformed frame's or the rest layout
/// estimated from its taps: [`crate::sim_sight::of_sensor`]), labels drawn in its own convention
/// (r in +-`r_range_mm`, theta swept over +-`theta_range_deg` of its
/// labels) and placed at their loop pose (eq. L1), so the set looks like
/// the sensor's real collection. `rig_cfg.sensor` is not used.
pub fn collect_calibrated(
    rig_cfg: &RigConfig,
    sensor: &SensorFolder,
    shape: &Contour,
    cfg: &CollectConfig,
    origin: &str,
    progress: impl FnMut(usize),
) -> Result<Collected> {
    let spec = &sensor.spec;
    let convention = sensor.label_convention();
    let model = sensor.model()?;
    let sight = crate::sim_sight::of_sensor(sensor)?;
    rig_cfg.validate()?;
    let names = [
        format!("r_mm ({})", spec.labels.r),
        format!("theta_deg ({})", spec.labels.theta),
    ];
    let world = SimWorld {
        rig: rig_cfg,
        model: &model,
        mount_yaw_deg: convention.mount_yaw_deg,
        shape,
        reference: &sensor.reference,
        reader: &sight.reader,
        labels: Some((convention, names)),
    };
    let settings = serde_json::json!({
        "rig": rig_cfg, "collect": cfg, "calibrated_sensor": sensor.source,
    });
    collect_simulated(
        world,
        cfg,
        "simulated (calibrated sensor)",
        origin,
        settings,
        progress,
    )
}

/// The simulated rig of a collection, shared by every thread: the arm's
/// and workspace's settings, the TacTip model (mounted turned by
/// `mount_yaw_deg`), the object, the reference frame (kept with the
/// frames), the reader of its taps' pins, and the label convention with its target names (as [`EdgeRig`]).
struct SimWorld<'a> {
    rig: &'a RigConfig,
    model: &'a TacTipModel,
    mount_yaw_deg: f64,
    shape: &'a Contour,
    reference: &'a Frame,
    reader: &'a PinReader,
    labels: Option<(LabelConvention, [String; 2])>,
}

/// One simulated tap's displacement vector, its labels and its frame.
struct TapRow {
    inputs: Vec<f32>,
    targets: [f32; 2],
    missing: bool,
    frame: Option<Frame>,
    /// The frame area-averaged for the image models, when asked for.
    small: Option<SmallFrame>,
}

/// [`collect_on`] on the simulated rig, taps on all cores (see the module
/// docs); `progress` hears the number of taps done after every batch.
fn collect_simulated(
    world: SimWorld,
    cfg: &CollectConfig,
    source: &str,
    origin: &str,
    settings: serde_json::Value,
    mut progress: impl FnMut(usize),
) -> Result<Collected> {
    check_samples(cfg)?;
    let input = crate::tap_images::sim_input(cfg.frames_size)?;
    let rest = world.reader.tracker().reference();
    let dim = 2 * rest.len();
    let rows = cfg.samples.min(PRESIZED_ROWS);
    let mut inputs = Vec::with_capacity(rows * dim);
    let mut targets = Vec::with_capacity(rows * 2);
    let mut frames = Vec::new();
    let mut small = Vec::new();
    let mut with_missing = 0;
    for first in (0..cfg.samples).step_by(TAPS_PER_BATCH) {
        let last = (first + TAPS_PER_BATCH).min(cfg.samples);
        let batch: Vec<TapRow> = (first..last)
            .into_par_iter()
            .map(|i| simulated_tap(&world, cfg, input.as_ref(), i))
            .collect::<Result<_>>()?;
        for (i, row) in (first..).zip(batch) {
            with_missing += usize::from(row.missing);
            inputs.extend(row.inputs);
            targets.extend(row.targets);
            small.extend(row.small);
            if let Some(frame) = row.frame {
                frames.push((format!("frame_{i:05}.png"), png_bytes(&frame, "frame")?));
            }
        }
        progress(last);
    }
    if cfg.save_frames {
        frames.push((
            "reference.png".into(),
            png_bytes(world.reference, "reference")?,
        ));
    }
    let meta = dataset_meta(cfg, (source, origin), settings, rest, with_missing);
    let images = input.and_then(|i| crate::import::images_of(&i, small));
    let names = world.labels.map(|(_, n)| n);
    Ok(Collected {
        data: TapData {
            inputs,
            targets,
            meta: DatasetMeta {
                targets: names.map_or(meta.targets, |n| n.into()),
                ..meta
            },
        },
        frames,
        images,
    })
}

/// Tap `i` of the collection on the simulated rig, with generators of its
/// own: stream `i` of the collection's seed draws its labels and depth,
/// then seeds the arm's noise and the camera's nuisance. The arm starts at
/// the tap's approach pose (checked by the limiter), taps down, and the
/// sensor renders the pins at the pose physically reached. With `input`,
/// the frame is also made into an image model's input.
fn simulated_tap(
    world: &SimWorld,
    cfg: &CollectConfig,
    input: Option<&ImageInput>,
    i: usize,
) -> Result<TapRow> {
    let tap_cfg = &world.rig.tap;
    let (mut rng, r, depth) = tap_draws(cfg, tap_cfg, i);
    let theta = sweep(i, cfg.samples, cfg.theta_range_deg);
    let (edge, normal) = world.shape.at_arc_length(cfg.edge_arc_mm);
    let labels = world.labels.as_ref().map(|(c, _)| c);
    let at = LabelConvention::edge_pose_of(labels, r, theta);
    let approach = pose_at_edge(edge, normal, at.0, at.1, tap_cfg.height_mm);
    let arm_cfg = SimArmConfig {
        seed: rng.next_u64(),
        ..world.rig.arm.clone()
    };
    let (sim_arm, probe) = SimArm::with_probe(arm_cfg, approach);
    let mut arm = LimitedArm::new(sim_arm, world.rig.workspace.clone(), LimitMode::Refuse);
    let mut sensor = TapCamera {
        world,
        probe,
        nuisance: ChaCha8Rng::seed_from_u64(rng.next_u64()),
    };
    arm.move_to(approach)?;
    let frame = tap(&mut arm, &mut sensor, depth)?;
    let tracked = world.reader.read_preprocessed(&frame)?.tracked;
    Ok(TapRow {
        inputs: tracked.displacement(world.reader.tracker().reference()),
        targets: [r as f32, theta as f32],
        missing: tracked.missing > 0,
        small: input.map(|i| crate::tap_images::small_of(i, &frame)),
        frame: cfg.save_frames.then_some(frame),
    })
}

/// Tap `i`'s generator (stream `i` of the collection's seed) after it
/// drew the tap's edge position r (mm) and depth (mm): the same on every
/// rig, so a real rig replaying a simulated collection's frames gets its
/// labels.
fn tap_draws(cfg: &CollectConfig, tap_cfg: &TapConfig, i: usize) -> (ChaCha8Rng, f64, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    rng.set_stream(i as u64);
    let r = rng.random_range(-cfg.r_range_mm..=cfg.r_range_mm);
    let depth = tap_cfg.depth_mm + rng.random_range(-1.0..=1.0) * tap_cfg.depth_jitter_mm;
    (rng, r, depth)
}

/// The simulated TacTip of one tap over the shared model: what
/// `tactrace_sensor::SimTacTip` captures (the pins at the physically
/// reached pose, as the camera sees them, rendered with nuisance), without
/// a copy of the model per tap.
struct TapCamera<'a> {
    world: &'a SimWorld<'a>,
    probe: PoseProbe,
    nuisance: ChaCha8Rng,
}

impl TactileSensor for TapCamera<'_> {
    fn capture(&mut self) -> std::result::Result<Frame, SensorError> {
        let mut tip = self.probe.actual();
        tip.rz += self.world.mount_yaw_deg;
        let model = self.world.model;
        let pins = model.seen_pins(model.pins(self.world.shape, tip, None));
        Ok(model.render(&pins, Some(&mut self.nuisance)))
    }
}

/// `--samples` must be positive.
pub fn check_samples(cfg: &CollectConfig) -> Result<()> {
    if cfg.samples == 0 {
        return Err(LabError::Config("--samples must be at least 1".into()));
    }
    let ranges_ok = cfg.r_range_mm.is_finite()
        && cfg.r_range_mm >= 0.0
        && cfg.theta_range_deg.is_finite()
        && cfg.theta_range_deg >= 0.0
        && cfg.edge_arc_mm.is_finite();
    if !ranges_ok {
        return Err(LabError::Config(
            "r_range_mm and theta_range_deg must be finite and >= 0, edge_arc_mm finite".into(),
        ));
    }
    Ok(())
}

/// An arm and sensor (simulated or real) at an edge: the undeformed
/// reference frame, the detector settings, the tap and the edge point with its
/// outward normal in the work frame.
pub struct EdgeRig<'a> {
    pub arm: &'a mut dyn Arm,
    pub sensor: &'a mut dyn TactileSensor,
    pub reference: &'a Frame,
    pub detect: &'a DetectorParams,
    pub tap: &'a TapConfig,
    pub edge: Vec2,
    pub normal: Vec2,
    /// A sensor's label convention and its target names: labels are drawn
    /// in it and placed at their loop pose (eq. L1). `None`: the labels
    /// are the loop's edge pose.
    pub labels: Option<(LabelConvention, [String; 2])>,
}

/// The collection of report ch. 4.1 on any rig: the labels are the poses
/// commanded relative to the edge; `source` and `settings` go into the
/// dataset's metadata.
pub fn collect_on(
    on: EdgeRig,
    cfg: &CollectConfig,
    source: &str,
    origin: &str,
    settings: serde_json::Value,
    mut progress: impl FnMut(usize),
) -> Result<Collected> {
    check_samples(cfg)?;
    let EdgeRig {
        arm,
        sensor,
        reference,
        detect,
        tap: tap_cfg,
        edge,
        normal,
        labels,
    } = on;
    let extractor = PinExtractor::with_detector(reference, detect.clone().check()?)?;
    let dim = 2 * extractor.tracker.reference().len();
    // Reserved for at most PRESIZED_ROWS: a huge --samples grows the
    // buffers as taps come instead of aborting on one giant allocation.
    let rows = cfg.samples.min(PRESIZED_ROWS);
    let mut inputs = Vec::with_capacity(rows * dim);
    let mut targets = Vec::with_capacity(rows * 2);
    let mut frames = Vec::new();
    let mut with_missing = 0;
    for i in 0..cfg.samples {
        let (_, r, depth) = tap_draws(cfg, tap_cfg, i);
        let theta = sweep(i, cfg.samples, cfg.theta_range_deg);
        let at = LabelConvention::edge_pose_of(labels.as_ref().map(|(c, _)| c), r, theta);
        arm.move_to(pose_at_edge(edge, normal, at.0, at.1, tap_cfg.height_mm))?;
        let frame = tap(arm, sensor, depth)?;
        let tracked = extractor.extract(&frame)?;
        if tracked.missing > 0 {
            with_missing += 1;
        }
        inputs.extend(tracked.displacement(extractor.tracker.reference()));
        targets.extend([r as f32, theta as f32]);
        if cfg.save_frames {
            frames.push((format!("frame_{i:05}.png"), png_bytes(&frame, "frame")?));
        }
        progress(i + 1);
    }
    if cfg.save_frames {
        frames.push(("reference.png".into(), png_bytes(reference, "reference")?));
    }
    let meta = dataset_meta(
        cfg,
        (source, origin),
        settings,
        extractor.tracker.reference(),
        with_missing,
    );
    let names = labels.map(|(_, n)| n);
    let meta = DatasetMeta {
        targets: names.map_or(meta.targets, |n| n.into()),
        ..meta
    };
    Ok(Collected {
        data: TapData {
            inputs,
            targets,
            meta,
        },
        frames,
        // A rig's camera frames are kept by `save_frames`, not as images.
        images: None,
    })
}

/// A collection's metadata (targets named `r_mm`, `theta_deg`).
pub(crate) fn dataset_meta(
    cfg: &CollectConfig,
    (source, origin): (&str, &str),
    settings: serde_json::Value,
    reference_pins: &[[f64; 2]],
    with_missing: usize,
) -> DatasetMeta {
    let reference_pins = reference_pins.to_vec();
    DatasetMeta {
        source: source.into(),
        origin: origin.into(),
        seed: Some(cfg.seed),
        samples: cfg.samples,
        pins: reference_pins.len(),
        targets: vec!["r_mm".into(), "theta_deg".into()],
        target_columns: Default::default(),
        frames_with_missing_pins: with_missing,
        reference_pins,
        settings,
        tactrace_version: crate::VERSION.into(),
        input_layout: tactrace_store::dataset::INPUT_LAYOUT.into(),
        images: Vec::new(),
        tracking: tactrace_store::TrackTotals::frames(cfg.samples, with_missing),
    }
}

/// The blob detector `blob` over the pins it finds in the undeformed
/// frame `reference` (the default simulated TacTip's rest frame), in
/// detection order.
fn blob_reader(reference: &Frame, blob: &BlobParams) -> Result<PinReader> {
    let sight = SightParams {
        preprocess: Default::default(),
        detect: DetectorParams::Blobs(blob.clone()),
    };
    let detector = sight.check(reference.width(), reference.height())?;
    let rest = detector.detector().detect(reference).points;
    let rest = rest.iter().map(|k| [k.x, k.y]).collect();
    Ok(PinReader::new(detector, rest)?)
}

/// theta for sample `i` of `n`, sweeping linearly from -range to +range.
fn sweep(i: usize, n: usize, range: f64) -> f64 {
    if n <= 1 {
        return 0.0;
    }
    -range + 2.0 * range * i as f64 / (n - 1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use tactrace_geometry::{builtin_shape, BuiltinShape};

    fn collect_with_threads(threads: usize, cfg: &CollectConfig) -> Collected {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let (rig, disk) = (RigConfig::default(), builtin_shape(BuiltinShape::Disk));
        pool.install(|| collect(&rig, &disk, cfg, "disk", |_| {}))
            .expect("collect")
    }

    /// Taps on all cores give the dataset of one thread, bit for bit
    /// (more taps than a batch, frames kept).
    #[test]
    fn collect_on_two_threads_equals_one_thread_bit_for_bit() {
        let cfg = CollectConfig {
            samples: TAPS_PER_BATCH + 9,
            seed: 5,
            save_frames: true,
            ..CollectConfig::default()
        };
        let (one, two) = (collect_with_threads(1, &cfg), collect_with_threads(2, &cfg));
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one.data.inputs), bits(&two.data.inputs));
        assert_eq!(bits(&one.data.targets), bits(&two.data.targets));
        assert_eq!(one.frames, two.frames);
        assert_eq!(one.frames.len(), cfg.samples + 1);
        let (a, b) = (&one.data.meta, &two.data.meta);
        assert_eq!(a.frames_with_missing_pins, b.frames_with_missing_pins);
        // Every tap drew its own labels, and the sweep still runs in order.
        let r: Vec<f32> = one.data.targets.iter().step_by(2).copied().collect();
        let distinct = r
            .iter()
            .map(|v| v.to_bits())
            .collect::<std::collections::HashSet<_>>();
        assert_eq!(distinct.len(), r.len());
        let theta: Vec<f32> = one
            .data
            .targets
            .iter()
            .skip(1)
            .step_by(2)
            .copied()
            .collect();
        assert!(theta.windows(2).all(|w| w[0] < w[1]));
        let other = collect_with_threads(
            2,
            &CollectConfig {
                seed: 6,
                ..cfg.clone()
            },
        );
        assert_ne!(bits(&other.data.inputs), bits(&one.data.inputs));
    }
}
