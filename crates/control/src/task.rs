//! The servo tasks of pose-based tactile servoing and the pose components
//! each one senses (the field's edge_2d, surface_3d, edge_3d, edge_5d).
use serde::{Deserialize, Serialize};

/// Names of the six pose components, in order (mm, mm, mm, deg, deg, deg).
pub const COMPONENTS: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];

/// A servo task: which components of the sensor's pose relative to the
/// feature (surface or edge) its pose model predicts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Task {
    /// Following an edge in the plane: x (offset from the edge) and rz
    /// (yaw to the edge normal); the report's task.
    #[serde(rename = "edge_2d")]
    Edge2d,
    /// Following a surface: z (depth) and the tilts rx, ry.
    #[serde(rename = "surface_3d")]
    Surface3d,
    /// Following an edge at a varying height: x, z and rz.
    #[serde(rename = "edge_3d")]
    Edge3d,
    /// Following an edge in 3D: x, z, rx, ry and rz.
    #[serde(rename = "edge_5d")]
    Edge5d,
}

impl Task {
    /// Every task, in the order above.
    pub const ALL: [Task; 4] = [Task::Edge2d, Task::Surface3d, Task::Edge3d, Task::Edge5d];

    /// Which of (x, y, z, rx, ry, rz) the task senses.
    pub fn sensed(self) -> [bool; 6] {
        match self {
            Task::Edge2d => [true, false, false, false, false, true],
            Task::Surface3d => [false, false, true, true, true, false],
            Task::Edge3d => [true, false, true, false, false, true],
            Task::Edge5d => [true, false, true, true, true, true],
        }
    }

    /// The task's name as the command line and configs write it.
    pub fn name(self) -> &'static str {
        match self {
            Task::Edge2d => "edge_2d",
            Task::Surface3d => "surface_3d",
            Task::Edge3d => "edge_3d",
            Task::Edge5d => "edge_5d",
        }
    }

    /// The names of the sensed components, e.g. `["z", "rx", "ry"]`.
    pub fn sensed_names(self) -> Vec<&'static str> {
        let sensed = self.sensed();
        (0..6)
            .filter(|&k| sensed[k])
            .map(|k| COMPONENTS[k])
            .collect()
    }

    /// A full six-component pose from a prediction: the sensed components
    /// kept, the others 0 (a model of the task predicts nothing there).
    pub fn fill(self, prediction: [f64; 6]) -> [f64; 6] {
        let sensed = self.sensed();
        std::array::from_fn(|k| if sensed[k] { prediction[k] } else { 0.0 })
    }
}

impl std::fmt::Display for Task {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
