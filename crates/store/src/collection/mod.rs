//! A labelled collection of real TacTip frames: where its frames are, the
//! detector settings that read them, its reference, which columns of its
//! labels file are the targets ([`TargetSpec`]: unit, circular or not, and
//! the image-name column) and the tap's conditions ([`TapColumns`]), and
//! which rows it takes ([`RowSelection`]). The one description of a real
//! collection for every command that reads one (`import`, `twin`,
//! `calibrate`, `sim-fit`, `follow --replay`, `reproduce --real`, the
//! Python package), with the one reader of its labels file
//! ([`LabelledCollection::read_rows`]).
//!
//! A collection is checked when it is made (parameters -> checked
//! parameters, as linfa's `param_guard`): its constructors and its file
//! form refuse a target spec without targets or naming a column twice, a
//! keep rule that divides by zero and blob parameters OpenCV would refuse,
//! so a collection in hand is one that can be read. The Bristol layout's
//! names are in [`bristol`], used by [`LabelledCollection::bristol`] and
//! as the CLI's defaults.
mod columns;
mod edits;
mod rows;
mod select;
mod targets;

pub use edits::CollectionEdits;
pub use rows::{LabelledRow, TapFields};
pub use select::{frame_number, KeepRule, RowSelection};
pub use targets::{Target, TargetSpec, Unit};

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_vision::{BlobParams, SightParams};

/// The layout of the Bristol tactile robotics group's collections (the
/// shared 2D edge set): its files and label columns. The defaults of every
/// command that reads a real collection.
pub mod bristol {
    /// The frames folder, in the collection's folder.
    pub const FRAMES: &str = "frames";
    /// The labels file, in the collection's folder.
    pub const TARGETS: &str = "targets.csv";
    /// The undeformed frame, in the collection's folder.
    pub const REFERENCE: &str = "frames/init_0.png";
    /// The column naming each row's frame file.
    pub const IMAGE_COLUMN: &str = "image_name";
    /// The edge position r, mm.
    pub const R_COLUMN: &str = "pose_2";
    /// The edge angle theta, deg.
    pub const THETA_COLUMN: &str = "pose_6";
    /// The tap's vertical offset, mm.
    pub const DEPTH_COLUMN: &str = "pose_3";
    /// The tap's shear: x and y (mm, work frame), rotation (deg).
    pub const SHEAR_COLUMNS: [&str; 3] = ["move_1", "move_2", "move_6"];
    /// The blob preset for its binarised 256 x 256 frames.
    pub const BLOB_PRESET: &str = "real256";
}

/// Why a collection's description cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CollectionError {
    /// A target spec without a target.
    #[error("the target spec names no target column: give at least one")]
    NoTargets,
    /// A label column named by an empty string.
    #[error("a label column's name is empty")]
    EmptyColumn,
    /// One column named for two labels.
    #[error("the column `{column}` is named for two labels: each needs its own column")]
    ColumnTwice { column: String },
    /// A spec that is not the edge task's two targets where an edge is
    /// replayed or simulated (twin, calibrate, the real-frame world).
    #[error(
        "the targets are {targets}: this command replays or simulates an edge task's two \
         targets, an edge position (mm) then an angle (deg)"
    )]
    NotAnEdgeTask { targets: String },
    /// A `--target` that is not `COLUMN:UNIT[:circular][:ROLE]`.
    #[error(
        "the target `{text}`: expected COLUMN:UNIT[:circular][:ROLE] with unit mm or deg and \
         role position or angle (e.g. pose_6:deg:circular, pose_2:mm:position)"
    )]
    TargetText { text: String },
    /// `--target` given with `--r-column` / `--theta-column`.
    #[error(
        "--target names every target: give the position and angle columns as --target \
         COLUMN:mm --target COLUMN:deg, not with --r-column/--theta-column"
    )]
    TargetsAndEdgeColumns,
    /// Roles marked on targets of the wrong unit, or one role twice.
    #[error("{reason}: mark one target `position` (mm) and one `angle` (deg), at most")]
    Roles { reason: String },
    /// A circular target not in degrees.
    #[error("the target `{column}` is circular but not in degrees: only an angle wraps")]
    CircularNotDegrees { column: String },
    /// A row rule that is not `N%M==K` with `0 <= K < M`.
    #[error(
        "the row rule `{text}` (--replay-keep): expected `N%M==K` with 0 <= K < M (frame \
         number N, e.g. N%5==0)"
    )]
    KeepRule { text: String },
    /// Shear columns not three (x, y, rotation).
    #[error("--shear-columns wants three columns (x, y, rotation) or `none`, got {got}")]
    ShearColumns { got: usize },
    /// Blob parameters the detector refuses.
    #[error("the collection's blob parameters")]
    Blob(#[source] tactrace_vision::VisionError),
    /// A command that needs an undeformed frame, given a collection whose
    /// rest layout is estimated from taps.
    #[error(
        "this command needs the sensor's undeformed frame (--reference): the rest layout \
         estimated from taps is used by import, predict and follow only"
    )]
    NoReferenceFrame,
}

/// What every pin displacement is measured from: the rest layout, which
/// also defines the pin order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Reference {
    /// An undeformed frame (taken without contact), by its file.
    Frame(PathBuf),
    /// No undeformed frame: the rest layout is to be estimated from the
    /// taps themselves when the collection is read (`import` without
    /// `--reference`), looking for `pins` pins (the sensor file's count;
    /// `None`: the count most frames show).
    Estimate {
        /// The sensor's pin count.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        pins: Option<usize>,
    },
    /// A rest layout estimated from the taps (what [`Reference::Estimate`]
    /// becomes once done, recorded in the dataset so another split or a
    /// model reads the same pins).
    Estimated(EstimatedRest),
}

/// A rest layout estimated from taps, and how well the taps agree with it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatedRest {
    /// The pins, px in the preprocessed frame, in the order every dataset
    /// made from it uses.
    pub pins: Vec<[f64; 2]>,
    /// RMS distance of the least pressed taps' pins to the layout, px.
    pub residual_px: f64,
    /// Taps it was estimated from.
    pub frames: usize,
}

impl Reference {
    /// The undeformed frame's file, when the reference is one.
    pub fn frame(&self) -> Option<&Path> {
        match self {
            Reference::Frame(p) => Some(p),
            Reference::Estimate { .. } | Reference::Estimated(_) => None,
        }
    }

    /// The undeformed frame's file; an error for commands that need one
    /// when the rest layout is (to be) estimated from taps.
    pub fn path(&self) -> Result<&Path, CollectionError> {
        self.frame().ok_or(CollectionError::NoReferenceFrame)
    }
}

/// The columns of a tap's conditions besides its targets (the twin
/// replays them; the real-frame world matches on the depth).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TapColumns {
    /// The tap's vertical offset, mm (`None`: every tap at the nominal depth).
    pub depth: Option<String>,
    /// Shear x and y (mm, work frame) and rotation (deg) (`None`: taps
    /// without shear).
    pub shear: Option<[String; 3]>,
}

impl TapColumns {
    /// The Bristol layout's: depth `pose_3`, shear `move_1`, `move_2`, `move_6`.
    pub fn bristol() -> Self {
        Self {
            depth: Some(bristol::DEPTH_COLUMN.into()),
            shear: Some(bristol::SHEAR_COLUMNS.map(String::from)),
        }
    }

    /// The depth column from a name, `none` (any case) or empty meaning none.
    pub fn optional(name: &str) -> Option<String> {
        let name = name.trim();
        (!name.is_empty() && !name.eq_ignore_ascii_case("none")).then(|| name.to_string())
    }

    /// The shear columns from `x,y,rotation`, `none` or empty meaning none.
    pub fn shear_list(list: &str) -> Result<Option<[String; 3]>, CollectionError> {
        let Some(list) = Self::optional(list) else {
            return Ok(None);
        };
        let cols: Vec<String> = list.split(',').map(|c| c.trim().to_string()).collect();
        let got = cols.len();
        <[String; 3]>::try_from(cols)
            .map(Some)
            .map_err(|_| CollectionError::ShearColumns { got })
    }
}

/// A labelled collection of real frames (module docs); checked when made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CollectionFile", into = "CollectionFile")]
pub struct LabelledCollection {
    frames: PathBuf,
    targets: PathBuf,
    reference: Reference,
    spec: TargetSpec,
    tap: TapColumns,
    rows: RowSelection,
    blob: BlobParams,
    sight: Option<SightParams>,
}

/// The file form of a [`LabelledCollection`], before its checks.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CollectionFile {
    frames: PathBuf,
    targets: PathBuf,
    reference: Reference,
    #[serde(default)]
    tap: TapColumns,
    #[serde(default)]
    rows: RowSelection,
    spec: TargetSpec,
    blob: BlobParams,
    /// The sensor file's preprocessing and detector (they replace `blob`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sight: Option<SightParams>,
}

impl TryFrom<CollectionFile> for LabelledCollection {
    type Error = CollectionError;

    fn try_from(f: CollectionFile) -> Result<Self, Self::Error> {
        f.blob.validate().map_err(CollectionError::Blob)?;
        Ok(Self {
            frames: f.frames,
            targets: f.targets,
            reference: f.reference,
            spec: f.spec,
            tap: f.tap,
            rows: f.rows,
            blob: f.blob,
            sight: f.sight,
        })
    }
}

impl From<LabelledCollection> for CollectionFile {
    fn from(c: LabelledCollection) -> Self {
        CollectionFile {
            frames: c.frames,
            targets: c.targets,
            reference: c.reference,
            tap: c.tap,
            rows: c.rows,
            spec: c.spec,
            blob: c.blob,
            sight: c.sight,
        }
    }
}

impl LabelledCollection {
    /// The frames in `frames`, labelled by the CSV `targets`, displaced
    /// from the undeformed frame `reference`, read in the Bristol layout's
    /// columns ([`bristol`]: r, theta, depth, shear) with its blob preset,
    /// every row: the one place those defaults are set.
    pub fn new(frames: PathBuf, targets: PathBuf, reference: PathBuf) -> Self {
        let spec = TargetSpec::edge(
            bristol::IMAGE_COLUMN,
            bristol::R_COLUMN,
            bristol::THETA_COLUMN,
        )
        .expect("distinct built-in columns");
        Self {
            frames,
            targets,
            reference: Reference::Frame(reference),
            spec,
            tap: TapColumns::bristol(),
            rows: RowSelection::default(),
            blob: BlobParams::preset(bristol::BLOB_PRESET).expect("built-in preset"),
            sight: None,
        }
    }

    /// The collection in the folder `dir`, in the Bristol layout
    /// (`frames/`, `targets.csv`, `frames/init_0.png`).
    pub fn bristol(dir: &Path) -> Self {
        Self::new(
            dir.join(bristol::FRAMES),
            dir.join(bristol::TARGETS),
            dir.join(bristol::REFERENCE),
        )
    }

    /// The folder of the frames its labels name.
    pub fn frames(&self) -> &Path {
        &self.frames
    }

    /// The labels file (CSV, one row per frame).
    pub fn targets(&self) -> &Path {
        &self.targets
    }

    /// The reference the displacements are measured from.
    pub fn reference(&self) -> &Reference {
        &self.reference
    }

    /// The label columns: image name and targets.
    pub fn spec(&self) -> &TargetSpec {
        &self.spec
    }

    /// The tap's condition columns.
    pub fn tap(&self) -> &TapColumns {
        &self.tap
    }

    /// The rows it takes.
    pub fn rows(&self) -> &RowSelection {
        &self.rows
    }

    /// The blob detector that finds the frames' pins.
    pub fn blob(&self) -> &BlobParams {
        &self.blob
    }

    /// The preprocessing and detector of a sensor file, when one was given
    /// (they replace [`LabelledCollection::blob`]).
    pub fn sight(&self) -> Option<&SightParams> {
        self.sight.as_ref()
    }

    /// The sensor file's preprocessing and detector (checked against the
    /// frames when they are read).
    pub fn with_sight(self, sight: Option<SightParams>) -> Self {
        Self { sight, ..self }
    }

    /// Another reference (an undeformed frame, or a rest layout estimated
    /// from the taps).
    pub fn with_reference(self, reference: Reference) -> Self {
        Self { reference, ..self }
    }

    /// Another frames folder.
    pub fn with_frames(self, frames: PathBuf) -> Self {
        Self { frames, ..self }
    }

    /// Another labels file (the same columns).
    pub fn with_targets_file(self, targets: PathBuf) -> Self {
        Self { targets, ..self }
    }

    /// Another undeformed reference frame.
    pub fn with_reference_frame(self, reference: PathBuf) -> Self {
        Self {
            reference: Reference::Frame(reference),
            ..self
        }
    }

    /// Other label columns.
    pub fn with_spec(self, spec: TargetSpec) -> Self {
        Self { spec, ..self }
    }

    /// Other tap columns.
    pub fn with_tap(self, tap: TapColumns) -> Self {
        Self { tap, ..self }
    }

    /// Another row selection.
    pub fn with_rows(self, rows: RowSelection) -> Self {
        Self { rows, ..self }
    }

    /// Another blob detector, refused when OpenCV would refuse it.
    pub fn with_blob(self, blob: BlobParams) -> Result<Self, CollectionError> {
        blob.validate().map_err(CollectionError::Blob)?;
        Ok(Self { blob, ..self })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bristol_defaults_are_set_in_one_constructor() {
        let c = LabelledCollection::bristol(Path::new("set"));
        assert_eq!(c.frames(), Path::new("set/frames"));
        assert_eq!(c.targets(), Path::new("set/targets.csv"));
        assert_eq!(
            c.reference().path().unwrap(),
            Path::new("set/frames/init_0.png")
        );
        assert_eq!(c.spec().image_column(), "image_name");
        assert_eq!(c.spec().edge_columns().unwrap(), ["pose_2", "pose_6"]);
        let units: Vec<Unit> = c.spec().targets().iter().map(|t| t.unit).collect();
        assert_eq!(units, [Unit::Mm, Unit::Deg]);
        assert!(c.spec().targets().iter().all(|t| !t.circular));
        assert_eq!(c.tap().depth.as_deref(), Some("pose_3"));
        assert_eq!(
            c.tap().shear,
            Some(["move_1", "move_2", "move_6"].map(String::from))
        );
        assert_eq!(c.rows(), &RowSelection::default());
        assert_eq!(c.blob(), &BlobParams::preset("real256").unwrap());
    }

    #[test]
    fn a_collection_round_trips_through_its_file_form_and_is_checked() {
        let mut angle = Target::new("pose_6", Unit::Deg);
        angle.circular = true;
        let spec = TargetSpec::new("image", vec![Target::new("pose_2", Unit::Mm), angle]).unwrap();
        let c = LabelledCollection::bristol(Path::new("set"))
            .with_spec(spec)
            .with_tap(TapColumns {
                depth: None,
                shear: None,
            })
            .with_rows(RowSelection {
                limit: Some(40),
                keep: KeepRule::new(5, 0),
            });
        let text = toml::to_string(&c).unwrap();
        assert!(text.contains("remainder = 0"), "{text}");
        let back: LabelledCollection = toml::from_str(&text).unwrap();
        assert_eq!(back, c);
        let json = serde_json::to_string(&c).unwrap();
        assert_eq!(
            serde_json::from_str::<LabelledCollection>(&json).unwrap(),
            c
        );
        // An unknown key, a spec naming a column twice, a bad blob range:
        // refused as the file is read.
        let unknown = text.replacen("frames =", "frame_dir = \"x\"\nframes =", 1);
        assert!(toml::from_str::<LabelledCollection>(&unknown).is_err());
        let twice = text.replace("column = \"pose_6\"", "column = \"pose_2\"");
        let err = toml::from_str::<LabelledCollection>(&twice).unwrap_err();
        assert!(err.to_string().contains("`pose_2`"), "{err}");
        let mut blob = BlobParams::preset("real256").unwrap();
        blob.min_area = 100.0;
        blob.max_area = 10.0;
        assert!(c.clone().with_blob(blob).is_err());
    }

    #[test]
    fn tap_columns_read_none_and_three_shear_columns() {
        assert_eq!(TapColumns::optional(" None "), None);
        assert_eq!(TapColumns::optional("pose_3").as_deref(), Some("pose_3"));
        assert_eq!(TapColumns::shear_list("none").unwrap(), None);
        assert!(TapColumns::shear_list("a,b").is_err());
        assert_eq!(
            TapColumns::shear_list("a, b,c").unwrap(),
            Some(["a", "b", "c"].map(String::from))
        );
    }
}
