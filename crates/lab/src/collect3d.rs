//! Data collection for the 3D tasks (`collect --task surface_3d`): taps
//! on a 3D object at poses drawn in the anchors' ranges, labelled by
//! their pose relative to the surface.
//!
//! 1. The feature frame F at the object's surface point over `at_mm`
//!    (z the outward normal; x, y the work frame's turned the least way).
//!    edge_5d and edge_3d: the edge's own frame at the edge sample nearest `at_mm`
//!    (z the pressed face's normal, x across the edge out of the object).
//! 2. Tap i draws its label s: depth z uniform in [`depth_range_mm`],
//!    tilts rx, ry uniform in +-`tilt_range_deg`; edge_5d also x uniform
//!    in +-`x_range_mm` and rz in +-`rz_range_deg` (the others 0);
//!    edge_3d as edge_5d, level to the face (rx = ry = 0).
//! 3. The simulated arm moves to the tap's approach (the pose lifted
//!    `tap.height_mm` along the sensor's own axis), then presses along
//!    the axis to the pose F T(s) (z = -depth); the simulated TacTip
//!    renders the pins at the pose the arm physically reached
//!    (`TacTipModel::pins_3d`), with nuisance.
//!    With an unlabelled shear ([`Collect3dConfig::shear_mm`],
//!    [`Collect3dConfig::shear_deg`]; the anchors' real taps carry
//!    +-5 mm / +-5 deg) the arm presses at the pose moved back by a
//!    random slide (dx, dy uniform in +-`shear_mm` in the sensor's
//!    plane) and twist (drz uniform in +-`shear_deg`), then slides to the
//!    pose in contact: the skin lags (S7, or B1-B3), the label is the pose
//!    alone. The shear has a generator of its own, so a sheared set has
//!    the unsheared set's labels and noise at the same seed.
//!    With curved patches ([`Collect3dConfig::curvature_per_mm`] K > 0;
//!    surface_3d only) tap i is on a surface of its own instead of the
//!    object: the quadric patch z = -(k1 u^2 + k2 v^2) / 2 level at the
//!    origin, k1 and k2 uniform in +-K (convex, concave, saddle-shaped or
//!    nearly flat), u along an azimuth uniform in [0, 180) deg, drawn
//!    from a generator of its own, so the labels and noise are the flat
//!    set's at the same seed. The label is the pose in the patch's
//!    feature frame at the origin: with x = y = 0 the pole lies on the
//!    normal there, which is the nearest surface point (the true label a
//!    run is scored by, `tactrace_shape3d::true_label`).
//!    Along the edge ([`Collect3dConfig::along_edge`]; edge tasks only)
//!    tap i is placed in the edge frame of an edge sample drawn uniformly
//!    (a generator of its own) instead of the one nearest `at_mm`.
//! 4. The pins' displacements are the inputs, s's sensed components the
//!    named targets (surface_3d `z` mm, `rx`, `ry` deg; edge_5d `x`, `z`
//!    mm, `rx`, `ry` deg, `rz` deg circular; edge_3d `x`, `z`, `rz`).
//!
//! Every tap has generators of its own (stream i of the seed), so the set
//! is the same whatever the number of threads.
//!
//! [`depth_range_mm`]: Collect3dConfig::depth_range_mm
use crate::collect::{check_samples, dataset_meta, CollectConfig, Collected};
use crate::error::{LabError, Result};
use rand::{Rng, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use tactrace_arm::{Arm, LimitMode, LimitedArm, Pose, SimArm, SimArmConfig};
use tactrace_control::Task;
use tactrace_learn::{ModelTarget, Unit};
use tactrace_sensor::{Frame, Shear, TacTipModel};
use tactrace_servo::{lifted, RigConfig};
use tactrace_shape3d::{
    feature_frame, pose_of_label, surface_point, HeightField, Surface, MAX_QUADRIC_CURVATURE,
};
use tactrace_store::dataset::TargetColumns;
use tactrace_store::frame_file::png_bytes;
use tactrace_store::{DatasetMeta, TapData};
use tactrace_vision::PinExtractor;

/// What a 3D collection draws (the anchors' surface_3d ranges by default).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Collect3dConfig {
    pub samples: usize,
    pub seed: u64,
    /// The task whose components are drawn and named.
    pub task: Task,
    /// The surface point tapped: the object's top over this (x, y), mm.
    pub at_mm: [f64; 2],
    /// Depths are uniform in [min, max], mm.
    pub depth_range_mm: [f64; 2],
    /// rx and ry are uniform in +-this, deg.
    pub tilt_range_deg: f64,
    /// edge_5d: x (across the edge) is uniform in +-this, mm.
    pub x_range_mm: f64,
    /// edge_5d: rz is uniform in +-this, deg.
    pub rz_range_deg: f64,
    /// Unlabelled shear: the slide ending at each tap's pose has dx, dy
    /// uniform in +-this (sensor frame), mm; 0 for none.
    pub shear_mm: f64,
    /// Unlabelled shear: the twist ending at each tap's pose is uniform
    /// in +-this, deg; 0 for none.
    pub shear_deg: f64,
    /// surface_3d: each tap on a quadric patch of its own whose principal
    /// curvatures are uniform in +-this, 1/mm (at most 1/20); 0 (the
    /// default) taps the object.
    pub curvature_per_mm: f64,
    /// Edge tasks: each tap at an edge sample drawn uniformly along the
    /// edge instead of the one nearest `at_mm`.
    pub along_edge: bool,
    /// Keep the PNG of every tap.
    pub save_frames: bool,
}

impl Default for Collect3dConfig {
    fn default() -> Self {
        Self {
            samples: 1000,
            seed: 1,
            task: Task::Surface3d,
            at_mm: [0.0, 0.0],
            depth_range_mm: [1.0, 5.0],
            tilt_range_deg: 25.0,
            x_range_mm: 5.0,
            rz_range_deg: 180.0,
            shear_mm: 0.0,
            shear_deg: 0.0,
            curvature_per_mm: 0.0,
            along_edge: false,
            save_frames: false,
        }
    }
}

impl Collect3dConfig {
    /// Refuse a task this collection cannot draw and ranges that cannot work.
    pub fn validate(&self) -> Result<()> {
        if self.task == Task::Edge2d {
            return Err(LabError::Config(format!(
                "collect --task {} is the planar task: collect it with --shape",
                self.task
            )));
        }
        let [lo, hi] = self.depth_range_mm;
        let ok = lo.is_finite()
            && hi.is_finite()
            && 0.0 <= lo
            && lo <= hi
            && self.tilt_range_deg.is_finite()
            && (0.0..90.0).contains(&self.tilt_range_deg)
            && self.x_range_mm.is_finite()
            && self.x_range_mm >= 0.0
            && (0.0..=180.0).contains(&self.rz_range_deg)
            && (0.0..=MAX_SHEAR_MM).contains(&self.shear_mm)
            && (0.0..=MAX_SHEAR_DEG).contains(&self.shear_deg)
            && self.at_mm.iter().all(|v| v.is_finite());
        if !ok {
            return Err(LabError::Config(
                "depth_range_mm must be 0 <= min <= max, tilt_range_deg in [0, 90), x_range_mm >= 0, \
                 rz_range_deg in [0, 180], shear_mm in [0, 10], shear_deg in [0, 45], at_mm finite"
                    .into(),
            ));
        }
        let k = self.curvature_per_mm;
        if !(0.0..=MAX_QUADRIC_CURVATURE).contains(&k) {
            return Err(LabError::Config(format!(
                "curvature_per_mm = {k}: must be in [0, {MAX_QUADRIC_CURVATURE}] (a radius of 20 mm \
                 or more)"
            )));
        }
        if k > 0.0 && self.task != Task::Surface3d {
            return Err(LabError::Config(format!(
                "curved patches are surface_3d's: {} taps an object's edge",
                self.task
            )));
        }
        if self.along_edge && self.task == Task::Surface3d {
            return Err(LabError::Config(
                "taps along the edge are the edge tasks': surface_3d has no edge".into(),
            ));
        }
        check_samples(&CollectConfig {
            samples: self.samples,
            ..CollectConfig::default()
        })
    }
}

/// The largest unlabelled slide a collection draws, mm (twice the anchors').
pub const MAX_SHEAR_MM: f64 = 10.0;
/// The largest unlabelled twist a collection draws, deg.
pub const MAX_SHEAR_DEG: f64 = 45.0;

/// Mixed into the seed of the shear's own generators.
const SHEAR_STREAM_SALT: u64 = 0x5348_4541_5233_4400;

/// The unlabelled shear of tap `i`: its own generator (stream `i` of the
/// salted seed), so the labels and noise do not depend on it; `None`
/// when the collection has none.
pub fn tap_shear(cfg: &Collect3dConfig, i: usize) -> Option<Shear> {
    if cfg.shear_mm == 0.0 && cfg.shear_deg == 0.0 {
        return None;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed ^ SHEAR_STREAM_SALT);
    rng.set_stream(i as u64);
    let (m, a) = (cfg.shear_mm, cfg.shear_deg);
    Some(Shear {
        dx_mm: rng.random_range(-m..=m),
        dy_mm: rng.random_range(-m..=m),
        drz_deg: rng.random_range(-a..=a),
    })
}

/// Mixed into the seed of the curved patches' own generators.
const PATCH_STREAM_SALT: u64 = 0x5041_5443_4833_4400;

/// The curved patch tap `i` presses (its own generator, stream `i` of the
/// salted seed): principal curvatures uniform in +-`curvature_per_mm`
/// along an azimuth uniform in [0, 180) deg; `None` without patches.
pub fn tap_patch(cfg: &Collect3dConfig, i: usize) -> Result<Option<Surface>> {
    let k = cfg.curvature_per_mm;
    if k == 0.0 {
        return Ok(None);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed ^ PATCH_STREAM_SALT);
    rng.set_stream(i as u64);
    let curvatures = [rng.random_range(-k..=k), rng.random_range(-k..=k)];
    let azimuth = rng.random_range(0.0..180.0);
    let patch = HeightField::quadric(curvatures, azimuth)?;
    Ok(Some(std::sync::Arc::new(patch)))
}

/// Mixed into the seed of the edge samples' own generators.
const EDGE_STREAM_SALT: u64 = 0x4544_4745_3344_4400;

/// The edge frame tap `i` is placed in along `edge` (its own generator,
/// stream `i` of the salted seed: a sample drawn uniformly).
pub fn tap_edge_frame(
    cfg: &Collect3dConfig,
    edge: &tactrace_shape3d::EdgeCurve,
    i: usize,
) -> nalgebra::Isometry3<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed ^ EDGE_STREAM_SALT);
    rng.set_stream(i as u64);
    edge.samples[rng.random_range(0..edge.samples.len())].frame()
}

/// Where a tap whose `pose` ends a `shear` starts its slide: the pose
/// moved back by the slide and twist, in its own frame.
fn slide_start(pose: Pose, shear: Shear) -> Pose {
    let slide = Pose::new(shear.dx_mm, shear.dy_mm, 0.0, 0.0, 0.0, shear.drz_deg);
    Pose::from_isometry(&(pose.to_isometry() * slide.to_isometry().inverse()))
}

/// The named targets of `task`'s sensed components (x, y, z in mm; rx, ry,
/// rz in deg, rz circular), as a 3D collection writes them.
pub fn task_targets(task: Task) -> Vec<ModelTarget> {
    task.sensed_names()
        .into_iter()
        .map(|name| match name {
            "rz" => ModelTarget::circular(name),
            "rx" | "ry" => ModelTarget::new(name, Unit::Deg),
            _ => ModelTarget::new(name, Unit::Mm),
        })
        .collect()
}

/// One tap: its displacement vector, labels and frame.
struct Row {
    inputs: Vec<f32>,
    targets: Vec<f32>,
    missing: bool,
    frame: Option<Frame>,
}

/// Collect `cfg.samples` taps on `object` (named `origin`) with the
/// simulated rig `rig_cfg` (its sensor, arm noise, workspace, tap height
/// and blob settings); `progress` hears the taps done after each batch.
pub fn collect_3d(
    rig_cfg: &RigConfig,
    object: &Surface,
    cfg: &Collect3dConfig,
    origin: &str,
    mut progress: impl FnMut(usize),
) -> Result<Collected> {
    cfg.validate()?;
    rig_cfg.validate()?;
    let model = TacTipModel::new(rig_cfg.sensor.clone())?;
    let reference = model.render(model.rest_pins(), None);
    let extractor = PinExtractor::from_reference_frame(&reference, rig_cfg.blob.clone())?;
    let frame = task_frame(object, cfg, origin)?;
    let world = World {
        rig: rig_cfg,
        model: &model,
        object,
        frame,
        edge: cfg.along_edge.then(|| object.edge()).flatten(),
        extractor: &extractor,
    };
    let targets = task_targets(cfg.task);
    let mut data = TapData {
        inputs: Vec::new(),
        targets: Vec::new(),
        meta: meta(cfg, origin, rig_cfg, &extractor, &targets),
    };
    let mut frames = Vec::new();
    let mut missing = 0;
    for first in (0..cfg.samples).step_by(256) {
        let last = (first + 256).min(cfg.samples);
        let batch: Vec<Row> = (first..last)
            .into_par_iter()
            .map(|i| world.tap(cfg, i))
            .collect::<Result<_>>()?;
        for (i, row) in (first..).zip(batch) {
            missing += usize::from(row.missing);
            data.inputs.extend(row.inputs);
            data.targets.extend(row.targets);
            if let Some(f) = row.frame {
                frames.push((format!("frame_{i:05}.png"), png_bytes(&f, "frame")?));
            }
        }
        progress(last);
    }
    if cfg.save_frames {
        frames.push(("reference.png".into(), png_bytes(&reference, "reference")?));
    }
    data.meta.frames_with_missing_pins = missing;
    data.meta.tracking = tactrace_store::TrackTotals::frames(cfg.samples, missing);
    Ok(Collected {
        data,
        frames,
        images: None,
    })
}

/// The frame the labels are placed in: surface_3d the feature frame at
/// the surface over `at_mm`, edge_5d the edge's own frame at the edge
/// sample nearest `at_mm` (in x, y).
fn task_frame(
    object: &Surface,
    cfg: &Collect3dConfig,
    origin: &str,
) -> Result<nalgebra::Isometry3<f64>> {
    let [x, y] = cfg.at_mm;
    if cfg.task != Task::Surface3d {
        let edge = object.edge().ok_or_else(|| {
            LabError::Config(format!(
                "the object {origin} has no edge ({} needs one)",
                cfg.task
            ))
        })?;
        let near = |p: &tactrace_shape3d::Vec3| (p.x - x).hypot(p.y - y);
        let sample = edge
            .samples
            .iter()
            .min_by(|a, b| near(&a.point).total_cmp(&near(&b.point)))
            .ok_or_else(|| LabError::Config(format!("the edge of {origin} has no sample")))?;
        return Ok(sample.frame());
    }
    let q = surface_point(object.as_ref(), x, y).ok_or_else(|| {
        LabError::Config(format!(
            "the object {origin} has no surface over ({x}, {y}) mm"
        ))
    })?;
    feature_frame(object.as_ref(), q, nalgebra::UnitQuaternion::identity())
        .ok_or_else(|| LabError::Config(format!("the surface of {origin} faces down there")))
}

/// The metadata of a 3D collection: its named targets and settings.
fn meta(
    cfg: &Collect3dConfig,
    origin: &str,
    rig_cfg: &RigConfig,
    extractor: &PinExtractor,
    targets: &[ModelTarget],
) -> DatasetMeta {
    let edge = CollectConfig {
        samples: cfg.samples,
        seed: cfg.seed,
        ..CollectConfig::default()
    };
    let settings = serde_json::json!({ "rig": rig_cfg, "collect_3d": cfg });
    let base = dataset_meta(
        &edge,
        ("simulated", origin),
        settings,
        extractor.tracker.reference(),
        0,
    );
    DatasetMeta {
        targets: TargetColumns::display(targets),
        target_columns: TargetColumns::of(targets),
        ..base
    }
}

/// The simulated rig of a 3D collection, shared by every thread.
struct World<'a> {
    rig: &'a RigConfig,
    model: &'a TacTipModel,
    object: &'a Surface,
    /// The feature frame of the tapped surface point (object frame).
    frame: nalgebra::Isometry3<f64>,
    /// The edge its taps are spread along (`along_edge`), else `None`.
    edge: Option<tactrace_shape3d::EdgeCurve>,
    extractor: &'a PinExtractor,
}

impl World<'_> {
    /// Tap `i`: its own generator draws the label, then seeds the arm's
    /// noise and the camera's nuisance.
    fn tap(&self, cfg: &Collect3dConfig, i: usize) -> Result<Row> {
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
        rng.set_stream(i as u64);
        let [lo, hi] = cfg.depth_range_mm;
        let t = cfg.tilt_range_deg;
        let z = rng.random_range(lo..=hi);
        let rx = rng.random_range(-t..=t);
        let ry = rng.random_range(-t..=t);
        let label = if cfg.task != Task::Surface3d {
            let (xr, rzr) = (cfg.x_range_mm, cfg.rz_range_deg);
            let x = rng.random_range(-xr..=xr);
            let rz = rng.random_range(-rzr..=rzr);
            // edge_3d: level to the face (its tilts drawn all the same,
            // so its x, z and rz are edge_5d's of the same seed).
            let level = cfg.task == Task::Edge3d;
            let (rx, ry) = if level { (0.0, 0.0) } else { (rx, ry) };
            [x, 0.0, z, rx, ry, rz]
        } else {
            [0.0, 0.0, z, rx, ry, 0.0]
        };
        let patch = tap_patch(cfg, i)?;
        // A patch is level at the origin: its feature frame is the identity.
        let (object, frame) = match &patch {
            Some(p) => (p, nalgebra::Isometry3::identity()),
            None => match &self.edge {
                Some(edge) => (self.object, tap_edge_frame(cfg, edge, i)),
                None => (self.object, self.frame),
            },
        };
        let pose = pose_of_label(&frame, label);
        let shear = tap_shear(cfg, i);
        let pressed = shear.map_or(pose, |s| slide_start(pose, s));
        let approach = lifted(pressed, self.rig.tap.height_mm);
        let arm_cfg = SimArmConfig {
            seed: rng.next_u64(),
            ..self.rig.arm.clone()
        };
        let (sim_arm, probe) = SimArm::with_probe(arm_cfg, approach);
        let mut arm = LimitedArm::new(sim_arm, self.rig.workspace.clone(), LimitMode::Refuse);
        arm.move_to(approach)?;
        if shear.is_some() {
            arm.move_to(pressed)?;
        }
        arm.move_to(pose)?;
        let mut nuisance = ChaCha8Rng::seed_from_u64(rng.next_u64());
        let pins = self.model.pins_3d(object.as_ref(), probe.actual(), shear);
        let frame = self
            .model
            .render(&self.model.seen_pins(pins), Some(&mut nuisance));
        arm.move_to(lifted(pose, self.rig.tap.height_mm))?;
        let tracked = self.extractor.extract(&frame)?;
        Ok(Row {
            inputs: tracked.displacement(self.extractor.tracker.reference()),
            targets: (0..6)
                .filter(|k| cfg.task.sensed()[*k])
                .map(|k| label[k] as f32)
                .collect(),
            missing: tracked.missing > 0,
            frame: cfg.save_frames.then_some(frame),
        })
    }
}
