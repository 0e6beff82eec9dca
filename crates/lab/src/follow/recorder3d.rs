//! The 3D runs' loop and step sink, written once: every edge or surface
//! run (simulated or in the real-frame world) runs its SE(3) controller
//! through [`record_loop_3d`], and every step goes to its `trajectory.csv`
//! row writer (a [`StepRows`]: the edge's or the surface's truth columns),
//! then to the caller's progress, and is kept with the pose the arm
//! physically reached (and, when asked, the pin field) for the metrics and
//! figures written after the loop.
use crate::error::Result;
use std::path::PathBuf;
use tactrace_arm::{Arm, Pose, PoseProbe};
use tactrace_control::{Se3Config, Se3Controller};
use tactrace_servo::{servo_loop_3d_taps, Loop3dConfig, LoopSummary, Sensed, ServoError, Step3d};

/// A finished 3D run: how its loop ended, its scores `M`, its folder.
pub struct Outcome3d<M> {
    pub summary: LoopSummary,
    pub metrics: M,
    pub dir: PathBuf,
}

/// A 3D run's `trajectory.csv`: one row per step.
pub trait StepRows {
    /// Write step `s`'s row, `reached` being the pose the arm reached.
    fn write(&mut self, s: &Step3d, reached: Pose) -> tactrace_store::Result<()>;
}

/// What a 3D run keeps of its steps: the loop's records, the poses the arm
/// reached (mm, deg) and, when kept, each step's pin field.
pub(super) struct Recorded3d {
    /// The loop's steps, in order.
    pub steps: Vec<Step3d>,
    /// The pose the arm reached at each step.
    pub reached: Vec<Pose>,
    /// Each step's pin field (empty unless kept).
    pub fields: Vec<Vec<f32>>,
}

/// The sink of a 3D run's loop: rows to `rows`, each step to `progress`,
/// the steps kept in [`Recorded3d`].
pub(super) struct Recorder3d<'a, R: StepRows> {
    rows: R,
    probe: PoseProbe,
    progress: &'a mut dyn FnMut(&Step3d),
    keep_fields: bool,
    kept: Recorded3d,
}

impl<'a, R: StepRows> Recorder3d<'a, R> {
    /// A recorder writing to `rows`, reading the reached pose from `probe`
    /// and telling `progress` of each step; fields are kept when
    /// `keep_fields`.
    pub fn new(
        rows: R,
        probe: PoseProbe,
        progress: &'a mut dyn FnMut(&Step3d),
        keep_fields: bool,
    ) -> Self {
        Self {
            rows,
            probe,
            progress,
            keep_fields,
            kept: Recorded3d {
                steps: Vec::new(),
                reached: Vec::new(),
                fields: Vec::new(),
            },
        }
    }

    /// Record one step of the loop (its pin field `field`); a row that
    /// cannot be written stops the loop as a sink error of that step.
    pub fn record(&mut self, s: &Step3d, field: &[f32]) -> tactrace_servo::Result<()> {
        // The arm is still at the tap's pose: what it physically reached.
        let at = self.probe.actual();
        self.rows.write(s, at).map_err(|e| ServoError::Sink {
            step: s.step,
            source: Box::new(e),
        })?;
        (self.progress)(s);
        self.kept.steps.push(s.clone());
        self.kept.reached.push(at);
        if self.keep_fields {
            self.kept.fields.push(field.to_vec());
        }
        Ok(())
    }

    /// The steps kept, the row writer closed.
    pub fn finish(self) -> Recorded3d {
        self.kept
    }
}

/// Run a 3D run's loop (`loop_cfg`) with the SE(3) controller `controller`,
/// from the arm's pose, each tap's percept from `tap` and each step to
/// `recorder`: how the loop ended, and the steps it kept.
pub(super) fn record_loop_3d<R: StepRows>(
    arm: &mut dyn Arm,
    tap: &mut dyn FnMut() -> tactrace_servo::Result<Sensed>,
    (controller, loop_cfg): (&Se3Config, &Loop3dConfig),
    mut recorder: Recorder3d<'_, R>,
) -> Result<(LoopSummary, Recorded3d)> {
    let mut controller = Se3Controller::try_new(controller.clone())?;
    let summary = {
        let mut sink = |s: &Step3d, field: &[f32]| recorder.record(s, field);
        servo_loop_3d_taps(arm, tap, &mut controller, loop_cfg, &mut sink)?
    };
    Ok((summary, recorder.finish()))
}

#[cfg(test)]
mod tests {
    use super::{Recorder3d, StepRows};
    use std::path::PathBuf;
    use tactrace_arm::{Pose, SimArm, SimArmConfig};
    use tactrace_servo::{ServoError, Step3d};
    use tactrace_store::StoreError;

    /// Rows kept in memory; the step numbered `fail_at` cannot be written.
    struct Rows {
        written: Vec<(usize, Pose)>,
        fail_at: usize,
    }

    impl StepRows for &mut Rows {
        fn write(&mut self, s: &Step3d, reached: Pose) -> tactrace_store::Result<()> {
            if s.step == self.fail_at {
                return Err(StoreError::Write {
                    path: PathBuf::from("trajectory.csv"),
                    source: std::io::Error::other("disk full"),
                });
            }
            self.written.push((s.step, reached));
            Ok(())
        }
    }

    fn step(step: usize) -> Step3d {
        Step3d {
            step,
            pose: Pose::new(1.0, 2.0, 3.0, 0.0, 0.0, 0.0),
            label: [0.0; 6],
            mean_displacement_px: 0.5,
            contact: true,
            u: [0.0; 6],
        }
    }

    /// Each step: its row at the reached pose, then progress, then kept
    /// (fields only when asked); a row that fails is the sink error of
    /// its step and the step is not kept.
    #[test]
    fn the_3d_recorder_writes_tells_and_keeps_each_step() {
        let start = Pose::new(10.0, 20.0, 30.0, 0.0, 0.0, 45.0);
        let (_arm, probe) = SimArm::with_probe(SimArmConfig::default(), start);
        for keep_fields in [false, true] {
            let mut rows = Rows {
                written: Vec::new(),
                fail_at: 2,
            };
            let mut heard = Vec::new();
            let mut progress = |s: &Step3d| heard.push(s.step);
            let mut rec = Recorder3d::new(&mut rows, probe.clone(), &mut progress, keep_fields);
            rec.record(&step(0), &[1.0, 2.0]).expect("step 0");
            rec.record(&step(1), &[3.0]).expect("step 1");
            let err = rec.record(&step(2), &[4.0]).expect_err("step 2 fails");
            assert!(matches!(err, ServoError::Sink { step: 2, .. }), "{err}");
            let kept = rec.finish();
            assert_eq!(
                kept.steps.iter().map(|s| s.step).collect::<Vec<_>>(),
                [0, 1]
            );
            assert_eq!(kept.reached, [start, start]);
            let fields: &[Vec<f32>] = if keep_fields {
                &[vec![1.0, 2.0], vec![3.0]]
            } else {
                &[]
            };
            assert_eq!(kept.fields, fields);
            assert_eq!(heard, [0, 1]);
            assert_eq!(rows.written, [(0, start), (1, start)]);
        }
    }
}
