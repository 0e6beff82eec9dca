//! A user's own robot and camera drive the Rust servo loop: duck-typed
//! Python objects wrapped into types implementing `tactrace_arm::Arm` and
//! `tactrace_sensor::TactileSensor`, opened as a world of their own
//! (`tactrace_lab::world::OpenWorld::own_rig`, the arm behind the
//! workspace limiter) and run by `follow_rig` through
//! `tactrace_lab::follow::run`, as `tactrace follow --hardware` runs the
//! UR5.
//!
//! The loop runs with the GIL released; each call into the Python objects
//! takes it for the call. An `Exception` raised by them is a fault of the
//! arm or camera: the loop stops safely (as for a real driver's error), and
//! the exception becomes the cause of the `RunFailedError`. Other
//! exceptions (KeyboardInterrupt, SystemExit) stop the call at once.
use crate::errors::{lab, RunFailedError};
use crate::follow::{follow_config, loaded_model, outcome_dict, run_world, shape_contour};
use crate::interrupt::raise;
use crate::vision::to_frame;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use tactrace_arm::{Arm, ArmError};
use tactrace_geometry::Pose;
use tactrace_lab::world::OpenWorld;
use tactrace_sensor::{Frame, SensorError, TactileSensor};

/// The first `Exception` a Python object raised during the run.
type Fault = Arc<Mutex<Option<PyErr>>>;

/// A Python error as a driver error, kept in `fault`; a non-`Exception`
/// (KeyboardInterrupt, SystemExit) ends the call at once.
fn fault(py: Python<'_>, err: PyErr, fault: &Fault, what: &str) -> String {
    if !err.is_instance_of::<PyException>(py) {
        raise(err);
    }
    let msg = format!("{what}: {}", err.value(py));
    if let Ok(mut slot) = fault.lock() {
        slot.get_or_insert(err);
    }
    msg
}

/// A message as an error value.
#[derive(Debug)]
struct PyFault(String);

impl std::fmt::Display for PyFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PyFault {}

/// A Python object with `move_to(pose)` and `pose()` (and optionally
/// `tap_down(depth_mm)`, `tap_up(depth_mm)`) as an [`Arm`].
struct PyArm {
    obj: Py<PyAny>,
    /// The last pose read, for `pose()` when the object fails to answer.
    last: Mutex<Pose>,
    fault: Fault,
}

fn pose_tuple(p: Pose) -> (f64, f64, f64, f64, f64, f64) {
    (p.x, p.y, p.z, p.rx, p.ry, p.rz)
}

impl PyArm {
    /// Call `method(args)` on the object; an exception becomes an
    /// [`ArmError::Hardware`].
    fn call<A>(&self, method: &str, args: A) -> Result<(), ArmError>
    where
        A: for<'py> pyo3::call::PyCallArgs<'py>,
    {
        Python::attach(|py| {
            self.obj
                .bind(py)
                .call_method1(method, args)
                .map(|_| ())
                .map_err(|e| {
                    let msg = fault(py, e, &self.fault, &format!("arm.{method}"));
                    ArmError::Hardware(Arc::new(PyFault(msg)))
                })
        })
    }

    fn has(&self, method: &str) -> bool {
        Python::attach(|py| self.obj.bind(py).hasattr(method).unwrap_or(false))
    }
}

impl Arm for PyArm {
    fn move_to(&mut self, pose: Pose) -> Result<(), ArmError> {
        self.call("move_to", (pose_tuple(pose),))
    }

    fn pose(&self) -> Pose {
        let got = Python::attach(|py| {
            let r = self.obj.bind(py).call_method0("pose");
            match r.and_then(|v| v.extract::<[f64; 6]>()) {
                Ok(p) => Some(Pose::new(p[0], p[1], p[2], p[3], p[4], p[5])),
                Err(e) => {
                    fault(py, e, &self.fault, "arm.pose() (a sequence of 6 numbers)");
                    None
                }
            }
        });
        let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
        match got {
            Some(p) => {
                *last = p;
                p
            }
            // NaN: the next move is refused (non-finite pose) and the run
            // stops with the fault kept.
            None => Pose::new(f64::NAN, f64::NAN, f64::NAN, 0.0, 0.0, 0.0),
        }
    }

    fn tap_down(&mut self, depth_mm: f64) -> Result<(), ArmError> {
        if self.has("tap_down") {
            return self.call("tap_down", (depth_mm,));
        }
        let p = self.pose();
        self.move_to(Pose {
            z: p.z - depth_mm,
            ..p
        })
    }

    fn tap_up(&mut self, depth_mm: f64) -> Result<(), ArmError> {
        if self.has("tap_up") {
            return self.call("tap_up", (depth_mm,));
        }
        let p = self.pose();
        self.move_to(Pose {
            z: p.z + depth_mm,
            ..p
        })
    }
}

/// A Python object with `capture()` returning a (H, W) frame as a
/// [`TactileSensor`].
struct PySensor {
    obj: Py<PyAny>,
    fault: Fault,
}

impl TactileSensor for PySensor {
    fn capture(&mut self) -> Result<Frame, SensorError> {
        Python::attach(|py| {
            let got = self
                .obj
                .bind(py)
                .call_method0("capture")
                .and_then(|f| to_frame(&f, "sensor.capture()"));
            got.map_err(|e| SensorError::FrameUnreadable {
                path: PathBuf::from("<python sensor>"),
                reason: fault(py, e, &self.fault, "sensor.capture()"),
            })
        })
    }
}

/// Follow a contour with your own arm and camera: the Rust servo loop on
/// Python objects.
///
/// ``arm`` has ``move_to(pose)`` (move linearly to ``pose`` = (x, y, z, rx,
/// ry, rz), mm and degrees, work frame, z the sensor tip's height above the
/// object's top face; block until reached) and ``pose()`` (the commanded
/// pose last reached, the same 6 numbers); optionally ``tap_down(depth_mm)``
/// and ``tap_up(depth_mm)`` (straight down / up, blocking; default: through
/// ``move_to``). It is driven behind the limiter of ``config``'s
/// ``rig.workspace`` (moves outside it, or too long, are refused). ``sensor``
/// has ``capture()`` returning the current frame, a (H, W) uint8 array
/// (blocking). Place the arm at the start (tap height, out of contact)
/// first: the reference frame is captured there. ``shape`` (optional, as in
/// ``follow``) is the object's true contour, used only to score the run.
/// Other arguments and the result as ``follow``.
#[pyfunction]
#[pyo3(signature = (model, arm, sensor, *, config = None, shape = None, out = None,
    steps = None, seed = None, force = false, check = true))]
#[allow(clippy::too_many_arguments)]
pub fn follow_rig<'py>(
    py: Python<'py>,
    model: &Bound<'py, PyAny>,
    arm: Py<PyAny>,
    sensor: Py<PyAny>,
    config: Option<&Bound<'py, PyAny>>,
    shape: Option<&Bound<'py, PyAny>>,
    out: Option<PathBuf>,
    steps: Option<usize>,
    seed: Option<u64>,
    force: bool,
    check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = follow_config(config, steps, seed)?;
    let model = loaded_model(model)?;
    let shape = shape.map(shape_contour).transpose()?;
    let reference = to_frame(
        &sensor.bind(py).call_method0("capture")?,
        "sensor.capture()",
    )?;
    let faults: Fault = Arc::default();
    let py_arm = PyArm {
        obj: arm,
        last: Mutex::new(Pose::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)),
        fault: faults.clone(),
    };
    let py_sensor = PySensor {
        obj: sensor,
        fault: faults.clone(),
    };
    let world = OpenWorld::own_rig(py_arm, py_sensor, reference, &cfg).map_err(lab)?;
    let named = shape.as_ref().map(|(n, c)| (n.as_str(), c));
    let res = run_world(py, world, &model, named, (out, force))?;
    let cause = faults.lock().ok().and_then(|mut s| s.take());
    let res = match res {
        Ok(r) => r,
        Err(e) => {
            let err = lab(e);
            err.set_cause(py, cause);
            return Err(err);
        }
    };
    outcome_dict(py, &res, check).inspect_err(|e| {
        if e.is_instance_of::<RunFailedError>(py) {
            e.set_cause(py, cause.as_ref().map(|c| c.clone_ref(py)));
        }
    })
}
