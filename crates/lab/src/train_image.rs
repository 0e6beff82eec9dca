//! Training and validation of the image models (`conv-dennn`,
//! `conv-mlp`: a dataset's `frames.npy` in, its N targets out), with the
//! same targets, validation figures and model folders as the pin models
//! (`crate::train`). docs/learning.md, "Images in".
use crate::error::{LabError, Result};
use crate::image_base::{base_settings, fit_base, split_base_table, BaseSettings};
use crate::image_base_reuse::reuse_base;
use crate::train::{data_targets, held_out_rows, named_targets, score_predictions, Validation};
use std::path::{Path, PathBuf};
use tactrace_convnet::{ConvConfig, EpochReport, Frames, ModelKind, TrainingHistory};
use tactrace_learn::{BaseFit, ImageModel, ModelTarget};
use tactrace_store::{
    stage_image_model, BaseFolds, ImageFrames, LoadedModel, StoredImageModel, TapData,
};

/// The configuration of an image model of `kind`: its defaults, then the
/// keys of an optional TOML override (unknown keys are errors), then
/// `epochs`; validated here, before any work. A `[base]` table is checked
/// and left out ([`resolve_image_settings`] keeps it).
pub fn resolve_image_config(
    kind: ModelKind,
    toml_text: Option<&str>,
    epochs: Option<usize>,
) -> Result<ConvConfig> {
    Ok(resolve_image_settings(kind, toml_text, epochs)?.0)
}

/// [`resolve_image_config`] and a residual model's base settings (its
/// `[base]` table, or the defaults; `None` for any other model).
pub fn resolve_image_settings(
    kind: ModelKind,
    toml_text: Option<&str>,
    epochs: Option<usize>,
) -> Result<(ConvConfig, Option<BaseSettings>)> {
    let mut cfg = ConvConfig::new(kind);
    let mut given = None;
    if let Some(text) = toml_text {
        let (rest, base) = split_base_table(text)?;
        cfg = tactrace_store::overlay(&cfg, &rest, "model config")?;
        cfg.kind = kind;
        given = base;
    }
    if let Some(e) = epochs {
        cfg.epochs = e;
    }
    cfg.validate().map_err(tactrace_learn::LearnError::from)?;
    let base = base_settings(&cfg, given)?;
    Ok((cfg, base))
}

/// The frames of the dataset `data` read from `dir`, refused (bad input)
/// when it has none: a dataset of pin vectors only.
pub fn data_frames(data: &TapData, dir: &Path) -> Result<ImageFrames> {
    tactrace_store::read_dataset_frames(dir, data)?.ok_or_else(|| no_frames(dir))
}

/// The refusal of the dataset folder `dir` for an image model: it holds
/// no frames as images.
pub(crate) fn no_frames(dir: &Path) -> LabError {
    LabError::Format {
        path: dir.to_path_buf(),
        reason: "the dataset holds pin displacements only, no frames as images \
                 (frames.npy): an image model trains on frames; import the collection \
                 again with --frames-size PX (e.g. 64)"
            .into(),
    }
}

/// A view of `frames` for the network, each frame with its row's pin
/// displacement vector from `data` (read by a pins-and-pixels model).
pub fn view<'a>(frames: &'a ImageFrames, data: &'a TapData) -> Result<Frames<'a>> {
    let (h, w) = (frames.info.height, frames.info.width);
    let view = Frames::new(&frames.pixels, frames.count(), h, w);
    Ok(view
        .and_then(|v| match data.dim() {
            0 => Ok(v),
            dim => v.with_pins(&data.inputs, dim),
        })
        .map_err(tactrace_learn::LearnError::from)?)
}

/// Fit an image model of `cfg` from `seed` on `data`'s targets and its
/// `frames`, scoring `val` (rows and their frames) after every epoch;
/// `on_epoch` sees each epoch's report as it ends.
pub fn train_image(
    cfg: &ConvConfig,
    seed: u64,
    (data, frames): (&TapData, &ImageFrames),
    val: Option<(&TapData, &ImageFrames)>,
    on_epoch: &mut dyn FnMut(&EpochReport),
) -> Result<(ImageModel, TrainingHistory)> {
    let outputs = data_targets(data)?;
    let (train, val) = views(&outputs, (data, frames), val)?;
    Ok(ImageModel::fit(
        &train,
        &data.targets,
        &outputs,
        cfg,
        seed,
        val,
        on_epoch,
    )?)
}

/// A residual model (`input = "pin_model_and_pixels"`) of `cfg` fitted
/// from `seed` on `data`'s targets and `frames` ([`train_image`]'s
/// arguments): its pin model of `base` fitted on every row of `data` (or,
/// with `fit_on = "first_dataset"`, on the rows flagged in `in_first`),
/// the rows' base predictions out of fold (crate::image_base), or, with
/// `[base] from`, the pin model and predictions of that folder's base
/// (crate::image_base_reuse); with the record of the folds for
/// `training.json`.
pub fn train_image_on_base(
    cfg: &ConvConfig,
    base: &BaseSettings,
    seed: u64,
    (data, frames, in_first): (&TapData, &ImageFrames, &[bool]),
    val: Option<(&TapData, &ImageFrames)>,
    on_epoch: &mut dyn FnMut(&EpochReport),
) -> Result<(ImageModel, TrainingHistory, BaseFolds)> {
    let outputs = data_targets(data)?;
    let (train, val) = views(&outputs, (data, frames), val)?;
    let (pin_model, rows, folds) = match base.from {
        Some(_) => reuse_base(base, data, in_first)?,
        None => fit_base(base, data, seed, in_first)?,
    };
    let fit = BaseFit {
        model: &pin_model,
        rows: &rows,
    };
    let (model, history) = ImageModel::fit_on_base(
        &train,
        &data.targets,
        &outputs,
        fit,
        cfg,
        seed,
        val,
        on_epoch,
    )?;
    Ok((model, history, folds))
}

/// [`train_image`] from the fitted model `start` instead of fresh
/// weights (`train --init`): its networks, scalings and targets kept,
/// `cfg`'s schedule; `data` must have `start`'s targets and `cfg` its
/// networks ([`ImageModel::fine_tune`]).
pub fn fine_tune_image(
    start: &ImageModel,
    cfg: &ConvConfig,
    seed: u64,
    (data, frames): (&TapData, &ImageFrames),
    val: Option<(&TapData, &ImageFrames)>,
    on_epoch: &mut dyn FnMut(&EpochReport),
) -> Result<(ImageModel, TrainingHistory)> {
    named_targets(start.outputs(), data)?;
    let (train, val) = views(start.outputs(), (data, frames), val)?;
    Ok(start.fine_tune(&train, &data.targets, cfg, seed, val, on_epoch)?)
}

/// The validation frames and their target rows, as the image model takes them.
type ValView<'a> = (Frames<'a>, &'a [f32]);

/// Views of the training `frames` and of the validation rows' frames and
/// targets, the validation set checked to have the targets `outputs` and
/// frames of the training frames' size.
fn views<'a>(
    outputs: &[ModelTarget],
    (data, frames): (&'a TapData, &'a ImageFrames),
    val: Option<(&'a TapData, &'a ImageFrames)>,
) -> Result<(Frames<'a>, Option<ValView<'a>>)> {
    let val = match val {
        Some((v, f)) => {
            named_targets(outputs, v)?;
            same_size(frames, f)?;
            Some((view(f, v)?, v.targets.as_slice()))
        }
        None => None,
    };
    Ok((view(frames, data)?, val))
}

fn same_size(a: &ImageFrames, b: &ImageFrames) -> Result<()> {
    if (a.info.height, a.info.width) == (b.info.height, b.info.width) {
        return Ok(());
    }
    Err(LabError::Config(format!(
        "frames of {} x {} px and of {} x {} px: import both datasets with the same --frames-size",
        a.info.height, a.info.width, b.info.height, b.info.width
    )))
}

/// Validate the image model `model` on `data` (named `what`) and its
/// `frames`: the same figures as a pin model's, every target scored;
/// counts the samples it was trained on when its folder records them.
pub fn validate_image(
    model: &StoredImageModel,
    data: &TapData,
    frames: &ImageFrames,
    what: &Path,
) -> Result<Validation> {
    let net = model.model();
    let (h, w) = net.input_size();
    if (frames.info.height, frames.info.width) != (h, w) {
        return Err(LabError::Format {
            path: what.to_path_buf(),
            reason: format!(
                "its frames are {} x {} px, the model takes {h} x {w} px: import it with \
                 --frames-size {h}",
                frames.info.height, frames.info.width
            ),
        });
    }
    model.check_pins(&data.meta.reference_pins, what)?;
    let targets = named_targets(net.outputs(), data)?;
    let predicted = net.predict_batch(&view(frames, data)?)?;
    let mut v = score_predictions(targets, data, predicted, net.edge_roles().ok())?;
    v.rows_seen_in_training = model.training().map(|t| t.rows_seen(data));
    v.turned_views = net.views_at_prediction();
    Ok(v)
}

/// Validate any model on the dataset `data` read from `dir` (an image
/// model on its frames), on every row or, with `held_out = Some((fraction,
/// seed))`, on the rows `train --val-fraction --split-seed` held out.
pub fn validate_loaded(
    model: &LoadedModel,
    data: &TapData,
    dir: &Path,
    held_out: Option<(f64, u64)>,
) -> Result<Validation> {
    match (model, held_out) {
        (LoadedModel::Pins(m), None) => crate::train::validate(m, data, dir),
        (LoadedModel::Pins(m), Some((f, s))) => crate::train::validate_held_out(m, data, dir, f, s),
        (LoadedModel::Image(m), held_out) => {
            let frames = data_frames(data, dir)?;
            match held_out {
                None => validate_image(m, data, &frames, dir),
                Some(split) => {
                    let rows = held_out_rows(m.training(), data, dir, split)?;
                    validate_image(m, &data.subset(&rows), &frames.subset(&rows), dir)
                }
            }
        }
    }
}

/// The per-epoch history as CSV: epoch, learning rate, training loss,
/// validation loss and each encoded output's validation MAE.
pub fn image_history_csv(history: &TrainingHistory) -> Vec<u8> {
    let mut out = String::from("epoch,learning_rate,loss,val_loss,val_mae\n");
    for e in &history.epochs {
        let (vl, vm) = match &e.validation {
            Some(v) => (
                v.loss.to_string(),
                v.mae
                    .iter()
                    .map(f64::to_string)
                    .collect::<Vec<_>>()
                    .join(" "),
            ),
            None => (String::new(), String::new()),
        };
        out.push_str(&format!(
            "{},{},{},{vl},{vm}\n",
            e.epoch, e.learning_rate, e.loss
        ));
    }
    out.into_bytes()
}

/// Save a trained image model, its history and `extra` text files into
/// `dir`, which appears only when complete.
pub fn save_image_model(
    dir: &Path,
    model: &StoredImageModel,
    history: &TrainingHistory,
    force: bool,
    extra: &[(&str, String)],
) -> Result<PathBuf> {
    let stage = stage_image_model(dir, model, &image_history_csv(history), force, extra)?;
    Ok(stage.commit()?)
}
