//! The image models' side of `train` and `predict`: `train --model
//! conv-dennn|conv-mlp` on a dataset's frames (`frames.npy`), with the pin
//! models' splits, record of the rows trained on, validation and model
//! folder; `predict` of one frame or a dataset.
use crate::cmd_learn::{PredictArgs, PresetArg, TrainArgs};
use crate::inputs::Inputs;
use crate::progress::bar;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use tactrace_convnet::{ConvConfig, ModelKind};
use tactrace_lab::image_base::BaseSettings;
use tactrace_lab::image_fit::{fit_fresh_image, store_fitted_image, FreshImage};
use tactrace_lab::train_sets::TrainingSets;
use tactrace_lab::{import_reader, train_image as ti, LabError};
use tactrace_servo::ImageInput;
use tactrace_store::{
    check_output_dir, fsutil, read_dataset, FramesInfo, ImageFrames, LoadedModel, SightFile,
    StoredImageModel, TapData,
};

/// Train the image model `kind` as `a` says.
pub fn train(kind: ModelKind, a: TrainArgs) -> Result<()> {
    if a.search || !matches!(a.preset, PresetArg::Default) {
        return Err(LabError::Config(format!(
            "{}: --search and --preset are the pin models' (an image model's settings: \
             --config FILE, --epochs, --seed)",
            kind.name()
        ))
        .into());
    }
    let text = a.config.as_deref().map(fsutil::read_text).transpose()?;
    let settings = ti::resolve_image_settings(kind, text.as_deref(), a.epochs);
    let (mut cfg, base) = settings.with_context(|| {
        a.config
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default()
    })?;
    if let Some(k) = a.ensemble {
        // `--ensemble K` is the image model's `members = K`.
        cfg.members = k;
        cfg.validate()
            .map_err(tactrace_learn::LearnError::from)
            .map_err(LabError::from)?;
    }
    let seed = a.seed.unwrap_or(0);
    if a.print_config {
        crate::say!("{}", resolved_toml(&cfg, base.as_ref())?.trim_end());
        return Ok(());
    }
    Inputs::new()
        .all("--train", &a.train)
        .all("--val", &a.val)
        .opt("--config", a.config.as_deref())
        .opt("--init", a.init.as_deref())
        .check_apart("--out", &a.out)?;
    let start = a.init.as_deref().map(start_model).transpose()?;
    let _out = check_output_dir(&a.out, a.force)?;
    let sets = TrainingSets::read(&a.train)?;
    let all_frames = sets.frames()?;
    let split = sets.split(a.val_fraction.map(|f| (f, a.split_seed)))?;
    let train_frames = all_frames.subset(&split.record.train_rows);
    let val_sets = (!a.val.is_empty())
        .then(|| TrainingSets::read(&a.val))
        .transpose()?;
    let (val, val_frames): (Option<TapData>, Option<ImageFrames>) = match &val_sets {
        Some(v) => (Some(v.data.clone()), Some(v.frames()?)),
        None => {
            let rows = split
                .record
                .split
                .as_ref()
                .map(|s| all_frames.subset(&s.rows));
            if let (Some(f), Some(va)) = (a.val_fraction, &split.val) {
                eprintln!(
                    "training on {} samples, holding out {} (fraction {f}, seed {})",
                    split.train.len(),
                    va.len(),
                    a.split_seed
                );
                if let Some(held) = &split.record.split {
                    let says = tactrace_lab::held_out_copies::held_out_lines;
                    for line in says(&sets.data, held, &split.train, va) {
                        eprintln!("{line}");
                    }
                }
            }
            (split.val.clone(), rows)
        }
    };
    let pb = bar(cfg.epochs as u64, "train");
    let t0 = std::time::Instant::now();
    let pair = val.as_ref().zip(val_frames.as_ref());
    let mut on_epoch = |e: &tactrace_convnet::EpochReport| {
        pb.set_position(e.epoch as u64 + 1);
        let val = e
            .validation
            .as_ref()
            .map(|v| format!(", validation loss {:.4}", v.loss))
            .unwrap_or_default();
        let secs = t0.elapsed().as_secs_f64();
        pb.suspend(|| {
            eprintln!(
                "epoch {}/{}: loss {:.4}{val} ({secs:.0} s)",
                e.epoch + 1,
                cfg.epochs,
                e.loss
            )
        });
    };
    let data = (&split.train, &train_frames);
    let in_first = split.record.in_first_dataset();
    let (model, history, folds) = match &start {
        Some((_, s)) => {
            same_frames(s, &all_frames.info)?;
            let (m, h) = ti::fine_tune_image(s.model(), &cfg, seed, data, pair, &mut on_epoch)?;
            (m, h, None)
        }
        None => {
            let fresh = FreshImage {
                cfg: &cfg,
                base: base.as_ref(),
                seed,
                in_first: &in_first,
            };
            fit_fresh_image(fresh, data, pair, &mut on_epoch)?
        }
    };
    pb.finish_and_clear();
    let secs = t0.elapsed().as_secs_f64();
    let pins = sets.data.meta.reference_pins.clone();
    let info = all_frames.info.clone();
    let stored = store_fitted_image(model, folds, info, split.record, pins);
    let resolved = format!(
        "# {} {} (seed {seed})\n{}",
        kind.name(),
        env!("CARGO_PKG_VERSION"),
        resolved_toml(&cfg, base.as_ref())?
    );
    let mut extra = vec![("config.toml", resolved)];
    if let Some((path, s)) = &start {
        extra.push(("init.toml", init_record(path, s)?));
    }
    let dir = ti::save_image_model(&a.out, &stored, &history, a.force, &extra)?;
    eprintln!(
        "trained {} in {secs:.1} s ({} epochs, seed {seed}); saved model to {}",
        kind.name(),
        cfg.epochs,
        dir.display()
    );
    if let (Some(v), Some(f)) = (&val, &val_frames) {
        let what = val_sets.as_ref().unwrap_or(&sets).first_dir();
        let score = ti::validate_image(&stored, v, f, what)?;
        crate::say!(
            "validation: {} over {} samples",
            score.per_target_line(),
            score.samples
        );
        if let Some(w) = score.seen_warning() {
            eprintln!("warning: {w}");
        }
    }
    Ok(())
}

/// The resolved configuration as TOML, a residual model's `[base]` table
/// last.
fn resolved_toml(cfg: &ConvConfig, base: Option<&BaseSettings>) -> Result<String> {
    let mut text = toml::to_string(cfg)?;
    if let Some(b) = base {
        let table = toml::Table::from_iter([("base".to_string(), toml::Value::try_from(b)?)]);
        text.push_str(&toml::to_string(&table)?);
    }
    Ok(text)
}

/// The image model `train --init` starts from, with its folder.
fn start_model(dir: &Path) -> Result<(PathBuf, StoredImageModel)> {
    match LoadedModel::load(dir)? {
        LoadedModel::Image(m) => Ok((dir.to_path_buf(), m)),
        LoadedModel::Pins(_) => Err(LabError::Config(format!(
            "--init {}: a pin model; an image model starts only from an image model",
            dir.display()
        ))
        .into()),
    }
}

/// Refuse training frames made otherwise than the starting model's (size
/// or sensor preprocessing): its weights read frames made its way.
fn same_frames(start: &StoredImageModel, frames: &FramesInfo) -> Result<()> {
    let (s, f) = (start.frames(), frames);
    if (s.height, s.width, &s.preprocess) == (f.height, f.width, &f.preprocess) {
        return Ok(());
    }
    Err(LabError::Config(format!(
        "--init's model reads {} x {} px frames{}; --train's are {} x {} px{}: import \
         them the same way (--frames-size, the sensor's preprocessing)",
        s.height,
        s.width,
        preprocessed(s),
        f.height,
        f.width,
        preprocessed(f)
    ))
    .into())
}

fn preprocessed(f: &FramesInfo) -> &'static str {
    match f.preprocess {
        Some(_) => " (preprocessed by a sensor's settings)",
        None => " (no preprocessing recorded)",
    }
}

/// `init.toml` of a model fine-tuned from `start` (folder `dir`): the
/// folder as given to --init, its kind, seed and configuration.
fn init_record(dir: &Path, start: &StoredImageModel) -> Result<String> {
    let net = start.model().network();
    let mut record = toml::Table::new();
    record.insert("model".into(), dir.display().to_string().into());
    record.insert("kind".into(), start.model().kind_name().into());
    record.insert("seed".into(), toml::Value::Integer(net.seed() as i64));
    record.insert("config".into(), toml::Value::try_from(net.config())?);
    Ok(format!(
        "# the model this one started from (train --init), then fine-tuned\n{}",
        toml::to_string(&record)?
    ))
}

/// `predict` with an image model: one frame (`--image`, made as the
/// training frames were: the preprocessing the model folder records, or
/// for a folder that records none the `--sensor` settings or the frame as
/// it is, then area-averaged to the model's input), or a dataset with
/// frames (`--data`), every target predicted then true.
pub fn predict(model: &StoredImageModel, a: PredictArgs) -> Result<()> {
    let net = model.model();
    match (a.image, a.data) {
        (Some(image), None) => {
            let input = predict_input(model, a.sensor.as_deref())?;
            let pixels = import_reader::image_input(&input, &image)?;
            let values = net.predict_targets(&pixels).map_err(LabError::from)?;
            crate::cmd_learn::say_prediction(&image, net.outputs(), &values)?;
        }
        (None, Some(dir)) => {
            let data = read_dataset(&dir)?;
            let loaded = LoadedModel::Image(model.clone());
            let v = ti::validate_loaded(&loaded, &data, &dir, None)?;
            crate::cmd_learn::say_target_rows(&v)?;
        }
        _ => {
            return Err(LabError::Config(
                "give either --image FRAME or --data DIR (with frames.npy)".into(),
            )
            .into())
        }
    }
    Ok(())
}

/// How `predict --image` makes the frame: as the model folder records
/// ([`tactrace_lab::follow::image_input_for`]); a folder that records no
/// preprocessing takes `--sensor`'s, if given (models trained before the
/// folder recorded it). A `--sensor` that disagrees with the record is
/// refused.
fn predict_input(model: &StoredImageModel, sensor: Option<&Path>) -> Result<ImageInput> {
    let recorded = model.frames().preprocess.as_ref();
    let Some(path) = sensor else {
        return Ok(tactrace_lab::follow::image_input_for(model)?);
    };
    let sight = SightFile::read(path)?.sight();
    let given = Some(&sight.preprocess).filter(|p| **p != Default::default());
    if recorded.is_some() && recorded != given {
        return Err(LabError::Config(format!(
            "{} preprocesses frames otherwise than the image model's training frames were              (its folder records how); leave out --sensor",
            path.display()
        ))
        .into());
    }
    let size = model.model().input_size();
    Ok(ImageInput::new(recorded.or(given), size).map_err(LabError::from)?)
}
