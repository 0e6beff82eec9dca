//! The 3D section `reproduce --3d` adds to the report: surface following
//! (surface_3d) in simulation over the saddle, bowl and wave.
use serde::Serialize;
use std::fmt::Write as _;
use tactrace_servo::Ending;

/// One object followed (`follow --task surface_3d`).
#[derive(Debug, Clone, Serialize)]
pub struct SurfaceRow {
    pub object: String,
    pub mean_distance_mm: f64,
    pub max_distance_mm: f64,
    pub mean_normal_error_deg: f64,
    pub max_normal_error_deg: f64,
    pub coverage: f64,
    pub steps: usize,
    pub ending: Ending,
}

/// The 3D section: the surface model's validation and the runs.
#[derive(Debug, Clone, Serialize)]
pub struct Surface3dSection {
    /// The model's kind.
    pub model: String,
    /// Training and validation taps (flat floor, separate seeds).
    pub train_samples: usize,
    pub val_samples: usize,
    /// Each target's validation MAE: (name, value, unit).
    pub validation_mae: Vec<(String, f64, String)>,
    pub rows: Vec<SurfaceRow>,
}

/// The section's markdown (its figures are the runs' own, under `follow-3d/`).
pub fn surface_markdown(md: &mut String, s: &Surface3dSection) {
    let _ = writeln!(
        md,
        "## Surface following in 3D (surface_3d, simulated)\n\n\
         A {} trained on {} simulated taps on a flat floor (depth 1-5 mm, tilts +-25 deg: \
         the anchors' ranges), validated on {} taps of another seed: {}. It follows a path \
         across each surface with the anchors' SE(3) controller (reference depth 3 mm, 1 mm \
         steps along the sensor's y axis). Distance: |true depth - 3 mm|; normal error: the \
         angle between the sensor's axis and the surface normal (after the first 5 steps). \
         Targets: mean distance <= 0.3 mm, normal error <= 2 deg.\n",
        s.model,
        s.train_samples,
        s.val_samples,
        s.validation_mae
            .iter()
            .map(|(n, v, u)| format!("{n} {v:.3} {u}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    md.push_str("| object | mean distance (mm) | max (mm) | mean normal error (deg) | max (deg) | coverage | steps | ending |\n|---|---|---|---|---|---|---|---|\n");
    for r in &s.rows {
        let _ = writeln!(
            md,
            "| {} | {:.3} | {:.3} | {:.2} | {:.2} | {:.0}% | {} | {} |",
            r.object,
            r.mean_distance_mm,
            r.max_distance_mm,
            r.mean_normal_error_deg,
            r.max_normal_error_deg,
            100.0 * r.coverage,
            r.steps,
            r.ending
        );
    }
    md.push('\n');
    for r in &s.rows {
        let _ = writeln!(
            md,
            "![surface_3d over the {0}](follow-3d/{0}/trajectory_3d.svg) ![errors over the {0}](follow-3d/{0}/errors.svg)\n",
            r.object
        );
    }
    let links: Vec<String> = s
        .rows
        .iter()
        .map(|r| format!("[{0}](follow-3d/{0}/replay.html)", r.object))
        .collect();
    let _ = writeln!(
        md,
        "Step-by-step replays with a view the mouse turns (open beside this report): {}.\n",
        links.join(", ")
    );
}
