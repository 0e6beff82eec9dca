//! The real-frame world's bank (`follow --replay`): at each tap the tool's
//! true pose against the contour is turned into the labels of a real
//! labelled collection on a straight edge (its label convention,
//! [`tactrace_sensor::LabelConvention`]) and the tap is answered by the
//! collection's frame whose labels are nearest (the scaled label distance
//! of [`FrameBank`]: each label divided by its spread over the bank). The
//! loop sees only that frame, through the same detection, pin order,
//! model and controller as on a real rig; the model's predictions, in the
//! collection's labels, are mapped back into the controller's frame by the
//! same convention. After the run, `answers.csv` lists every tap's answer.
//!
//! What this world cannot show: the frames are of a straight edge, so the
//! sensor never feels curvature or a corner; a contour's bends reach the
//! loop only as changes of the edge pose between taps.
use crate::error::{LabError, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;
use tactrace_sensor::{Answer, EdgeLabels, FrameBank, LabelledFrame};
use tactrace_store::collection::{CollectionEdits, TapColumns};
use tactrace_store::{CsvText, LabelledCollection, StoreError, TapFields};

/// Which real collection answers the taps (the `[replay]` table of a
/// follow configuration): checked when made, so its collection holds an
/// edge task's two targets and `far_distance` is positive.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "BankFile", into = "BankFile")]
pub struct ReplayBank {
    far_distance: f64,
    collection: LabelledCollection,
}

/// The file form of a [`ReplayBank`], before its checks.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct BankFile {
    far_distance: f64,
    collection: LabelledCollection,
}

impl TryFrom<BankFile> for ReplayBank {
    type Error = LabError;

    fn try_from(f: BankFile) -> Result<Self> {
        ReplayBank::new(f.collection, f.far_distance)
    }
}

impl From<ReplayBank> for BankFile {
    fn from(b: ReplayBank) -> Self {
        BankFile {
            far_distance: b.far_distance,
            collection: b.collection,
        }
    }
}

impl ReplayBank {
    /// The label distance beyond which an answer counts as uncovered.
    pub const FAR_DISTANCE: f64 = 0.5;

    /// The frames of `collection` answer the taps; a tap answered by a
    /// frame further than `far_distance` (scaled label distance) counts as
    /// uncovered, and the run says so.
    pub fn new(collection: LabelledCollection, far_distance: f64) -> Result<Self> {
        if !(far_distance.is_finite() && far_distance > 0.0) {
            return Err(LabError::Config("far_distance must be positive".into()));
        }
        collection.spec().edge_columns().map_err(StoreError::from)?;
        Ok(Self {
            far_distance,
            collection,
        })
    }

    /// The labelled collection in `dir` in the Bristol layout (frames/,
    /// targets.csv, frames/init_0.png; r, theta and the depth of
    /// [`tactrace_store::collection::bristol`]) with `edits` (the CLI's
    /// `--replay-*` flags, Python's `replay` dict); refused when `dir` has
    /// no frames folder or labels.
    pub fn from_dir(dir: &Path, edits: &CollectionEdits) -> Result<Self> {
        let bristol = LabelledCollection::bristol(dir);
        let depth_only = TapColumns {
            shear: None,
            ..bristol.tap().clone()
        };
        let collection = bristol
            .with_tap(depth_only)
            .edited(edits)
            .map_err(StoreError::from)?;
        let (frames, labels) = (collection.frames(), collection.targets());
        if !frames.is_dir() || !labels.is_file() {
            return Err(LabError::Config(format!(
                "--replay {}: not a labelled collection: it needs frames/ and targets.csv \
                 (or --targets); found frames/: {}, labels: {}",
                dir.display(),
                frames.is_dir(),
                labels.is_file()
            )));
        }
        Self::new(collection, Self::FAR_DISTANCE)
    }

    /// The collection whose frames answer.
    pub fn collection(&self) -> &LabelledCollection {
        &self.collection
    }

    /// The label distance beyond which an answer counts as uncovered.
    pub fn far_distance(&self) -> f64 {
        self.far_distance
    }

    /// The same bank answering from another collection (checked again).
    pub fn with_collection(self, collection: LabelledCollection) -> Result<Self> {
        Self::new(collection, self.far_distance)
    }
}

/// The bank's frames: the collection's rows with their labels (r, theta
/// and, when it names one, the depth); every frame file must exist.
pub fn load_bank(bank: &ReplayBank) -> Result<FrameBank> {
    let c = bank.collection();
    let rows = c.read_rows(TapFields::DEPTH)?;
    let frames: Vec<LabelledFrame> = rows
        .iter()
        .map(|r| LabelledFrame {
            path: c.frames().join(&r.image),
            labels: EdgeLabels {
                r_mm: f64::from(r.targets[0]),
                theta_deg: f64::from(r.targets[1]),
                dz_mm: r.depth_mm.map_or(0.0, f64::from),
            },
        })
        .collect();
    let missing: Vec<&LabelledFrame> = frames.iter().filter(|f| !f.path.is_file()).collect();
    if let Some(first) = missing.first() {
        return Err(LabError::Format {
            path: c.frames().to_path_buf(),
            reason: format!(
                "{} of the {} labelled frames are missing, e.g. {}: give the folder of the \
                 frames the labels name (--replay DIR holds frames/ and targets.csv)",
                missing.len(),
                frames.len(),
                first.path.display()
            ),
        });
    }
    FrameBank::new(frames, c.tap().depth.is_some()).map_err(|e| LabError::Format {
        path: c.targets().to_path_buf(),
        reason: e.to_string(),
    })
}

/// `answers.csv`: every tap's labels (of the pose reached), the frame that
/// answered, its labels and the label distance.
pub(crate) fn write_answers(path: &Path, answers: &[Answer], bank: &FrameBank) -> Result<()> {
    let mut csv = CsvText::new();
    csv.row([
        "step",
        "r_label_mm",
        "theta_label_deg",
        "dz_label_mm",
        "frame",
        "frame_r_mm",
        "frame_theta_deg",
        "frame_dz_mm",
        "distance",
    ]);
    for (step, a) in answers.iter().enumerate() {
        let f = &bank.frames()[a.frame];
        let (w, g) = (a.wanted, f.labels);
        csv.row([
            step.to_string(),
            format!("{:.4}", w.r_mm),
            format!("{:.3}", w.theta_deg),
            format!("{:.4}", w.dz_mm),
            image_name(&f.path),
            format!("{:.4}", g.r_mm),
            format!("{:.3}", g.theta_deg),
            format!("{:.4}", g.dz_mm),
            format!("{:.4}", a.distance),
        ]);
    }
    Ok(csv.write(path)?)
}

/// The distinct frames that answered, in order of first use, for the
/// run's replay page.
pub(crate) struct Answered {
    /// Their files (PNG bytes).
    pub images: Vec<Vec<u8>>,
    /// Their image names.
    pub names: Vec<String>,
    /// Each tap's index among them.
    pub per_step: Vec<usize>,
    /// Each tap's label distance.
    pub distances: Vec<f64>,
}

pub(crate) fn answered_frames(answers: &[Answer], bank: &FrameBank) -> Result<Answered> {
    let mut slot = std::collections::HashMap::new();
    let mut out = Answered {
        images: Vec::new(),
        names: Vec::new(),
        per_step: Vec::with_capacity(answers.len()),
        distances: answers.iter().map(|a| a.distance).collect(),
    };
    for a in answers {
        let next = slot.len();
        let k = *slot.entry(a.frame).or_insert(next);
        if k == out.images.len() {
            let path = &bank.frames()[a.frame].path;
            out.images
                .push(std::fs::read(path).map_err(tactrace_store::read_err(path))?);
            out.names.push(image_name(path));
        }
        out.per_step.push(k);
    }
    Ok(out)
}

/// A frame's image name: its file name in the collection.
fn image_name(path: &Path) -> String {
    path.file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bank_round_trips_and_is_checked_when_read() {
        let c = LabelledCollection::bristol(Path::new("set"));
        let bank = ReplayBank::new(c.clone(), 0.5).unwrap();
        let text = toml::to_string(&bank).unwrap();
        assert_eq!(toml::from_str::<ReplayBank>(&text).unwrap(), bank);
        let far = text.replace("far_distance = 0.5", "far_distance = -1.0");
        assert!(toml::from_str::<ReplayBank>(&far).is_err(), "{far}");
        assert!(ReplayBank::new(c, f64::NAN).is_err());
    }

    #[test]
    fn answers_csv_has_a_header_and_a_whole_line_a_tap() {
        let labels = |r: f64, t: f64| EdgeLabels {
            r_mm: r,
            theta_deg: t,
            dz_mm: 0.0,
        };
        let frame = |name: &str, l| LabelledFrame {
            path: Path::new("frames").join(name),
            labels: l,
        };
        let frames = vec![
            frame("frame_1_0.png", labels(1.0, 10.0)),
            frame("frame_2_0.png", labels(-1.0, 0.0)),
        ];
        let bank = FrameBank::new(frames, false).unwrap();
        let answers = [Answer {
            wanted: labels(0.5, 12.25),
            frame: 0,
            distance: 0.125,
        }];
        let root = tempfile::tempdir().unwrap();
        let path = root.path().join("answers.csv");
        write_answers(&path, &answers, &bank).unwrap();
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            "step,r_label_mm,theta_label_deg,dz_label_mm,frame,frame_r_mm,frame_theta_deg,\
             frame_dz_mm,distance\n0,0.5000,12.250,0.0000,frame_1_0.png,1.0000,10.000,0.0000,0.1250\n"
        );
    }
}
