//! What `import` is asked, as the CLI's flags and the Python package's
//! `import_dataset` give it, turned into the collection it reads: one
//! place, so both read frames the same way. The reference is an
//! undeformed frame, a dataset's recorded rest pins (and sensor settings),
//! or estimated from the taps; `like` takes everything from a dataset
//! imported before ([`crate::import_like`]).
use crate::error::Result;
use crate::import::recorded_reference;
use crate::import_like::{check_like, like_collection};
use std::path::PathBuf;
use tactrace_store::collection::{CollectionEdits, Reference};
use tactrace_store::{read_dataset, LabelledCollection, SightFile, TapData};

/// An import's inputs.
#[derive(Debug, Clone, Default)]
pub struct ImportRequest {
    /// The frames folder.
    pub frames: PathBuf,
    /// The labels CSV.
    pub targets: PathBuf,
    /// An undeformed frame, or a dataset folder (its rest pins and, with
    /// no `sensor`, its sensor settings); `None`: estimated from the taps.
    pub reference: Option<PathBuf>,
    /// A sensor file (`tactrace sensor inspect`).
    pub sensor: Option<PathBuf>,
    /// Another split of the collection this dataset was imported from
    /// (its reference, detector and targets); excludes the rest but
    /// `limit`.
    pub like: Option<PathBuf>,
    /// Label columns, targets, blob detector and `limit`; import reads
    /// no tap columns.
    pub edits: CollectionEdits,
}

/// The collection to import, and the dataset of `like` when given.
pub struct ImportPlan {
    /// What is read.
    pub collection: LabelledCollection,
    /// The `like` dataset, which the result must match
    /// ([`ImportPlan::check`]).
    pub like: Option<(TapData, PathBuf)>,
}

impl ImportRequest {
    /// The collection this request reads, checked.
    pub fn plan(&self) -> Result<ImportPlan> {
        if let Some(dir) = &self.like {
            let like = read_dataset(dir)?;
            let c = like_collection(&like, dir, self.frames.clone(), self.targets.clone())?;
            let c = c.edited(&CollectionEdits {
                limit: self.edits.limit,
                ..CollectionEdits::default()
            });
            return Ok(ImportPlan {
                collection: c.map_err(tactrace_store::StoreError::from)?,
                like: Some((like, dir.clone())),
            });
        }
        Ok(ImportPlan {
            collection: self.new_collection()?,
            like: None,
        })
    }

    fn new_collection(&self) -> Result<LabelledCollection> {
        let sensor = self.sensor.as_deref().map(SightFile::read).transpose()?;
        let recorded = match self.reference.as_deref() {
            Some(p) if p.is_dir() => Some(recorded_reference(p)?),
            _ => None,
        };
        let edits = CollectionEdits {
            depth_column: Some("none".into()),
            shear_columns: Some("none".into()),
            ..self.edits.clone()
        };
        let frame = self.reference.clone().unwrap_or_default();
        let mut base = LabelledCollection::new(self.frames.clone(), self.targets.clone(), frame);
        if self.reference.is_none() {
            base = base.with_reference(Reference::Estimate { pins: None });
        }
        let mut collection = base
            .edited(&edits)
            .map_err(tactrace_store::StoreError::from)?
            .with_sight(sensor.as_ref().map(SightFile::sight));
        if let Some((rest, sight)) = recorded {
            let sight = collection.sight().cloned().or(sight);
            collection = collection
                .with_reference(Reference::Estimated(rest))
                .with_sight(sight);
        } else if self.reference.is_none() {
            let pins = sensor.as_ref().map(|s| s.sensor.pins);
            collection = collection.with_reference(Reference::Estimate { pins });
        }
        Ok(collection)
    }
}

impl ImportPlan {
    /// Error unless `got` matches the `like` dataset (its reference pins,
    /// in order, and targets); nothing to check without `like`.
    pub fn check(&self, got: &TapData) -> Result<()> {
        match &self.like {
            Some((like, dir)) => check_like(got, like, dir),
            None => Ok(()),
        }
    }
}
