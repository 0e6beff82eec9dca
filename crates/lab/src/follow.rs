//! The contour-following experiment (report ch. 5.2-5.3): the servo loop
//! of `tactrace-servo` on a rig, into a run folder.
//!
//! A run folder holds `config.toml` (the resolved configuration, seed and
//! version), `trajectory.csv` (written and flushed step by step),
//! `replay.html` (the run step by step, self-contained), `metrics.json`
//! (with, in the real-frame world, the label distances of
//! the answered frames: [`crate::replay_world`]) and the trajectory and L2
//! figures. It is built in
//! `OUT.partial` and renamed to `OUT` when the run is over, so a folder
//! named `OUT` is always complete; a run stopped by an error (or killed)
//! leaves its trajectory so far in `OUT.partial`, which the next run into
//! `OUT` replaces.
use crate::error::{LabError, Result};
use crate::replay_world::{ReplayStats, ReplayWorld};
use crate::trajectory_csv::TrajectoryCsv;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_arm::Arm;
use tactrace_control::{PbtsConfig, PbtsController};
use tactrace_geometry::{Contour, Pose, Vec2};
use tactrace_report::figures;
use tactrace_report::replay_html::{replay_html, PinFields, ReplayPage, StepFrames};
use tactrace_sensor::{Frame, TactileSensor};
use tactrace_servo::{
    evaluate, l2_curve, servo_loop, start_pose, FnSink, FollowMetrics, LoopConfig, LoopSummary,
    Perception, RigConfig, SimRig, StartConfig, StepRecord, TapConfig,
};
use tactrace_store::{write_atomic, SensorFolder, StagedDir, StoredModel};
use tactrace_vision::{BlobParams, PinExtractor};

/// A follow run in the simulated world: one TOML file with these tables,
/// laid over [`SimFollowConfig::default`]; with a `[replay]` table, in the
/// real-frame world ([`crate::replay_world`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimFollowConfig {
    /// A calibrated sensor folder (`tactrace calibrate`, `--sensor`): it
    /// replaces `rig.sensor`, and the model is taken to predict labels in
    /// its convention (mapped to the loop's edge pose by eq. L1).
    pub calibrated_sensor: Option<PathBuf>,
    pub rig: RigConfig,
    pub controller: PbtsConfig,
    pub follow: LoopConfig,
    pub start: StartConfig,
    /// The real-frame world (`follow --replay`), if the run is in it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replay: Option<ReplayWorld>,
}

/// The simulated world's defaults, with the controller tuned in simulation
/// ([`PbtsConfig::tuned`], issue 12), which beats the report's on the
/// held-out contours (docs/results.md).
impl Default for SimFollowConfig {
    fn default() -> Self {
        Self {
            controller: PbtsConfig::tuned(),
            ..Self::report()
        }
    }
}

impl SimFollowConfig {
    /// The report's settings: its PI controller ([`PbtsConfig::report`]),
    /// as `reproduce` runs them.
    pub fn report() -> Self {
        Self {
            calibrated_sensor: None,
            rig: RigConfig::default(),
            controller: PbtsConfig::report(),
            follow: LoopConfig::default(),
            start: StartConfig::default(),
            replay: None,
        }
    }
}

/// What the servo loop needs besides the arm, the sensor and the model:
/// the same on every rig.
#[derive(Debug, Clone, Serialize)]
pub struct ServoSettings {
    pub blob: BlobParams,
    pub controller: PbtsConfig,
    pub follow: LoopConfig,
    pub tap: TapConfig,
}

impl SimFollowConfig {
    /// The loop settings of this configuration.
    pub fn servo_settings(&self) -> ServoSettings {
        ServoSettings {
            blob: self.rig.blob.clone(),
            controller: self.controller.clone(),
            follow: self.follow.clone(),
            tap: self.rig.tap,
        }
    }
}

/// The outcome of a follow run.
pub struct FollowOutcome {
    pub summary: LoopSummary,
    pub records: Vec<StepRecord>,
    /// Against the true contour, when it is known.
    pub metrics: Option<FollowMetrics>,
    pub l2_curve: Vec<f64>,
    /// The finished run folder.
    pub dir: PathBuf,
}

/// The perception of a rig whose undeformed frame is `reference`: refused
/// (before anything moves) when the frame lists its pins otherwise than the
/// model's training data, or the settings cannot work.
pub fn perception_for(
    reference: &Frame,
    model: &StoredModel,
    settings: &ServoSettings,
) -> Result<Perception> {
    settings.follow.validate()?;
    settings.controller.validate()?;
    let extractor = PinExtractor::from_reference_frame(reference, settings.blob.clone())?;
    let net = model.for_pins(
        extractor.tracker.reference(),
        Path::new("the rig's reference frame"),
    )?;
    Ok(Perception::new(
        extractor,
        net.clone(),
        settings.follow.contact_threshold_px,
    )?)
}

/// The servo loop on any arm and sensor, simulated or real, seeing frames
/// through `perception` ([`perception_for`]); each step goes to
/// `dir/trajectory.csv` as it happens and to `progress`.
pub fn follow_on_rig(
    arm: &mut dyn Arm,
    sensor: &mut dyn TactileSensor,
    perception: &Perception,
    settings: &ServoSettings,
    dir: &Path,
    progress: &mut dyn FnMut(&StepRecord),
) -> Result<(LoopSummary, Vec<StepRecord>)> {
    let r = follow_on_rig_recorded(arm, sensor, perception, settings, dir, progress)?;
    Ok((r.summary, r.records))
}

/// A finished loop: how it ended, every step, and every tap's pin
/// displacement vector as the model saw it.
pub struct Recorded {
    pub summary: LoopSummary,
    pub records: Vec<StepRecord>,
    /// One displacement vector a tap (x of every pin, then y, px), in the
    /// perception's reference pin order; empty for a tap whose pins could
    /// not be extracted.
    pub fields: Vec<Vec<f32>>,
}

/// A sensor that keeps the displacement vector of every frame it passes on.
struct FieldRecorder<'a> {
    inner: &'a mut dyn TactileSensor,
    perception: &'a Perception,
    fields: Vec<Vec<f32>>,
}

impl TactileSensor for FieldRecorder<'_> {
    fn capture(&mut self) -> std::result::Result<Frame, tactrace_sensor::SensorError> {
        let frame = self.inner.capture()?;
        let field = self.perception.displacement(&frame).unwrap_or_default();
        self.fields.push(field);
        Ok(frame)
    }
}

/// As [`follow_on_rig`], keeping every tap's displacement vector (for the
/// run's replay page).
pub fn follow_on_rig_recorded(
    arm: &mut dyn Arm,
    sensor: &mut dyn TactileSensor,
    perception: &Perception,
    settings: &ServoSettings,
    dir: &Path,
    progress: &mut dyn FnMut(&StepRecord),
) -> Result<Recorded> {
    let mut controller = PbtsController::try_new(settings.controller.clone())?;
    let mut csv = TrajectoryCsv::create(&dir.join("trajectory.csv"))?;
    let mut records: Vec<StepRecord> = Vec::new();
    let mut bar = FnSink(|r: &StepRecord| progress(r));
    let mut recorder = FieldRecorder {
        inner: sensor,
        perception,
        fields: Vec::new(),
    };
    let summary = servo_loop(
        arm,
        &mut recorder,
        perception,
        &mut controller,
        &settings.follow,
        &settings.tap,
        &mut [&mut csv, &mut records, &mut bar],
    )?;
    let mut fields = recorder.fields;
    fields.truncate(records.len());
    Ok(Recorded {
        summary,
        records,
        fields,
    })
}

/// metrics.json of a follow run: every metric at the top level (the keys
/// scripts read: `mean_l2_mm`, `closed`, `steps`, ...) and how it ended.
#[derive(Serialize)]
struct MetricsDocument<'a> {
    #[serde(flatten)]
    metrics: Option<&'a FollowMetrics>,
    /// The loop's step count when there are no metrics (which have their
    /// own `steps`: one key, not two).
    #[serde(skip_serializing_if = "Option::is_none")]
    steps: Option<usize>,
    ending: tactrace_servo::Ending,
    succeeded: bool,
    message: &'a str,
    /// Why the metrics may say little (a contour smaller than the sensor,
    /// real frames far from the poses reached).
    #[serde(skip_serializing_if = "Option::is_none")]
    warning: Option<String>,
    /// The real-frame world: how near the answered frames' labels were.
    #[serde(skip_serializing_if = "Option::is_none")]
    replay: Option<&'a ReplayStats>,
}

/// What a run knows besides its trajectory: the real-frame world's label
/// distances, and the taps' displacement vectors with the reference pins
/// (px) they are ordered by.
#[derive(Default)]
pub struct RunExtras<'a> {
    pub replay: Option<&'a ReplayStats>,
    pub fields: Option<PinFields<'a>>,
    /// The frames the taps saw (the real-frame world's answers).
    pub frames: Option<StepFrames<'a>>,
}

/// The diameter of the real TacTip's dome, mm (the simulated one's is in
/// its configuration).
pub fn tactip_diameter_mm() -> f64 {
    2.0 * tactrace_sensor::SkinGeometry::default().dome_radius_mm
}

/// A contour smaller than the sensor (`sensor_diameter_mm` across) cannot
/// be followed, and its metrics say little: often a contour in metres
/// where millimetres are meant. The warning, if so.
pub fn size_warning(name: &str, contour: &Contour, sensor_diameter_mm: f64) -> Option<String> {
    let (min, max) = contour.bounds();
    let across = (max - min).max();
    (across < sensor_diameter_mm).then(|| {
        format!(
            "the contour {name} is {across:.3} mm across, smaller than the sensor \
             ({sensor_diameter_mm:.0} mm): it cannot be followed and its metrics say \
             little (contours are in millimetres)"
        )
    })
}

/// Score a finished run against the true contour `shape` (named `name`),
/// if known (report ch. 5.3 and beyond), write `metrics.json` and the
/// figures into `dir`. `sensor_diameter_mm` flags contours smaller than
/// the sensor ([`size_warning`]).
pub fn write_results(
    shape: Option<(&str, &Contour)>,
    records: &[StepRecord],
    summary: &LoopSummary,
    follow: &LoopConfig,
    sensor_diameter_mm: f64,
    dir: &Path,
) -> Result<(Option<FollowMetrics>, Vec<f64>)> {
    let extras = RunExtras::default();
    write_results_with(
        shape,
        records,
        summary,
        follow,
        sensor_diameter_mm,
        dir,
        &extras,
    )
}

/// As [`write_results`], with what else the run knows (`extras`).
pub fn write_results_with(
    shape: Option<(&str, &Contour)>,
    records: &[StepRecord],
    summary: &LoopSummary,
    follow: &LoopConfig,
    sensor_diameter_mm: f64,
    dir: &Path,
    extras: &RunExtras,
) -> Result<(Option<FollowMetrics>, Vec<f64>)> {
    let traj: Vec<Vec2> = records
        .iter()
        .map(|r| Vec2::new(r.pose.x, r.pose.y))
        .collect();
    let scored = shape.map(|(name, contour)| {
        let m = evaluate(
            contour,
            &traj,
            follow.close_radius_mm,
            follow.min_excursion_mm,
        );
        (name, contour, m, l2_curve(contour, &traj, 1000))
    });
    let document = MetricsDocument {
        metrics: scored.as_ref().map(|s| &s.2),
        steps: scored.is_none().then_some(summary.steps),
        ending: summary.ending,
        succeeded: summary.ending.succeeded(),
        message: &summary.message,
        warning: join_warnings([
            shape.and_then(|(name, c)| size_warning(name, c, sensor_diameter_mm)),
            extras.replay.and_then(ReplayStats::warning),
        ]),
        replay: extras.replay,
    };
    let json = serde_json::to_string_pretty(&document).expect("metrics serialise");
    write_atomic(&dir.join("metrics.json"), json.as_bytes())?;
    let page = ReplayPage {
        title: &format!("{} ({})", shape.map_or("run", |s| s.0), world_name(extras)),
        contour: shape.map(|s| s.1),
        steps: records,
        sensor_radius_mm: sensor_diameter_mm / 2.0,
        fields: extras.fields,
        frames: extras.frames,
        notes: &page_notes(&document, extras),
    };
    write_atomic(&dir.join("replay.html"), replay_html(&page).as_bytes())?;
    let Some((name, contour, metrics, curve)) = scored else {
        return Ok((None, Vec::new()));
    };
    if !records.is_empty() {
        let xy: Vec<(f64, f64)> = traj.iter().map(|p| (p.x, p.y)).collect();
        figures::trajectory(&dir.join("trajectory"), name, contour, &xy)?;
        figures::error_curve(&dir.join("l2_error"), name, contour, &curve)?;
    }
    Ok((Some(metrics), curve))
}

/// Which world the run was in, for the replay page's title.
fn world_name(extras: &RunExtras) -> &'static str {
    if extras.replay.is_some() {
        "real-frame world"
    } else {
        "follow run"
    }
}

/// The replay page's summary lines: how the run ended, its metrics, its
/// label distances and warnings.
fn page_notes(doc: &MetricsDocument, extras: &RunExtras) -> Vec<String> {
    let mut notes = vec![format!("{}: {}", doc.ending, doc.message)];
    if let Some(m) = doc.metrics {
        notes.push(format!(
            "{} steps; mean L2 {:.3} mm, track error mean {:.3} / max {:.3} mm, coverage {:.0}%, closed: {}",
            m.steps,
            m.mean_l2_mm,
            m.mean_track_error_mm,
            m.max_track_error_mm,
            100.0 * m.coverage,
            m.closed
        ));
    }
    notes.extend(extras.replay.map(ReplayStats::summary));
    notes.extend(doc.warning.iter().map(|w| format!("warning: {w}")));
    notes
}

/// The warnings given, as one (`None` when there are none).
fn join_warnings<const N: usize>(warnings: [Option<String>; N]) -> Option<String> {
    let all: Vec<String> = warnings.into_iter().flatten().collect();
    (!all.is_empty()).then(|| all.join("; "))
}

/// A run folder being written: `OUT.partial` until [`RunFolder::finish`].
pub struct RunFolder(StagedDir);

impl RunFolder {
    /// Start `out` (refused when it exists, unless `force`), recording the
    /// resolved configuration, seed and version in `config.toml` first.
    pub fn start(out: &Path, force: bool, config: &impl Serialize) -> Result<Self> {
        let stage = StagedDir::new_keeping_partial(out, force)?;
        let text = tactrace_store::resolved_config_toml(crate::VERSION, config)?;
        write_atomic(&stage.path().join("config.toml"), text.as_bytes())?;
        Ok(Self(stage))
    }

    /// Where the run writes now.
    pub fn path(&self) -> &Path {
        self.0.path()
    }

    /// The run is over: the folder becomes `out`.
    pub fn finish(self) -> Result<PathBuf> {
        Ok(self.0.commit()?)
    }
}

/// The start pose of `cfg` on `shape`, refused when the arm's workspace
/// does not hold it.
pub(crate) fn reachable_start(cfg: &SimFollowConfig, shape: &Contour) -> Result<Pose> {
    let start = start_pose(shape, &cfg.start, cfg.rig.tap.height_mm)?;
    cfg.rig.workspace.validate()?;
    cfg.rig.workspace.check_inside(start).map_err(|e| {
        LabError::Config(format!(
            "the arm cannot reach the start on this contour ({:.1}, {:.1}) mm: {e}",
            start.x, start.y
        ))
    })?;
    Ok(start)
}

/// The calibrated sensor of `cfg`, if it names one.
pub fn read_calibrated(cfg: &SimFollowConfig) -> Result<Option<SensorFolder>> {
    match &cfg.calibrated_sensor {
        Some(dir) => Ok(Some(SensorFolder::read(dir)?)),
        None => Ok(None),
    }
}

/// Run the experiment on `shape` (named `name`) in the simulated world with
/// `model`, into the run folder `out`. With `cfg.calibrated_sensor` the
/// world is that sensor and the model predicts in its label convention.
pub fn follow_simulated(
    cfg: &SimFollowConfig,
    model: &StoredModel,
    (name, shape): (&str, &Contour),
    (out, force): (&Path, bool),
    progress: &mut dyn FnMut(&StepRecord),
) -> Result<FollowOutcome> {
    cfg.follow.validate()?;
    let calibrated = read_calibrated(cfg)?;
    let start = reachable_start(cfg, shape)?;
    let seed = cfg.follow.seed;
    let mut rig = match &calibrated {
        Some(s) => {
            cfg.rig.validate()?;
            let mount = s.label_convention().mount_yaw_deg;
            SimRig::with_model(&cfg.rig, s.model()?, mount, shape.clone(), start, seed)
        }
        None => SimRig::new(&cfg.rig, shape.clone(), start, seed)?,
    };
    let mut settings = cfg.servo_settings();
    let perception = match &calibrated {
        // The sensor's real reference frame and blob detector order its
        // taps' pins, as for its real frames; it is mounted so that the
        // controller's aligned pose is its own label angle zero.
        Some(s) => {
            settings.blob = s.spec.blob.clone();
            perception_for(&s.reference, model, &settings)?
                .with_label_convention(s.label_convention())
        }
        None => perception_for(&rig.reference_frame(), model, &settings)?,
    };
    let dome_mm = match &calibrated {
        Some(s) => s.spec.sensor.geometry.dome_radius_mm,
        None => cfg.rig.sensor.geometry.dome_radius_mm,
    };
    let run = RunFolder::start(out, force, cfg)?;
    let (arm, sensor) = rig.parts();
    let Recorded {
        summary,
        records,
        fields,
    } = follow_on_rig_recorded(arm, sensor, &perception, &settings, run.path(), progress)?;
    let extras = RunExtras {
        replay: None,
        fields: Some(PinFields {
            reference_pins: perception.reference_pins(),
            fields: &fields,
        }),
        frames: None,
    };
    let (metrics, l2_curve) = write_results_with(
        Some((name, shape)),
        &records,
        &summary,
        &cfg.follow,
        2.0 * dome_mm,
        run.path(),
        &extras,
    )?;
    let dir = run.finish()?;
    Ok(FollowOutcome {
        summary,
        records,
        metrics,
        l2_curve,
        dir,
    })
}
