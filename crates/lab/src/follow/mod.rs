//! The contour-following experiment (report ch. 5.2-5.3): the servo loop
//! of `tactrace-servo` in a world ([`crate::world`]: the simulated TacTip,
//! a calibrated sensor, the real-frame world, the real rig, or a user's own
//! arm and camera), into a run folder, by one function: [`run`].
//!
//! A run folder holds `config.toml` (the resolved configuration, seed and
//! version), `trajectory.csv` (written and flushed step by step),
//! `replay.html` (the run step by step, self-contained), `metrics.json`
//! (with, in the real-frame world, the label distances of the answered
//! frames, which `answers.csv` lists) and the trajectory and L2 figures.
//! It is built in `OUT.partial` and renamed to `OUT` when the run is over,
//! so a folder named `OUT` is always complete; a run stopped by an error
//! (or killed, or by Ctrl-C on a real rig) leaves its trajectory so far in
//! `OUT.partial`, which the next run into `OUT` replaces.
mod config;
pub mod edge3d;
pub mod edge3d_results;
mod recorder3d;
mod results;
mod results3d;
mod settings3d;
mod sim3d;
pub mod surface_replay;
pub mod task3d;
pub mod task3d_results;

pub use config::{ServoSettings, SimFollowConfig};
pub use recorder3d::Outcome3d;
pub use results::{size_warning, tactip_diameter_mm, write_results, write_results_with, RunExtras};
pub use settings3d::Run3dSettings;

use crate::error::Result;
use crate::trajectory_csv::TrajectoryCsv;
use crate::world::{OpenWorld, ReplayStats};
use serde::Serialize;
use std::path::{Path, PathBuf};
use tactrace_arm::Arm;
use tactrace_control::PbtsController;
use tactrace_geometry::Contour;
use tactrace_sensor::{Frame, TactileSensor};
use tactrace_servo::{
    servo_loop, FnSink, FollowMetrics, ImageInput, LoopSummary, Perception, StepRecord,
};
use tactrace_store::{write_atomic, LoadedModel, StagedDir, StoredImageModel, StoredModel};
use tactrace_vision::PinReader;

/// The outcome of a follow run.
pub struct FollowOutcome {
    pub summary: LoopSummary,
    pub records: Vec<StepRecord>,
    /// Against the true contour, when it is known.
    pub metrics: Option<FollowMetrics>,
    pub l2_curve: Vec<f64>,
    /// The finished run folder.
    pub dir: PathBuf,
    /// In the real-frame world: how near the answered frames' labels were.
    pub replay: Option<ReplayStats>,
}

/// What a run tells its caller as it goes, and how a real rig's run is
/// stopped; each left out (the default) is not told or never asked.
#[derive(Default)]
pub struct RunHooks<'a> {
    /// After every step.
    pub progress: Option<&'a mut dyn FnMut(&StepRecord)>,
    /// What the user should know before the run starts (a contour
    /// smaller than the sensor).
    pub warn: Option<&'a mut dyn FnMut(&str)>,
    /// Stops a real rig's run (SIGINT / SIGTERM in the binary): the arm
    /// is sent `stopl` and the run is kept in `OUT.partial`.
    #[cfg(feature = "hardware")]
    pub stop: Option<&'a crate::hardware::StopFlag>,
}

/// Follow `shape` (its name and its true contour; a real rig may run
/// without one, it is then not scored) in `world` with `model`, into the
/// run folder `out` (refused when it exists, unless `force`): the output
/// is claimed first, then the world builds its arm and sensor (a real rig
/// connects and moves to its start) and the perception, which refuses a
/// model whose pins are ordered otherwise than the world's reference
/// frame; then the run folder gets the world's configuration, the loop
/// runs, and its results are written. A run whose loop ended without
/// error is renamed to `out`, however it ended (its metrics say how); a
/// real rig stopped by `hooks.stop` keeps its steps in `OUT.partial` and
/// fails with [`crate::LabError::Interrupted`].
pub fn run(
    world: OpenWorld,
    model: &StoredModel,
    shape: Option<(&str, &Contour)>,
    (out, force): (&Path, bool),
    hooks: RunHooks,
) -> Result<FollowOutcome> {
    let model = LoadedModel::Pins(model.clone());
    run_model(world, &model, shape, (out, force), hooks)
}

/// [`run`] with any model: a pin model, or an image model, which reads
/// the taps' pixels ([`perception_of`]).
pub fn run_model(
    world: OpenWorld,
    model: &LoadedModel,
    shape: Option<(&str, &Contour)>,
    (out, force): (&Path, bool),
    hooks: RunHooks,
) -> Result<FollowOutcome> {
    let _claim = tactrace_store::check_output_dir(out, force)?;
    let diameter = world.sensor_diameter_mm();
    if let Some(w) = shape.and_then(|(name, c)| size_warning(name, c, diameter)) {
        hooks.warn.unwrap_or(&mut |_| {})(&w);
    }
    #[cfg(feature = "hardware")]
    let stop = hooks.stop.cloned().unwrap_or_default();
    #[cfg(not(feature = "hardware"))]
    let stop = ();
    let (parts, settings, record) = world.into_parts();
    let mut rig = parts.build(shape, model, &settings, &stop)?;
    let run = RunFolder::start(out, force, &record)?;
    let (arm, sensor, perception) = rig.split();
    let mut untold = |_: &StepRecord| {};
    let progress = hooks.progress.unwrap_or(&mut untold);
    let looped = follow_on_rig_recorded(arm, sensor, perception, &settings, run.path(), progress);
    let written = (model, &settings);
    #[cfg(feature = "hardware")]
    if let Some(signal) = stop.requested() {
        return Err(match rig.stop(signal, &stop) {
            crate::LabError::Interrupted {
                signal,
                arm_stopped,
                ..
            } => {
                // The steps so far and how the run ended, in the kept OUT.partial.
                if let Ok(recorded) = &looped {
                    rig.write_results(recorded, shape, written, (run.path(), diameter))?;
                }
                crate::LabError::Interrupted {
                    signal,
                    arm_stopped,
                    kept: Some(run.path().to_path_buf()),
                }
            }
            other => other,
        });
    }
    let recorded = looped?;
    let (metrics, l2_curve, replay) =
        rig.write_results(&recorded, shape, written, (run.path(), diameter))?;
    let dir = run.finish()?;
    Ok(FollowOutcome {
        summary: recorded.summary,
        records: recorded.records,
        metrics,
        l2_curve,
        dir,
        replay,
    })
}

/// The perception of a rig whose undeformed frame is `reference`: refused
/// (before anything moves) when the frame lists its pins otherwise than the
/// model's training data, or when the model predicts no edge pose (one
/// target in mm, one in deg: the controller's r and theta). The pins are
/// found by the settings' detector (blob or small-pin).
pub fn perception_for(
    reference: &Frame,
    model: &StoredModel,
    settings: &ServoSettings,
) -> Result<Perception> {
    perception_with(reference_reader(reference, settings)?, model, settings)
}

/// The settings' detector over the pins it finds in `reference`.
fn reference_reader(reference: &Frame, settings: &ServoSettings) -> Result<PinReader> {
    Ok(PinReader::from_reference_frame(
        settings.detector()?,
        reference,
    )?)
}

/// As [`perception_for`] with the pins read by `reader` (ordered by its
/// rest pins: a calibrated sensor's own, a collection's).
pub fn perception_with(
    reader: PinReader,
    model: &StoredModel,
    settings: &ServoSettings,
) -> Result<Perception> {
    let net = model.for_pins(
        reader.tracker().reference(),
        Path::new("the rig's reference frame"),
    )?;
    net.edge_roles()?;
    Ok(Perception::new(
        reader,
        net.clone(),
        settings.follow().contact_threshold_px,
    )?)
}

/// The perception of `model`, pin or image model, on a rig whose
/// undeformed frame is `reference` ([`perception_for`] a pin model). An
/// image model must predict an edge pose and have been trained on frames
/// that the rig's frames make through its dataset's preprocessing (it
/// sees them made as its training frames were: [`image_input_for`]).
pub fn perception_of(
    reference: &Frame,
    model: &LoadedModel,
    settings: &ServoSettings,
) -> Result<Perception> {
    match model {
        LoadedModel::Pins(m) => perception_for(reference, m, settings),
        LoadedModel::Image(m) => {
            let reader = reference_reader(reference, settings)?;
            image_perception(reader, reference, m, settings)
        }
    }
}

/// The perception of the image model `image` on a rig whose undeformed
/// frame is `reference`, its contact rule's pins read by `reader` (the
/// rig's sensor's detector over its rest pins).
pub fn image_perception(
    reader: PinReader,
    reference: &Frame,
    image: &StoredImageModel,
    settings: &ServoSettings,
) -> Result<Perception> {
    image.model().edge_roles()?;
    image.check_pins(
        reader.tracker().reference(),
        Path::new("the rig's reference frame"),
    )?;
    let input = image_input_for(image)?;
    let rig = input.preprocessed_size(reference.width(), reference.height());
    let trained = image.frames().source_size;
    if rig.as_ref().ok() != Some(&trained) {
        let seen = match &rig {
            Ok([h, w]) => format!("make {h} x {w} px frames"),
            Err(e) => format!("cannot be preprocessed as its training frames were: {e}"),
        };
        return Err(crate::LabError::Config(format!(
            "the image model was trained on frames of {} x {} px, this world's {} x {} px ones {seen}",
            trained[0],
            trained[1],
            reference.height(),
            reference.width()
        )));
    }
    Ok(Perception::with_image_model(
        reader,
        image.model().clone(),
        input,
        settings.follow().contact_threshold_px,
    )?)
}

/// How `model`'s input frames are made: the preprocessing its folder
/// records (none for a folder that records none), then area-averaged to
/// its input size, as its training dataset's `frames.npy` was.
pub fn image_input_for(model: &StoredImageModel) -> Result<ImageInput> {
    Ok(ImageInput::new(
        model.frames().preprocess.as_ref(),
        model.model().input_size(),
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
    let mut controller = PbtsController::try_new(settings.controller().clone())?;
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
        settings.follow(),
        settings.tap(),
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
