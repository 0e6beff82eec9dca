//! Training that starts from a fitted model instead of fresh weights:
//! pretrain on one set of frames (e.g. the calibrated simulator's), then
//! fine-tune on another (the real fit frames). The new fit keeps the
//! starting model's networks, its pixel and target scalings (its weights
//! are in those units) and its layers; only the schedule (epochs, step
//! size, batches, regularisers) and the frames are new. Adam starts again
//! from zero moments; the shuffles come from the new seed.
use crate::config::ConvConfig;
use crate::data::{Frames, Targets};
use crate::error::{config_error, ConvError};
use crate::hybrid;
use crate::model::ConvModel;
use crate::train::{EpochReport, TrainingHistory};

impl ConvModel {
    /// A copy of this model trained further on `frames` and `targets` by
    /// `config`'s rule and schedule, shuffled from `seed` (network `k`
    /// from `seed + k`); `validation` is scored after every epoch and
    /// each epoch's report handed to `on_epoch`. `config` must describe
    /// the same networks as this model's (layers, activation, input
    /// centring and channels, number of networks) and the frames be of
    /// its input size, with one target a column of its outputs; anything
    /// else is refused before any work.
    pub fn fine_tune_with(
        &self,
        frames: &Frames,
        targets: &Targets,
        config: &ConvConfig,
        seed: u64,
        validation: Option<(Frames, Targets)>,
        on_epoch: &mut dyn FnMut(&EpochReport),
    ) -> Result<(ConvModel, TrainingHistory), ConvError> {
        config.validate()?;
        same_networks(&self.config, config)?;
        self.check_data(frames, targets)?;
        hybrid::check_pins(&self.input, frames)?;
        if let Some((vf, vt)) = &validation {
            self.check_data(vf, vt)?;
            hybrid::check_pins(&self.input, vf)?;
        }
        if frames.count() == 0 {
            return Err(ConvError::Empty);
        }
        let start = ConvModel {
            config: config.clone(),
            seed,
            nets: self.nets.clone(),
            input: self.input.clone(),
            targets: self.targets.clone(),
        };
        start.trained((frames, targets), validation, on_epoch)
    }

    /// `frames` of this model's input size and `targets` one row a frame,
    /// one column an output.
    fn check_data(&self, frames: &Frames, targets: &Targets) -> Result<(), ConvError> {
        let (height, width) = self.input_size();
        let (got_height, got_width) = frames.size();
        if (height, width) != (got_height, got_width) {
            return Err(ConvError::FrameSize {
                height,
                width,
                got_height,
                got_width,
            });
        }
        let checks = [
            ("target rows (one a frame)", frames.count(), targets.count()),
            ("targets a row", self.outputs(), targets.dim()),
        ];
        for (what, expected, got) in checks {
            if expected != got {
                return Err(ConvError::Shape {
                    what,
                    expected,
                    got,
                });
            }
        }
        Ok(())
    }
}

/// Whether `new` describes the networks `start` has: the first setting
/// that differs is the error, named.
fn same_networks(start: &ConvConfig, new: &ConvConfig) -> Result<(), ConvError> {
    let differs = [
        ("conv", start.conv != new.conv),
        ("dense", start.dense != new.dense),
        ("activation", start.activation != new.activation),
        ("input_centring", start.input_centring != new.input_centring),
        ("coord_channels", start.coord_channels != new.coord_channels),
        ("input", start.input != new.input),
        ("members", start.members != new.members),
    ];
    match differs.iter().find(|(_, d)| *d) {
        Some((field, _)) => Err(config_error(
            field,
            "differs from the starting model's (fine-tuning keeps its networks)",
        )),
        None => Ok(()),
    }
}
