//! `--views on|off` of `validate`, `predict` and `follow`: a model fitted
//! on turned copies (`rotations`) predicts with or without the mean over
//! each tap's turned views, and a pin model fitted on mirror copies
//! (`reflections`) with or without the mean of the tap and its mirror
//! copy, whatever its file says, so the two can be compared without
//! editing the model folder. Refused (exit 2, naming the folder) for a
//! model fitted with neither.
use anyhow::Result;
use clap::{Args, ValueEnum};
use tactrace_lab::LabError;
use tactrace_store::LoadedModel;

/// Turned views at prediction, on or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ViewsArg {
    /// The mean over the tap's turned views, each prediction turned back.
    On,
    /// The tap alone.
    Off,
}

/// The `--views` flag.
#[derive(Args, Clone, Copy, Debug, Default)]
pub struct ViewsFlag {
    /// Views at prediction of a model fitted on turned copies
    /// (`rotations`) or mirror copies (`reflections`): on, the mean over
    /// each tap's turned views (or the tap and its mirror copy); off, the
    /// tap alone. Default: what the model's file says. Refused for a model
    /// fitted with neither.
    #[arg(long, value_enum, value_name = "on|off")]
    pub views: Option<ViewsArg>,
}

impl ViewsFlag {
    /// `model` with its turned views switched as the flag says (left as
    /// its file says without the flag).
    pub fn apply(self, model: &mut LoadedModel) -> Result<()> {
        if let Some(v) = self.views {
            model
                .set_turned_views(v == ViewsArg::On)
                .map_err(LabError::from)?;
        }
        Ok(())
    }

    /// Whether the flag was given.
    pub fn given(self) -> bool {
        self.views.is_some()
    }
}
