//! The one reader of a collection's labels file (`targets.csv`): columns
//! found by name ([`super::columns`]), numbers checked, rows selected
//! ([`super::RowSelection`]); and the same file cut to some of its frames.
use super::columns::column_indices;
use super::LabelledCollection;
use crate::error::{Result, StoreError};
use std::path::Path;

/// Which of the tap's columns ([`super::TapColumns`]) to read besides the
/// image name and the targets (a column not named by the collection is
/// never read).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TapFields {
    pub depth: bool,
    pub shear: bool,
}

impl TapFields {
    /// The image name and the targets only.
    pub const NONE: Self = Self {
        depth: false,
        shear: false,
    };
    /// With the tap's vertical offset.
    pub const DEPTH: Self = Self {
        depth: true,
        shear: false,
    };
    /// With the vertical offset and the shear.
    pub const ALL: Self = Self {
        depth: true,
        shear: true,
    };
}

/// One labelled row of the labels file.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelledRow {
    /// Index among the file's data rows (0 = the first after the header).
    pub index: usize,
    /// The frame's file name in the frames folder.
    pub image: String,
    /// The targets, in the spec's order (mm, deg).
    pub targets: Vec<f32>,
    /// The tap's vertical offset, mm, when read.
    pub depth_mm: Option<f32>,
    /// The tap's shear x, y (mm) and rotation (deg), when read.
    pub shear: Option<[f32; 3]>,
}

impl LabelledCollection {
    /// The rows of the labels file this collection takes (its
    /// [`super::RowSelection`]), with the tap columns asked for in
    /// `fields`: every number finite, at least one row.
    pub fn read_rows(&self, fields: TapFields) -> Result<Vec<LabelledRow>> {
        let path = self.targets();
        let fmt = |reason: String| StoreError::Format {
            path: path.to_path_buf(),
            reason,
        };
        // A regular file only: a FIFO would block the reader for ever.
        let (file, _) = crate::open_regular(path)?;
        let mut rdr = csv::Reader::from_reader(std::io::BufReader::new(file));
        let headers = rdr.headers().map_err(|e| fmt(e.to_string()))?.clone();
        let spec = self.spec();
        let tap = self.tap();
        let depth = tap.depth.as_deref().filter(|_| fields.depth);
        let shear = tap.shear.as_ref().filter(|_| fields.shear);
        let names: Vec<&str> = std::iter::once(spec.image_column())
            .chain(spec.targets().iter().map(|t| t.column.as_str()))
            .chain(depth)
            .chain(shear.iter().flat_map(|s| s.iter().map(String::as_str)))
            .collect();
        let at = column_indices(&headers, &names).map_err(fmt)?;
        let n_targets = spec.targets().len();
        let (image_at, rest) = at.split_first().expect("the image column");
        let (target_at, rest) = rest.split_at(n_targets);
        let (depth_at, shear_at) = rest.split_at(usize::from(depth.is_some()));
        let selection = self.rows();
        let mut rows = Vec::new();
        let mut read = 0;
        for (k, rec) in rdr.records().enumerate() {
            read += 1;
            let rec = rec.map_err(|e| fmt(e.to_string()))?;
            let num = |c: usize| -> Result<f32> {
                let cell = rec.get(c).unwrap_or("");
                let v: f32 = cell
                    .trim()
                    .parse()
                    .map_err(|_| fmt(format!("row {}: `{cell}` is not a number", k + 2)))?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(fmt(format!("row {}: non-finite value", k + 2)))
                }
            };
            let image = rec.get(*image_at).unwrap_or("").trim().to_string();
            let targets = target_at.iter().map(|&c| num(c)).collect::<Result<_>>()?;
            let depth_mm = depth_at.first().map(|&c| num(c)).transpose()?;
            let shear = match shear_at {
                [x, y, rz] => Some([num(*x)?, num(*y)?, num(*rz)?]),
                _ => None,
            };
            if selection.keep.is_none_or(|rule| rule.keeps(&image)) {
                rows.push(LabelledRow {
                    index: k,
                    image,
                    targets,
                    depth_mm,
                    shear,
                });
            }
            if selection.limit.is_some_and(|l| read >= l) {
                break;
            }
        }
        if read == 0 {
            return Err(fmt("no data rows".into()));
        }
        if rows.is_empty() {
            let rule = selection.keep.map_or(String::new(), |k| k.to_string());
            return Err(fmt(format!(
                "no labelled row is kept by the rule {rule} (--replay-keep)"
            )));
        }
        Ok(rows)
    }

    /// The same collection with only the rows whose image is among
    /// `images`: their lines of the labels file (the header and every
    /// column kept) are written to `out`, which becomes its labels file.
    pub fn with_images(&self, images: &[String], out: &Path) -> Result<LabelledCollection> {
        let path = self.targets();
        let fmt = |reason: String| StoreError::Format {
            path: path.to_path_buf(),
            reason,
        };
        let keep: std::collections::HashSet<&str> = images.iter().map(String::as_str).collect();
        let (file, _) = crate::open_regular(path)?;
        let mut rdr = csv::Reader::from_reader(std::io::BufReader::new(file));
        let headers = rdr.headers().map_err(|e| fmt(e.to_string()))?.clone();
        let col = column_indices(&headers, &[self.spec().image_column()]).map_err(fmt)?[0];
        let mut w = crate::csv_text::CsvText::new();
        w.row(&headers);
        for rec in rdr.records() {
            let rec = rec.map_err(|e| fmt(e.to_string()))?;
            if rec.get(col).is_some_and(|v| keep.contains(v.trim())) {
                w.row(&rec);
            }
        }
        w.write(out)?;
        Ok(self.clone().with_targets_file(out.to_path_buf()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collection::{KeepRule, RowSelection, TapColumns};

    const CSV: &str = "image_name,pose_2,pose_3,pose_6,move_1,move_2,move_6\n\
                       frame_0_0.png,1,0.5,10,0.1,0.2,3\n\
                       frame_1_0.png,2,-0.5,20,0,0,0\n\
                       frame_5_0.png,3,0,30,1,2,-3\n";

    fn collection(dir: &Path, csv: &str) -> LabelledCollection {
        std::fs::write(dir.join("targets.csv"), csv).unwrap();
        LabelledCollection::bristol(dir)
    }

    #[test]
    fn one_reader_takes_targets_tap_columns_and_the_selected_rows() {
        let root = tempfile::tempdir().unwrap();
        let c = collection(root.path(), CSV);
        let rows = c.read_rows(TapFields::ALL).unwrap();
        assert_eq!(rows.len(), 3);
        assert_eq!(rows[0].image, "frame_0_0.png");
        assert_eq!(rows[0].targets, [1.0, 10.0]);
        assert_eq!(rows[0].depth_mm, Some(0.5));
        assert_eq!(rows[2].shear, Some([1.0, 2.0, -3.0]));
        let plain = c.read_rows(TapFields::NONE).unwrap();
        assert_eq!((plain[1].depth_mm, plain[1].shear), (None, None));
        assert_eq!(plain[1].targets, [2.0, 20.0]);
        let depth = c.read_rows(TapFields::DEPTH).unwrap();
        assert_eq!((depth[1].depth_mm, depth[1].shear), (Some(-0.5), None));
        // The first two rows; of all, the frames N%5==0 (indices kept).
        let first = c.clone().with_rows(RowSelection {
            limit: Some(2),
            keep: None,
        });
        assert_eq!(first.read_rows(TapFields::NONE).unwrap().len(), 2);
        let kept = c.clone().with_rows(RowSelection {
            limit: None,
            keep: KeepRule::new(5, 0),
        });
        let idx: Vec<usize> = kept
            .read_rows(TapFields::NONE)
            .unwrap()
            .iter()
            .map(|r| r.index)
            .collect();
        assert_eq!(idx, [0, 2]);
        let none_kept = c.clone().with_rows(RowSelection {
            limit: None,
            keep: KeepRule::new(5, 4),
        });
        let err = none_kept
            .read_rows(TapFields::NONE)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("no labelled row is kept by the rule N%5==4"),
            "{err}"
        );
    }

    #[test]
    fn the_reader_names_a_missing_tap_column_and_a_bad_number() {
        let root = tempfile::tempdir().unwrap();
        let c = collection(root.path(), "image_name,pose_2,pose_6\nf_0.png,1,x\n");
        let err = c.read_rows(TapFields::NONE).unwrap_err().to_string();
        assert!(err.contains("row 2: `x` is not a number"), "{err}");
        let c = collection(root.path(), "image_name,pose_2,pose_6\nf_0.png,1,2\n");
        assert!(c.read_rows(TapFields::NONE).is_ok());
        let err = c.read_rows(TapFields::DEPTH).unwrap_err().to_string();
        assert!(err.contains("no column `pose_3`"), "{err}");
        let no_tap = c.clone().with_tap(TapColumns::default());
        assert!(no_tap.read_rows(TapFields::ALL).is_ok());
        let c = collection(root.path(), "image_name,pose_2,pose_6\n");
        let err = c.read_rows(TapFields::NONE).unwrap_err().to_string();
        assert!(err.ends_with("no data rows"), "{err}");
    }

    #[test]
    fn a_collection_cut_to_some_images_keeps_their_lines_whole() {
        let root = tempfile::tempdir().unwrap();
        let c = collection(root.path(), CSV);
        let out = root.path().join("bank.csv");
        let part = c.with_images(&["frame_5_0.png".into()], &out).unwrap();
        assert_eq!(part.targets(), out);
        let text = std::fs::read_to_string(&out).unwrap();
        assert_eq!(
            text,
            "image_name,pose_2,pose_3,pose_6,move_1,move_2,move_6\nframe_5_0.png,3,0,30,1,2,-3\n"
        );
    }
}
