//! What real frames and their reference are checked for before and after
//! an import (`import`, `calibrate`, `sim-fit`, `reproduce --real`): a
//! `--frames` folder one level above the frames, a `--reference` frame
//! that is itself pressed, a target of one value in every row, and pins
//! that do not move at all (every frame the same, or the reference one
//! of them: [`still_pins`], a warning here and a refusal in `train`).
//!
//! **A pressed reference.** Pressing the dome spreads its pins apart in
//! the image: against the undeformed frame every tap of the shared real
//! set (3762 frames) and of the simulator has a positive spread `s`, the
//! least-squares isotropic scale of its displacement field about the
//! reference pins' centroid, `s = sum (p - c) . d / sum |p - c|^2` (the
//! least spread 0.016 on the real set). Against a tapped frame taken as
//! reference, the frames less pressed than it contract: 4.8-83 % of them
//! had `s < 0` for the four tapped frames tried. More than [`PRESSED_FRACTION`] of
//! the frames contracting names the reference as pressed. The test is
//! cheap (one pass over the displacements) and needs no model of the
//! sensor; it cannot see a reference pressed no more than the lightest
//! taps, whose fields are then off by little.
use crate::error::LabError;
use std::path::Path;
use tactrace_learn::Unit;
use tactrace_store::TapData;

/// Fraction of frames that may be less spread than the reference before
/// it is called pressed (noise on a truly undeformed reference leaves none
/// on the shared real set).
pub const PRESSED_FRACTION: f64 = 0.01;
/// Fewest frames the pressed-reference check judges.
pub const PRESSED_MIN_FRAMES: usize = 10;

/// An error when the first labelled frame `image` is not in `frames` but a
/// subfolder of it holds it (`--frames` given one level too high), or when
/// it is nowhere there; `None` when it is there.
pub(crate) fn frames_folder(frames: &Path, image: &str) -> Option<LabError> {
    if image.is_empty() || frames.join(image).exists() {
        return None;
    }
    let holder = std::fs::read_dir(frames).ok().and_then(|entries| {
        let mut dirs: Vec<_> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_dir() && p.join(image).is_file())
            .collect();
        dirs.sort();
        dirs.into_iter().next()
    });
    let reason = match holder {
        Some(sub) => format!(
            "no frame `{image}` (the first labelled row's image) in this folder, but its \
             subfolder {} holds it: give --frames {}",
            sub.display(),
            sub.display()
        ),
        None => format!(
            "no frame `{image}` (the first labelled row's image) in this folder: --frames \
             is the folder of the labelled images (named by the --image-column)"
        ),
    };
    Some(LabError::Format {
        path: frames.to_path_buf(),
        reason,
    })
}

/// The spread of each of the `n` displacement rows of `inputs` (`n x 2P`:
/// P x-displacements then P y-displacements, px) about the centroid of
/// `reference` (P pins, px): the least-squares isotropic scale.
pub fn spreads(reference: &[[f64; 2]], inputs: &[f32], n: usize) -> Vec<f64> {
    let p = reference.len();
    if p == 0 || inputs.len() != n * 2 * p {
        return Vec::new();
    }
    let c = reference.iter().fold([0.0, 0.0], |a, q| {
        [a[0] + q[0] / p as f64, a[1] + q[1] / p as f64]
    });
    let arm: Vec<[f64; 2]> = reference
        .iter()
        .map(|q| [q[0] - c[0], q[1] - c[1]])
        .collect();
    let norm: f64 = arm.iter().map(|a| a[0] * a[0] + a[1] * a[1]).sum();
    if norm <= 0.0 {
        return Vec::new();
    }
    inputs
        .chunks_exact(2 * p)
        .map(|row| {
            let (dx, dy) = row.split_at(p);
            let dot: f64 = arm
                .iter()
                .zip(dx.iter().zip(dy))
                .map(|(a, (&x, &y))| a[0] * f64::from(x) + a[1] * f64::from(y))
                .sum();
            dot / norm
        })
        .collect()
}

/// A warning when the reference of the `n` imported rows looks pressed
/// (see the module's notes); `reference_path` names it.
pub fn pressed_reference(
    reference_path: &Path,
    reference: &[[f64; 2]],
    inputs: &[f32],
    n: usize,
) -> Option<String> {
    let s = spreads(reference, inputs, n);
    if s.len() < PRESSED_MIN_FRAMES {
        return None;
    }
    let contracting = s.iter().filter(|v| **v < 0.0).count();
    let fraction = contracting as f64 / s.len() as f64;
    (fraction > PRESSED_FRACTION).then(|| {
        format!(
            "{}: the reference looks pressed: {contracting} of the {} frames ({:.0}%) have \
             their pins closer together than it has (a tap spreads them apart); give the \
             sensor's frame taken without contact as --reference, or the displacements and \
             everything trained on them are off",
            reference_path.display(),
            s.len(),
            100.0 * fraction
        )
    })
}

/// A warning for each target that has one value in every row of `data`
/// (of two rows or more): a label column that is not the one meant (the
/// edge task's `pose_2` and `pose_6`, read by default, are zero in a
/// collection of surface taps), which no model can learn anything from.
pub fn constant_targets(data: &TapData) -> Vec<String> {
    let (n, k) = (data.len(), data.n_targets());
    let names: Vec<String> = match data.meta.model_targets() {
        Ok(t) => t.into_iter().map(|t| t.name).collect(),
        Err(_) => data.meta.targets.clone(),
    };
    if n < 2 || names.len() != k {
        return Vec::new();
    }
    let column = |j: usize| data.targets.iter().skip(j).step_by(k);
    (0..k)
        .filter(|&j| column(j).all(|v| *v == data.targets[j]))
        .map(|j| {
            format!(
                "the target {} is {} in every one of the {n} rows: is it the label column \
                 meant? Name the label columns with --target COLUMN:UNIT",
                names[j], data.targets[j]
            )
        })
        .collect()
}

/// Span (deg) from which an angle not marked circular is warned about.
pub const WRAP_SPAN_DEG: f64 = 300.0;

/// A warning for each target in degrees, not marked circular, whose
/// values span [`WRAP_SPAN_DEG`] or more: likely an angle over the full
/// circle (a heading, say), whose -179 and 179 deg the model would learn
/// as 358 deg apart. Marked `--target COLUMN:deg:circular`, it is learnt
/// as its sine and cosine and its errors are wrapped.
pub fn wrapping_angles(data: &TapData) -> Vec<String> {
    let (n, k) = (data.len(), data.n_targets());
    let Ok(targets) = data.meta.model_targets() else {
        return Vec::new();
    };
    if n < 2 || targets.len() != k {
        return Vec::new();
    }
    let span = |j: usize| {
        let column = data
            .targets
            .iter()
            .skip(j)
            .step_by(k)
            .map(|v| f64::from(*v));
        let (lo, hi) = column.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        hi - lo
    };
    targets
        .iter()
        .enumerate()
        .filter(|(_, t)| t.unit == Unit::Deg && !t.circular)
        .filter_map(|(j, t)| {
            let s = span(j);
            (s >= WRAP_SPAN_DEG).then(|| {
                format!(
                    "the target {} spans {s:.0} deg and is not marked circular: if it is an \
                     angle that wraps (-180 and 180 the same), import it as --target {}:deg:circular",
                    t.name, t.name
                )
            })
        })
        .collect()
}

/// How the pin displacements of a dataset fail to vary, when they do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StillPins {
    /// Every displacement of every row is 0: each frame shows its pins
    /// where the reference has them (the reference is every frame).
    AllZero,
    /// Every row is the same, not all zero: the frames are all alike.
    AllSame,
}

impl StillPins {
    /// What it means for the user, for a dataset of `rows` rows.
    pub fn says(self, rows: usize) -> String {
        let what = match self {
            StillPins::AllZero => {
                "every pin displacement is 0: each frame shows its pins where the reference \
                 has them (is the reference one of the frames, or are the frames all the same?)"
            }
            StillPins::AllSame => {
                "every row has the same pin displacements: the frames are all alike"
            }
        };
        format!(
            "{what}, in all {rows} rows; no model can learn a pose from them (give the \
             sensor's frame taken without contact as the reference, and frames of taps)"
        )
    }
}

/// Whether the `n` rows of `inputs` (each `inputs.len() / n` values) are
/// all zero or all the same; `None` when they vary, or for fewer than
/// two rows.
pub fn still_pins(inputs: &[f32], n: usize) -> Option<StillPins> {
    if n < 2 || inputs.is_empty() || !inputs.len().is_multiple_of(n) {
        return None;
    }
    let width = inputs.len() / n;
    let first = &inputs[..width];
    if inputs.chunks_exact(width).any(|row| row != first) {
        return None;
    }
    Some(if first.iter().all(|v| *v == 0.0) {
        StillPins::AllZero
    } else {
        StillPins::AllSame
    })
}

/// The warning of an import whose pins do not move ([`still_pins`]).
pub fn still_pins_warning(data: &TapData) -> Option<String> {
    still_pins(&data.inputs, data.len()).map(|still| still.says(data.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pins_that_never_move_are_told_apart_from_pins_that_do() {
        let zero = vec![0.0f32; 3 * 4];
        assert_eq!(still_pins(&zero, 3), Some(StillPins::AllZero));
        let same: Vec<f32> = [0.5f32, -1.0, 0.0, 2.0].repeat(3);
        assert_eq!(still_pins(&same, 3), Some(StillPins::AllSame));
        let mut moving = same.clone();
        moving[11] = 2.5;
        assert_eq!(still_pins(&moving, 3), None);
        assert_eq!(still_pins(&zero[..4], 1), None, "one row says nothing");
        assert!(StillPins::AllZero.says(3).contains("all 3 rows"));
    }

    #[test]
    fn a_target_of_one_value_is_named() {
        let mut data = crate::test_data::edge_data(
            vec![0.0; 6],
            vec![1.0, 0.0, 2.0, 0.0, 3.0, 0.0],
            &[[0.0, 0.0]],
        );
        let w = constant_targets(&data);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains("theta is 0 in every one of the 3 rows"),
            "{w:?}"
        );
        data.targets[5] = 0.5;
        assert!(constant_targets(&data).is_empty());
    }

    /// An angle spanning 300 deg or more is warned about unless it is
    /// circular; a narrower one, and a position, are not.
    #[test]
    fn a_wide_angle_not_marked_circular_is_warned_about() {
        let mut data = crate::test_data::edge_data(
            vec![0.0; 6],
            vec![1.0, -170.0, 2.0, 0.0, 400.0, 129.0],
            &[[0.0, 0.0]],
        );
        assert!(wrapping_angles(&data).is_empty(), "299 deg, and r in mm");
        data.targets[5] = 130.0;
        let w = wrapping_angles(&data);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("theta spans 300 deg"), "{w:?}");
        assert!(w[0].contains("--target theta:deg:circular"), "{w:?}");
    }

    /// A hexagon of pins about (10, 20) and rows scaled by `scales`.
    fn rows(scales: &[f64]) -> (Vec<[f64; 2]>, Vec<f32>) {
        let reference: Vec<[f64; 2]> = (0..6)
            .map(|k| {
                let t = k as f64 * std::f64::consts::PI / 3.0;
                [10.0 + 5.0 * t.cos(), 20.0 + 5.0 * t.sin()]
            })
            .collect();
        let mut inputs = Vec::new();
        for s in scales {
            let d: Vec<[f64; 2]> = reference
                .iter()
                .map(|q| [s * (q[0] - 10.0) + 0.3, s * (q[1] - 20.0) - 0.2])
                .collect();
            inputs.extend(d.iter().map(|v| v[0] as f32));
            inputs.extend(d.iter().map(|v| v[1] as f32));
        }
        (reference, inputs)
    }

    #[test]
    fn spreads_recover_an_isotropic_scale_whatever_the_shift() {
        let (reference, inputs) = rows(&[0.05, -0.02, 0.0]);
        let s = spreads(&reference, &inputs, 3);
        for (got, want) in s.iter().zip([0.05, -0.02, 0.0]) {
            assert!((got - want).abs() < 1e-6, "{got} vs {want}");
        }
    }

    #[test]
    fn a_reference_that_frames_contract_against_is_called_pressed() {
        let undeformed: Vec<f64> = (0..50).map(|k| 0.01 + 0.001 * k as f64).collect();
        let (reference, inputs) = rows(&undeformed);
        let path = Path::new("init_0.png");
        assert!(pressed_reference(path, &reference, &inputs, 50).is_none());
        let mut pressed = undeformed.clone();
        pressed[..10].iter_mut().for_each(|s| *s = -0.01);
        let (reference, inputs) = rows(&pressed);
        let w = pressed_reference(path, &reference, &inputs, 50).expect("pressed");
        assert!(
            w.contains("looks pressed") && w.contains("10 of the 50"),
            "{w}"
        );
        // Too few frames to judge.
        let (reference, inputs) = rows(&pressed[..5]);
        assert!(pressed_reference(path, &reference, &inputs, 5).is_none());
    }
}
