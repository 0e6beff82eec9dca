//! A move the arm refuses for its tilt (`ArmError::TiltTooLarge`) ends a
//! run safely as a refused move, like the workspace and step limits, in
//! the planar loop and the 3D loop (issue 23).
use tactrace_arm::{Arm, ArmError, Pose};
use tactrace_control::{PbtsConfig, PbtsController, Se3Config, Se3Controller, Task};
use tactrace_learn::{Dataset, ModelConfig, ModelKind, ModelTarget, PoseModel, Preset, Unit};
use tactrace_sensor::{Frame, SensorError, TacTipModel, TactileSensor};
use tactrace_servo::{
    servo_loop, servo_loop_3d, Ending, Loop3dConfig, LoopConfig, Perception, Perception3d,
    RigConfig, Step3d,
};
use tactrace_vision::{PinExtractor, PinReader};

/// An arm that taps straight down and up but refuses every other move
/// for its tilt.
struct TiltLimited(Pose);

impl Arm for TiltLimited {
    fn pose(&self) -> Pose {
        self.0
    }
    fn move_to(&mut self, target: Pose) -> Result<(), ArmError> {
        let vertical = target.x == self.0.x && target.y == self.0.y;
        let same_turn = target.rx == self.0.rx && target.ry == self.0.ry && target.rz == self.0.rz;
        if vertical && same_turn {
            self.0 = target;
            return Ok(());
        }
        Err(ArmError::TiltTooLarge {
            tilt_deg: 50.0,
            max_deg: 45.0,
        })
    }
}

/// Always the same pressed frame.
struct Pressed(Frame);

impl TactileSensor for Pressed {
    fn capture(&mut self) -> Result<Frame, SensorError> {
        Ok(self.0.clone())
    }
}

/// The rig's extractor, a pressed frame, and an untrained small model of
/// `targets` (only the loop's handling of the refusal matters here).
fn parts(targets: Vec<ModelTarget>) -> (PinExtractor, Frame, PoseModel) {
    let rig = RigConfig::default();
    let sensor = TacTipModel::new(rig.sensor.clone()).unwrap();
    let reference = sensor.render(sensor.rest_pins(), None);
    let extractor = PinExtractor::from_reference_frame(&reference, rig.blob).unwrap();
    let floor = tactrace_shape3d::HeightField::ramp(0.0, 0.0, 0.0).unwrap();
    let tip = Pose::new(0.0, 0.0, -3.0, 0.0, 0.0, 0.0);
    let frame = sensor.render(&sensor.pins_3d(&floor, tip, None), None);
    let dim = 2 * extractor.tracker.reference().len();
    let (n, t) = (8, targets.len());
    let x = (0..n * dim).map(|k| (k % 7) as f32 - 3.0).collect();
    let y = (0..t * n).map(|k| k as f32).collect();
    let data = Dataset::new(x, y, n, dim, t).unwrap();
    let mut cfg = ModelConfig::preset(ModelKind::DisDenNN, Preset::Default);
    cfg.set_epochs(1);
    if let Some(net) = cfg.pose.as_mut() {
        net.hidden = vec![4];
    }
    let model = PoseModel::fit_targets(&cfg, &targets, &data, None, &mut |_| {}).unwrap();
    (extractor, frame, model.0)
}

#[test]
fn tilt_too_large_ends_the_planar_loop_as_a_refused_move() {
    let (extractor, frame, model) = parts(vec![
        ModelTarget::new("r", Unit::Mm),
        ModelTarget::new("theta", Unit::Deg),
    ]);
    let reader = PinReader::new(
        tactrace_vision::FrameDetector::unprocessed(extractor.detector, [1, 1]).unwrap(),
        extractor.tracker.reference().to_vec(),
    )
    .unwrap();
    let perception = Perception::new(reader, model, 0.0).unwrap();
    let mut arm = TiltLimited(Pose::new(0.0, 0.0, 2.0, 0.0, 0.0, 0.0));
    let mut controller = PbtsController::try_new(PbtsConfig::report()).unwrap();
    let cfg = LoopConfig {
        steps: Some(5),
        ..LoopConfig::default()
    };
    let tap = RigConfig::default().tap;
    let summary = servo_loop(
        &mut arm,
        &mut Pressed(frame),
        &perception,
        &mut controller,
        &cfg,
        &tap,
        &mut [],
    )
    .unwrap();
    assert_eq!(summary.ending, Ending::Refused, "{}", summary.message);
    assert_eq!(summary.steps, 1);
    assert!(summary.message.contains("tilt"), "{}", summary.message);
}

#[test]
fn tilt_too_large_ends_the_surface_loop_as_a_refused_move() {
    let targets = vec![
        ModelTarget::new("z", Unit::Mm),
        ModelTarget::new("rx", Unit::Deg),
        ModelTarget::new("ry", Unit::Deg),
    ];
    let (extractor, frame, model) = parts(targets);
    let perception = Perception3d::new(extractor, model, Task::Surface3d.sensed(), 0.0).unwrap();
    let mut arm = TiltLimited(Pose::new(0.0, 0.0, -3.0, 0.0, 0.0, 0.0));
    let mut controller = Se3Controller::try_new(Se3Config::surface_3d()).unwrap();
    let cfg = Loop3dConfig {
        steps: 5,
        max_no_contact: 3,
        lift_mm: 0.0,
        closure: None,
    };
    let mut seen = 0;
    let mut sink = |_: &Step3d, _: &[f32]| {
        seen += 1;
        Ok(())
    };
    let summary = servo_loop_3d(
        &mut arm,
        &mut Pressed(frame),
        &perception,
        &mut controller,
        &cfg,
        &mut sink,
    )
    .unwrap();
    assert_eq!(summary.ending, Ending::Refused, "{}", summary.message);
    assert_eq!((summary.steps, seen), (1, 1));
    assert!(summary.message.contains("tilt"), "{}", summary.message);
}
