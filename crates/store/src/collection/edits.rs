//! Changes to a collection as the CLI's flags and the Python package's
//! keyword arguments give them (text, `none` for no column), turned into
//! a checked collection in one place.
use super::{
    CollectionError, KeepRule, LabelledCollection, RowSelection, TapColumns, Target, TargetSpec,
};
use std::path::PathBuf;
use tactrace_vision::BlobParams;

/// What to change in a collection; each `None` keeps the collection's.
#[derive(Debug, Clone, Default)]
pub struct CollectionEdits {
    /// Another labels file.
    pub targets: Option<PathBuf>,
    /// Another undeformed reference frame.
    pub reference: Option<PathBuf>,
    /// The column naming each row's frame file.
    pub image_column: Option<String>,
    /// The edge position column, mm.
    pub r_column: Option<String>,
    /// The edge angle column, deg.
    pub theta_column: Option<String>,
    /// Every target as `COLUMN:UNIT[:circular]` (`--target`, repeatable),
    /// in order; empty keeps the collection's (or the r and theta columns
    /// above). Given with `r_column` or `theta_column`, refused.
    pub target_list: Vec<String>,
    /// The tap's vertical offset column; `none` or empty: no column.
    pub depth_column: Option<String>,
    /// The shear columns `x,y,rotation`; `none` or empty: no shear.
    pub shear_columns: Option<String>,
    /// Only the first N rows.
    pub limit: Option<usize>,
    /// Only the frames whose number N has `N%M==K`.
    pub keep: Option<String>,
    /// Another blob detector.
    pub blob: Option<BlobParams>,
}

impl LabelledCollection {
    /// This collection with `edits` made, checked as every collection is.
    pub fn edited(self, edits: &CollectionEdits) -> Result<Self, CollectionError> {
        let e = edits.clone();
        let mut c = self;
        if let Some(t) = e.targets {
            c = c.with_targets_file(t);
        }
        if let Some(r) = e.reference {
            c = c.with_reference_frame(r);
        }
        if !e.target_list.is_empty() {
            if e.r_column.is_some() || e.theta_column.is_some() {
                return Err(CollectionError::TargetsAndEdgeColumns);
            }
            let targets = e
                .target_list
                .iter()
                .map(|t| Target::parse(t))
                .collect::<Result<Vec<_>, _>>()?;
            let image = e.image_column.as_deref().unwrap_or(c.spec().image_column());
            let spec = TargetSpec::new(image, targets)?;
            c = c.with_spec(spec);
        } else if e.image_column.is_some() || e.r_column.is_some() || e.theta_column.is_some() {
            let [r, theta] = c.spec().edge_columns()?;
            let spec = TargetSpec::edge(
                e.image_column.as_deref().unwrap_or(c.spec().image_column()),
                e.r_column.as_deref().unwrap_or(r),
                e.theta_column.as_deref().unwrap_or(theta),
            )?;
            c = c.with_spec(spec);
        }
        let mut tap = c.tap().clone();
        if let Some(depth) = e.depth_column {
            tap.depth = TapColumns::optional(&depth);
        }
        if let Some(shear) = e.shear_columns {
            tap.shear = TapColumns::shear_list(&shear)?;
        }
        let keep = e.keep.as_deref().map(KeepRule::parse).transpose()?;
        let rows = RowSelection {
            limit: e.limit.or(c.rows().limit),
            keep: keep.or(c.rows().keep),
        };
        c = c.with_tap(tap).with_rows(rows);
        match e.blob {
            Some(blob) => c.with_blob(blob),
            None => Ok(c),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn edits_as_flags_give_them_make_a_checked_collection() {
        let base = LabelledCollection::bristol(Path::new("set"));
        let c = base
            .clone()
            .edited(&CollectionEdits {
                targets: Some("part.csv".into()),
                r_column: Some("r".into()),
                depth_column: Some("none".into()),
                shear_columns: Some("a,b,c".into()),
                keep: Some("N%5==0".into()),
                ..CollectionEdits::default()
            })
            .unwrap();
        assert_eq!(c.targets(), Path::new("part.csv"));
        assert_eq!(c.frames(), base.frames());
        assert_eq!(c.spec().edge_columns().unwrap(), ["r", "pose_6"]);
        assert_eq!(c.tap().depth, None);
        assert_eq!(c.tap().shear, Some(["a", "b", "c"].map(String::from)));
        assert_eq!(c.rows().keep, KeepRule::new(5, 0));
        assert_eq!(
            base.clone().edited(&CollectionEdits::default()).unwrap(),
            base
        );
        let twice = CollectionEdits {
            theta_column: Some("pose_2".into()),
            ..CollectionEdits::default()
        };
        assert!(base.clone().edited(&twice).is_err());
        let bad_keep = CollectionEdits {
            keep: Some("N%5".into()),
            ..CollectionEdits::default()
        };
        assert!(base.edited(&bad_keep).is_err());
    }
}
