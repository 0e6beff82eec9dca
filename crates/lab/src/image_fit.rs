//! An image model trained from fresh weights, the one way `train --model
//! conv-dennn|conv-mlp` and the Python package's `train` do it: a plain
//! model by [`crate::train_image::train_image`], a residual one (`input =
//! "pin_model_and_pixels"`, its `[base]` settings) by
//! [`crate::train_image::train_image_on_base`] (its pin model fitted on
//! every training row, the rows' base predictions out of fold), then
//! stored with what it was trained on: `training.json`'s record, with a
//! residual's folds, and its pin model with the training data's reference
//! pins (the model folder's `base/`).
use crate::error::Result;
use crate::image_base::BaseSettings;
use crate::train_image::{train_image, train_image_on_base};
use tactrace_convnet::{ConvConfig, EpochReport, TrainingHistory};
use tactrace_learn::ImageModel;
use tactrace_store::{
    BaseFolds, FramesInfo, ImageFrames, StoredImageModel, TapData, TrainingRecord,
};

/// What a fresh image model is: its configuration, a residual model's
/// base settings (`None` for any other), its seed, and whether each
/// training row is of the first dataset given
/// ([`TrainingRecord::in_first_dataset`], read by `[base] fit_on`).
#[derive(Debug, Clone, Copy)]
pub struct FreshImage<'a> {
    pub cfg: &'a ConvConfig,
    pub base: Option<&'a BaseSettings>,
    pub seed: u64,
    pub in_first: &'a [bool],
}

/// A fitted image model, its history, and a residual model's folds.
pub type FittedImage = (ImageModel, TrainingHistory, Option<BaseFolds>);

/// Fit `fresh` on the training rows `data` and their frames, scoring
/// `val` after every epoch (as [`train_image`]).
pub fn fit_fresh_image(
    fresh: FreshImage,
    data: (&TapData, &ImageFrames),
    val: Option<(&TapData, &ImageFrames)>,
    on_epoch: &mut dyn FnMut(&EpochReport),
) -> Result<FittedImage> {
    match fresh.base {
        Some(base) => {
            let data = (data.0, data.1, fresh.in_first);
            let (m, h, folds) =
                train_image_on_base(fresh.cfg, base, fresh.seed, data, val, on_epoch)?;
            Ok((m, h, Some(folds)))
        }
        None => {
            let (m, h) = train_image(fresh.cfg, fresh.seed, data, val, on_epoch)?;
            Ok((m, h, None))
        }
    }
}

/// The fitted `model` as its folder stores it: its frames' `info`, the
/// record of the split it was trained on (`split`, with a residual
/// model's `folds`), and a residual model's pin model with `pins`, the
/// training data's reference pins, recorded as trained on the same rows.
pub fn store_fitted_image(
    model: ImageModel,
    folds: Option<BaseFolds>,
    info: FramesInfo,
    split: TrainingRecord,
    pins: Vec<[f64; 2]>,
) -> StoredImageModel {
    let record = TrainingRecord {
        base: folds,
        ..split.clone()
    };
    StoredImageModel::new(model, info)
        .with_training(record)
        .with_base_pins(pins, split)
}
