//! The simulated TacTip as a [`TactileSensor`]: asks the simulated arm where
//! the tip physically is, deforms the model skin against the object and
//! renders the frame with seeded nuisance; the object is an extruded
//! contour (the planar contact) or any 3D object (the tilted contact).
use crate::{Frame, SensorError, Shear, TacTipModel, TactileSensor};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tactrace_geometry::{Contour, Pose};
use tactrace_shape3d::Surface;

/// Where the tip physically is (mm, deg), e.g. read from a simulated arm.
pub type PoseSource = Box<dyn Fn() -> Pose + Send>;

/// What the simulated TacTip touches.
enum Touched {
    /// An extruded contour, its top face at z = 0 (`TacTipModel::pins`).
    Contour(Contour),
    /// A 3D object (`TacTipModel::pins_3d`).
    Object(Surface),
}

/// A simulated TacTip touching one object.
pub struct SimTacTip {
    model: TacTipModel,
    touched: Touched,
    pose_source: PoseSource,
    rng: ChaCha8Rng,
    shear: Option<Shear>,
}

impl SimTacTip {
    /// `pose_source` returns the PHYSICAL pose of the sensor tip (from the
    /// simulated arm); `seed` fixes the nuisance stream.
    pub fn new(model: TacTipModel, shape: Contour, pose_source: PoseSource, seed: u64) -> Self {
        Self {
            model,
            touched: Touched::Contour(shape),
            pose_source,
            rng: ChaCha8Rng::seed_from_u64(seed),
            shear: None,
        }
    }

    /// As [`Self::new`] over a 3D object: `pose_source` returns the tip's
    /// 6-DoF pose in the object's frame (see [`TacTipModel::pins_3d`]).
    pub fn over_object(
        model: TacTipModel,
        object: Surface,
        pose_source: PoseSource,
        seed: u64,
    ) -> Self {
        Self {
            model,
            touched: Touched::Object(object),
            pose_source,
            rng: ChaCha8Rng::seed_from_u64(seed),
            shear: None,
        }
    }

    /// The undeformed frame (no contact, no nuisance).
    pub fn reference_frame(&self) -> Frame {
        self.model.render(self.model.rest_pins(), None)
    }

    /// Slide applied to subsequent captures (None = plain taps).
    pub fn set_shear(&mut self, shear: Option<Shear>) {
        self.shear = shear;
    }

    /// The sensor model.
    pub fn model(&self) -> &TacTipModel {
        &self.model
    }
}

impl TactileSensor for SimTacTip {
    /// Reads the tip pose, computes the pins and renders with nuisance.
    fn capture(&mut self) -> Result<Frame, SensorError> {
        let tip = (self.pose_source)();
        let pins = match &self.touched {
            Touched::Contour(shape) => self.model.pins(shape, tip, self.shear),
            Touched::Object(object) => self.model.pins_3d(object.as_ref(), tip, self.shear),
        };
        let pins = self.model.seen_pins(pins);
        Ok(self.model.render(&pins, Some(&mut self.rng)))
    }
}
