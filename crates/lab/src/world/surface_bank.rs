//! The real-frame world for surfaces (`follow --task surface_3d
//! --replay-data DATASET`): every tap of a simulated arm over a flat
//! surface is answered by the labelled real frame whose labels (depth,
//! rx, ry) are nearest the tool's true pose, as the 2D real-frame world
//! answers edge taps ([`super::ReplayBank`]). The frames come already
//! read: the rows of a dataset that `import` made from a real surface
//! collection (its pins read by the sensor file's reader, in the
//! dataset's reference order), so the loop sees exactly the
//! displacement vectors a model trained on another import of the same
//! collection (`import --like`) expects.
//!
//! The distance between labels is each component's difference divided by
//! its spread (standard deviation) over the bank, then the Euclidean norm:
//! 1 is one spread away. The true label and the bank's share one
//! convention by construction (the world looks up the tool's label in the
//! collection's columns and the model predicts those columns), so the
//! loop is consistent whatever the collection's sign conventions are.
use crate::error::{LabError, Result};
use tactrace_servo::component_of;
use tactrace_store::TapData;

/// The labelled rows that answer taps.
#[derive(Debug, Clone)]
pub struct SurfaceBank {
    /// Each row's displacement vector (x of every pin, then y; px).
    inputs: Vec<Vec<f32>>,
    /// Each row's (depth mm, rx deg, ry deg).
    labels: Vec<[f64; 3]>,
    /// The image name of each row (empty when the dataset has none).
    images: Vec<String>,
    /// Each component's spread over the bank.
    scales: [f64; 3],
    reference_pins: Vec<[f64; 2]>,
    /// How many rows the model following in this world was trained on
    /// (None: not known).
    rows_seen_in_training: Option<usize>,
}

/// One tap's answer.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceAnswer {
    /// The row that answered.
    pub row: usize,
    /// Its scaled label distance from the tool's true label.
    pub distance: f64,
}

impl SurfaceBank {
    /// The bank of `labels` (depth, rx, ry) and their displacement vectors
    /// against `reference_pins`; refused when empty, of unequal lengths,
    /// not finite or without spread in a component.
    pub fn new(
        labels: Vec<[f64; 3]>,
        inputs: Vec<Vec<f32>>,
        images: Vec<String>,
        reference_pins: Vec<[f64; 2]>,
    ) -> Result<Self> {
        let n = labels.len();
        let width = 2 * reference_pins.len();
        if n < 2 || inputs.len() != n || inputs.iter().any(|r| r.len() != width) {
            return Err(LabError::Config(format!(
                "a surface bank needs at least 2 rows, each with {width} displacements \
                 ({} labels, {} input rows)",
                n,
                inputs.len()
            )));
        }
        let mut scales = [0.0; 3];
        for (k, scale) in scales.iter_mut().enumerate() {
            let mean = labels.iter().map(|l| l[k]).sum::<f64>() / n as f64;
            let var = labels.iter().map(|l| (l[k] - mean).powi(2)).sum::<f64>() / n as f64;
            *scale = var.sqrt();
            if !(scale.is_finite() && *scale > 0.0) {
                return Err(LabError::Config(format!(
                    "the bank's {} labels do not vary (or are not numbers)",
                    ["depth", "rx", "ry"][k]
                )));
            }
        }
        Ok(Self {
            inputs,
            labels,
            images,
            scales,
            reference_pins,
            rows_seen_in_training: None,
        })
    }

    /// The same bank, knowing that `seen` of its rows were in the
    /// training data of the model that follows in it (a figure over such
    /// a bank is not a held-out one; the run says so).
    pub fn with_rows_seen_in_training(mut self, seen: Option<usize>) -> Self {
        self.rows_seen_in_training = seen;
        self
    }

    /// How many rows the following model was trained on, if known.
    pub fn rows_seen_in_training(&self) -> Option<usize> {
        self.rows_seen_in_training
    }

    /// The bank of an imported dataset whose three targets name the
    /// depth, rx and ry (`z`, `rx`, `ry` or the Bristol `pose_3`,
    /// `pose_4`, `pose_5`), in any order.
    pub fn from_dataset(data: &TapData) -> Result<Self> {
        let targets = data.meta.model_targets().map_err(LabError::Config)?;
        let order: Vec<Option<usize>> = targets.iter().map(|t| component_of(&t.name)).collect();
        let column = |component: usize| order.iter().position(|c| *c == Some(component));
        let (Some(z), Some(rx), Some(ry)) = (column(2), column(3), column(4)) else {
            return Err(LabError::Config(
                "the bank's dataset must have the targets depth (z or pose_3), rx (pose_4) \
                 and ry (pose_5)"
                    .into(),
            ));
        };
        let t = targets.len();
        let width = 2 * data.meta.pins;
        let rows = data.targets.len() / t.max(1);
        let labels = (0..rows)
            .map(|i| {
                let r = &data.targets[i * t..(i + 1) * t];
                [r[z] as f64, r[rx] as f64, r[ry] as f64]
            })
            .collect();
        let inputs = data
            .inputs
            .chunks(width.max(1))
            .map(<[f32]>::to_vec)
            .collect();
        Self::new(
            labels,
            inputs,
            data.meta.images.clone(),
            data.meta.reference_pins.clone(),
        )
    }

    /// The rows' count.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// Never empty (checked when made).
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    /// The reference pins the displacement vectors are ordered by.
    pub fn reference_pins(&self) -> &[[f64; 2]] {
        &self.reference_pins
    }

    /// Row `row`'s displacement vector.
    pub fn input(&self, row: usize) -> &[f32] {
        &self.inputs[row]
    }

    /// Row `row`'s labels (depth mm, rx deg, ry deg).
    pub fn label(&self, row: usize) -> [f64; 3] {
        self.labels[row]
    }

    /// Row `row`'s image name, or `row N` without one.
    pub fn image(&self, row: usize) -> String {
        self.images
            .get(row)
            .cloned()
            .unwrap_or_else(|| format!("row {row}"))
    }

    /// The scaled label distance of two labels.
    pub fn distance(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        (0..3)
            .map(|k| ((a[k] - b[k]) / self.scales[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// The row whose labels are nearest `label` (the first of equals).
    pub fn nearest(&self, label: [f64; 3]) -> SurfaceAnswer {
        let mut best = SurfaceAnswer {
            row: 0,
            distance: f64::INFINITY,
        };
        for (row, l) in self.labels.iter().enumerate() {
            let distance = self.distance(label, *l);
            if distance < best.distance {
                best = SurfaceAnswer { row, distance };
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A synthetic bank: each tap is answered by the row of the nearest
    /// scaled labels, and the answer's distance is that scaled distance.
    #[test]
    fn surface_bank_answers_with_the_nearest_labelled_row() {
        let labels = vec![
            [1.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [3.0, 10.0, 0.0],
            [3.0, 0.0, -10.0],
            [5.0, 0.0, 0.0],
        ];
        let inputs: Vec<Vec<f32>> = (0..5).map(|i| vec![i as f32; 4]).collect();
        let pins = vec![[0.0, 0.0], [1.0, 1.0]];
        let bank = SurfaceBank::new(labels, inputs, vec![], pins).unwrap();
        let a = bank.nearest([3.1, 1.0, -0.5]);
        assert_eq!(a.row, 1);
        let want = bank.distance([3.1, 1.0, -0.5], [3.0, 0.0, 0.0]);
        assert!((a.distance - want).abs() < 1e-12 && a.distance > 0.0);
        assert_eq!(bank.nearest([3.0, 8.0, 0.0]).row, 2);
        assert_eq!(bank.nearest([2.9, 0.0, -7.0]).row, 3);
        assert_eq!(bank.nearest([5.0, 0.0, 0.0]).distance, 0.0);
        assert_eq!(bank.input(4), &[4.0; 4]);
        assert_eq!(bank.image(2), "row 2");
        assert!(SurfaceBank::new(
            vec![[1.0, 0.0, 0.0]; 3],
            vec![vec![0.0; 4]; 3],
            vec![],
            vec![[0.0; 2]; 2]
        )
        .is_err());
    }
}
