//! `reproduce --real DIR --image-model`: the image model beside the
//! PDenNN in the real-frame world. The real set is imported again with its
//! frames as 64 px images, split as the PDenNN's (the same seeded 80/20
//! rows), `conv-dennn` trained on the 80 % (`real/models/conv-dennn`), and
//! the report's four shapes followed with it, every tap answered by a
//! frame of the held-out 20 % (`real/follow-image/SHAPE`).
use crate::error::Result;
use crate::reproduce::{real_world_shapes, ReproduceConfig};
use crate::train_image::{save_image_model, train_image};
use std::path::Path;
use tactrace_convnet::{ConvConfig, ModelKind};
use tactrace_report::ReplayShapeRow;
use tactrace_store::{LabelledCollection, StoredImageModel, TapData, TrainingRecord};

/// Side of the image model's frames, px.
pub const IMAGE_SIZE: usize = 64;

/// Train `conv-dennn` on the real set `real`'s training part (the rows
/// `held_out` does not hold) and follow the four shapes with it in the
/// real-frame world of `held_out`, under `dir`.
pub(crate) fn image_world_shapes(
    cfg: &ReproduceConfig,
    real: &Path,
    held_out: &TapData,
    dir: &Path,
) -> Result<Vec<ReplayShapeRow>> {
    let collection = LabelledCollection::bristol(real);
    let imported = crate::import::import_with_frames(&collection, Some(IMAGE_SIZE), &|| {})?;
    let frames = imported.images.expect("frames were asked for");
    let data = imported.data;
    let held: std::collections::HashSet<&str> =
        held_out.meta.images.iter().map(String::as_str).collect();
    let rows: Vec<usize> = (0..data.len())
        .filter(|&i| !held.contains(data.meta.images[i].as_str()))
        .collect();
    let (train, train_frames) = (data.subset(&rows), frames.subset(&rows));
    let mut conv = ConvConfig::new(ModelKind::ConvDennn);
    if let Some(e) = cfg.epochs {
        conv.epochs = e;
    }
    let (model, history) =
        train_image(&conv, cfg.seed, (&train, &train_frames), None, &mut |_| {})?;
    let record = TrainingRecord::new(&data, Some(real), rows, None);
    let stored = StoredImageModel::new(model, frames.info.clone()).with_training(record);
    let model_dir = dir.join("models/conv-dennn");
    save_image_model(&model_dir, &stored, &history, true, &[])?;
    real_world_shapes(cfg, real, held_out, (&model_dir, &dir.join("follow-image")))
}
