//! The simulated TacTip from Python: `SimTacTip` over
//! `tactrace_lab::render::TapRenderer` (the code of `tactrace sensor
//! render`), the rig's default sensor over a contour or a calibrated
//! sensor folder on a straight edge.
use crate::arrays::points_array;
use crate::errors::{input, lab, store};
use crate::follow::shape_contour;
use crate::vision::frame_array;
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::path::PathBuf;
use tactrace_geometry::Pose;
use tactrace_lab::render::{TapPose, TapRenderer};
use tactrace_sensor::Shear;

/// A simulated TacTip (docs/sensor-model.md).
///
/// With no ``sensor`` it is the simulated rig's TacTip (``config``: a rig
/// configuration TOML as ``sensor render --config``) tapping ``shape`` (a
/// built-in name, a CSV of x,y points in mm, or an N x 2 array in mm) at an
/// edge point; with ``sensor``, a calibrated sensor folder (``tactrace
/// calibrate``), it taps a straight edge in that sensor's label convention
/// and pin layout. ``seed`` drives the optional noise of ``render(...,
/// noise=True)``.
#[pyclass(module = "tactrace")]
pub struct SimTacTip {
    renderer: TapRenderer,
    rng: ChaCha8Rng,
    calibrated: bool,
    contour: Option<tactrace_geometry::Contour>,
}

fn tap_pose(
    r_mm: f64,
    theta_deg: f64,
    depth_mm: Option<f64>,
    shear: Option<(f64, f64, f64)>,
    arc_mm: f64,
) -> TapPose {
    TapPose {
        r_mm,
        theta_deg,
        depth: depth_mm,
        arc_mm,
        shear: shear.map(|(dx_mm, dy_mm, drz_deg)| Shear {
            dx_mm,
            dy_mm,
            drz_deg,
        }),
    }
}

#[pymethods]
impl SimTacTip {
    #[new]
    #[pyo3(signature = (sensor = None, seed = 0, *, shape = None, config = None))]
    fn new(
        py: Python<'_>,
        sensor: Option<PathBuf>,
        seed: u64,
        shape: Option<&Bound<'_, PyAny>>,
        config: Option<PathBuf>,
    ) -> PyResult<Self> {
        let rng = ChaCha8Rng::seed_from_u64(seed);
        if let Some(dir) = sensor {
            if shape.is_some() || config.is_some() {
                return Err(input(
                    "a calibrated sensor taps its own straight edge: give sensor or shape/config, not both",
                ));
            }
            let folder = py
                .detach(|| tactrace_store::SensorFolder::read(&dir))
                .map_err(store)?;
            let renderer = TapRenderer::calibrated(&folder).map_err(lab)?;
            return Ok(Self {
                renderer,
                rng,
                calibrated: true,
                contour: None,
            });
        }
        let contour = match shape {
            Some(s) => shape_contour(s)?.1,
            None => shape_contour(pyo3::types::PyString::new(py, "disk").as_any())?.1,
        };
        let rig: tactrace_servo::RigConfig =
            tactrace_store::load_config(config.as_deref(), "rig configuration").map_err(store)?;
        let renderer = TapRenderer::simulated(&rig, contour.clone()).map_err(lab)?;
        Ok(Self {
            renderer,
            rng,
            calibrated: false,
            contour: Some(contour),
        })
    }

    /// Render a tap as a uint8 (H, W) frame, as ``tactrace sensor render``:
    /// edge position ``r_mm`` (positive: sensor centre outside the object),
    /// sensor angle ``theta_deg`` to the edge, ``depth_mm`` of indentation
    /// (default: the rig's nominal tap; for a calibrated sensor its
    /// vertical offset label, default 0), ``shear`` an optional slide
    /// ``(dx_mm, dy_mm, drz_deg)`` (sensor frame; for a calibrated sensor
    /// its move labels), ``arc_mm`` the edge point's arc length on the
    /// contour. ``noise=True`` adds the configured pin jitter and image
    /// noise from the seeded generator (both 0 in the fitted default
    /// sensor: set ``[sensor.nuisance]`` in ``config``).
    #[pyo3(signature = (r_mm, theta_deg, depth_mm = None, shear = None, *, arc_mm = 0.0, noise = false))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        r_mm: f64,
        theta_deg: f64,
        depth_mm: Option<f64>,
        shear: Option<(f64, f64, f64)>,
        arc_mm: f64,
        noise: bool,
    ) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        let t = tap_pose(r_mm, theta_deg, depth_mm, shear, arc_mm);
        let pins = self.renderer.pins(&t).map_err(lab)?;
        let rng = noise.then_some(&mut self.rng);
        let frame = self.renderer.model().render(&pins, rng);
        frame_array(py, frame)
    }

    /// The undeformed frame (sensor in the air): the reference frame of a
    /// ``PinExtractor``.
    fn render_rest<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        let model = self.renderer.model();
        frame_array(py, model.render(model.rest_pins(), None))
    }

    /// The true pin centres (P x 2 float64, px, rest-pin order) of the tap
    /// ``render`` draws with the same arguments.
    #[pyo3(signature = (r_mm, theta_deg, depth_mm = None, shear = None, *, arc_mm = 0.0))]
    fn true_pins<'py>(
        &self,
        py: Python<'py>,
        r_mm: f64,
        theta_deg: f64,
        depth_mm: Option<f64>,
        shear: Option<(f64, f64, f64)>,
        arc_mm: f64,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let t = tap_pose(r_mm, theta_deg, depth_mm, shear, arc_mm);
        points_array(py, &self.renderer.pins(&t).map_err(lab)?)
    }

    /// The frame with the sensor tip at ``pose`` = (x, y, z, rx, ry, rz) in
    /// the work frame (mm, deg; z the tip's height above the object's top
    /// face, negative when pressed in) over the contour: what a camera on
    /// an arm at that pose sees (the ``TactileSensor`` of a Python rig).
    fn render_at<'py>(
        &self,
        py: Python<'py>,
        pose: [f64; 6],
    ) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        let contour = self.contour.as_ref().ok_or_else(|| {
            input(
                "render_at needs a contour; a calibrated sensor taps a straight edge (use render)",
            )
        })?;
        if pose.iter().any(|v| !v.is_finite()) {
            return Err(input(format!(
                "pose ({}) has a non-finite component",
                crate::arrays::numbers_text(&pose)
            )));
        }
        let [x, y, z, rx, ry, rz] = pose;
        let model = self.renderer.model();
        let pins = model.pins(contour, Pose::new(x, y, z, rx, ry, rz), None);
        frame_array(py, model.render(&pins, None))
    }

    /// The rest pins (P x 2 float64, px), in the simulator's order.
    #[getter]
    fn rest_pins<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        points_array(py, self.renderer.model().rest_pins())
    }

    /// Frame size (height, width), px.
    #[getter]
    fn shape(&self) -> (u32, u32) {
        let (w, h) = self.renderer.model().image_size();
        (h, w)
    }

    /// True for a calibrated sensor folder.
    #[getter]
    fn calibrated(&self) -> bool {
        self.calibrated
    }
}
