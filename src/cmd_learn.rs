//! Learning commands: `train`, `validate`, `predict`.
use crate::inputs::Inputs;
use crate::progress::bar;
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
use tactrace_lab::train_sets::{check_val_pins, TrainingSets};
use tactrace_lab::{import_reader, train as tr, train_continue as tc, LabError};
use tactrace_learn::{ModelKind, ModelTarget, Preset, SearchSpace};
use tactrace_report::figures::{self, Predicted};
use tactrace_store::{check_output_dir, fsutil, read_dataset, LoadedModel, SightFile, StoredModel};

#[derive(Clone, Copy, ValueEnum)]
pub enum ModelArg {
    /// Two dendritic networks (position, angle), each on its own principal components.
    Pdennn,
    /// One dendritic network on principal components, both targets.
    Pcadennn,
    /// One dendritic network on the standardised pin displacements, both targets.
    Disdennn,
    /// Backprop twin of the PDenNN (same architecture, SGD backprop).
    Mlp,
}

impl From<ModelArg> for ModelKind {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Pdennn => ModelKind::PDenNN,
            ModelArg::Pcadennn => ModelKind::PcaDenNN,
            ModelArg::Disdennn => ModelKind::DisDenNN,
            ModelArg::Mlp => ModelKind::Mlp,
        }
    }
}

/// `train --model`: a pin model, or an image model (frames in).
#[derive(Clone, Copy, ValueEnum)]
pub enum TrainModelArg {
    /// Two dendritic networks (position, angle), each on its own principal components.
    Pdennn,
    /// One dendritic network on principal components, both targets.
    Pcadennn,
    /// One dendritic network on the standardised pin displacements, both targets.
    Disdennn,
    /// Backprop twin of the PDenNN (same architecture, SGD backprop).
    Mlp,
    /// Image model: a convolutional dendritic network on the dataset's
    /// frames (frames.npy), trained by equilibrium propagation.
    ConvDennn,
    /// Backprop twin of conv-dennn (same layers and initialisation).
    ConvMlp,
}

impl TrainModelArg {
    /// The pin model, or the image model's kind.
    pub(crate) fn pins(self) -> std::result::Result<ModelArg, tactrace_convnet::ModelKind> {
        match self {
            TrainModelArg::Pdennn => Ok(ModelArg::Pdennn),
            TrainModelArg::Pcadennn => Ok(ModelArg::Pcadennn),
            TrainModelArg::Disdennn => Ok(ModelArg::Disdennn),
            TrainModelArg::Mlp => Ok(ModelArg::Mlp),
            TrainModelArg::ConvDennn => Err(tactrace_convnet::ModelKind::ConvDennn),
            TrainModelArg::ConvMlp => Err(tactrace_convnet::ModelKind::ConvMlp),
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
pub enum PresetArg {
    /// Tuned to work on simulated and real data alike.
    Default,
    /// The report's Table 4.1 exactly.
    Report,
}

impl From<PresetArg> for Preset {
    fn from(p: PresetArg) -> Self {
        match p {
            PresetArg::Default => Preset::Default,
            PresetArg::Report => Preset::Report,
        }
    }
}

#[derive(Args)]
pub struct TrainArgs {
    /// Kind of pose model: a pin model (displacement vectors in) or an
    /// image model (conv-dennn, conv-mlp: the dataset's frames.npy in,
    /// from `import --frames-size`).
    #[arg(long, value_enum, default_value = "pdennn")]
    pub(crate) model: TrainModelArg,
    /// Training dataset directory; repeat it to train on several datasets
    /// as one (their rows joined in the order given; each must have the
    /// first's pins and reference order, targets and, for an image model,
    /// frame size and preprocessing).
    #[arg(long, required = true, value_name = "DIR")]
    pub(crate) train: Vec<PathBuf>,
    /// Validation dataset directory (scored after training); repeat it to
    /// score several datasets as one.
    #[arg(long, conflicts_with = "val_fraction", value_name = "DIR")]
    pub(crate) val: Vec<PathBuf>,
    /// Hold out this fraction of --train (seeded shuffle; of the rows of
    /// every --train joined) as the validation set instead of a separate
    /// --val directory; the model never sees it.
    #[arg(long)]
    pub(crate) val_fraction: Option<f64>,
    /// Seed of the --val-fraction shuffle.
    #[arg(long, default_value_t = 1)]
    pub(crate) split_seed: u64,
    /// Output model directory.
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Training epochs (default: the preset's).
    #[arg(long)]
    pub(crate) epochs: Option<usize>,
    /// Train an ensemble of K members (a pin model's nets K times, from
    /// seeds derived from the configuration's seed, in parallel; an image
    /// model's K networks from seeds seed, seed + 1, ...), their
    /// predictions averaged; saved as one model folder. Default: the
    /// configuration's `ensemble` (pin models) or `members` (image
    /// models), 1.
    #[arg(long, value_name = "K")]
    pub(crate) ensemble: Option<usize>,
    /// Seed of an image model's initialisation, shuffling and shifts
    /// (pin models take theirs from --config); at most 2^63 - 1, the
    /// largest a TOML record of the run holds.
    #[arg(long, value_parser = clap::value_parser!(u64).range(..=tactrace_learn::MAX_SEED))]
    pub(crate) seed: Option<u64>,
    /// Start from the trained model in this folder instead of fresh
    /// weights: an image model fine-tuned on --train (its networks, pixel
    /// and target scalings kept), or a pin model trained further on the
    /// rows it was trained on (its nets, standardiser, PCA and target
    /// scaling kept, its shuffles continued). --config / --epochs give the
    /// new schedule and must describe the same networks. Recorded in the
    /// new model folder's init.toml. Default: fresh weights.
    #[arg(long, value_name = "MODEL")]
    pub(crate) init: Option<PathBuf>,
    /// Hyper-parameter preset the --config file is laid over (pin models).
    #[arg(long, value_enum, default_value = "default")]
    pub(crate) preset: PresetArg,
    /// TOML overriding any hyper-parameter of the preset (of an image
    /// model: of its defaults, `--print-config` shows them).
    #[arg(long)]
    pub(crate) config: Option<PathBuf>,
    /// Run a hyper-parameter search first (on a validation split carved out
    /// of the training data), then train the best configuration on all of it.
    #[arg(long)]
    pub(crate) search: bool,
    /// TOML with the search grid (keys of `SearchSpace`; missing keys take
    /// the built-in grid).
    #[arg(long, requires = "search")]
    search_space: Option<PathBuf>,
    /// Fraction of the training data the search validates on.
    #[arg(long, default_value_t = 0.25, requires = "search")]
    search_fraction: f64,
    /// Number of grid points to try (overrides the grid file).
    #[arg(long, requires = "search")]
    trials: Option<usize>,
    /// Print the resolved configuration as TOML and exit.
    #[arg(long)]
    pub(crate) print_config: bool,
    /// Replace an existing model directory.
    #[arg(long)]
    pub(crate) force: bool,
}

/// The model configuration `--model`, `--preset`, `--config FILE` and
/// `--epochs` resolve to (errors name the file).
pub fn model_config(
    model: ModelArg,
    preset: PresetArg,
    config: Option<&Path>,
    epochs: Option<usize>,
) -> Result<tactrace_learn::ModelConfig> {
    let text = config.map(fsutil::read_text).transpose()?;
    tr::resolve_config(model.into(), preset.into(), text.as_deref(), epochs)
        .with_context(|| config.map(|p| p.display().to_string()).unwrap_or_default())
}

pub fn train(a: TrainArgs) -> Result<()> {
    let model = match a.model.pins() {
        Ok(model) => model,
        Err(kind) => return crate::cmd_image::train(kind, a),
    };
    if a.seed.is_some() {
        return Err(LabError::Config(
            "--seed is an image model's; a pin model takes its seeds from --config".into(),
        )
        .into());
    }
    let start = a
        .init
        .as_deref()
        .map(crate::cmd_pin_init::start_model)
        .transpose()?;
    let mut cfg = model_config(model, a.preset, a.config.as_deref(), a.epochs)?;
    if let Some(k) = a.ensemble {
        cfg.ensemble = k;
        cfg.validate().map_err(LabError::from)?;
    }
    if a.print_config {
        crate::say!("{}", toml::to_string(&cfg)?.trim_end());
        return Ok(());
    }
    Inputs::new()
        .all("--train", &a.train)
        .all("--val", &a.val)
        .opt("--config", a.config.as_deref())
        .opt("--search-space", a.search_space.as_deref())
        .opt("--init", a.init.as_deref())
        .check_apart("--out", &a.out)?;
    let _out = check_output_dir(&a.out, a.force)?;
    let sets = TrainingSets::read(&a.train)?;
    let split = sets.split(a.val_fraction.map(|f| (f, a.split_seed)))?;
    let val_sets = (!a.val.is_empty())
        .then(|| TrainingSets::read(&a.val))
        .transpose()?;
    let (data, val, record) = match &val_sets {
        Some(v) => {
            check_val_pins(&sets, v)?;
            (split.train, Some(v.data.clone()), split.record)
        }
        None => {
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
            (split.train, split.val, split.record)
        }
    };
    let held_out = if a.val.is_empty() {
        val.as_ref().map_or(0, |v| v.len())
    } else {
        0
    };
    tr::check_trainable(&cfg, &data, held_out)?;
    if let Some((_, start)) = &start {
        crate::cmd_pin_init::check_start(start, &cfg, &record, a.search)?;
    }
    let (cfg, mut extra) = if a.search {
        let space = search_space(a.search_space.as_deref(), a.trials)?;
        let t0 = std::time::Instant::now();
        let mut k = 0;
        let outputs = tr::data_targets(&data)?;
        let trials = tr::search(
            &cfg,
            &space,
            &data,
            a.search_fraction,
            a.split_seed.wrapping_add(1),
            &mut |t| {
                k += 1;
                eprintln!(
                    "trial {k}: {} -> validation {}; score {:.4} ({:.0} s so far)",
                    tr::trial_summary(t),
                    tr::trial_errors(t, &outputs),
                    t.score,
                    t0.elapsed().as_secs_f64()
                );
            },
        )?;
        let best = trials
            .first()
            .filter(|t| t.score.is_finite())
            .ok_or_else(|| LabError::Config("every search trial diverged".into()))?;
        eprintln!("best: {}", tr::trial_summary(best));
        let extra = vec![
            ("search.csv", tr::trials_csv(&trials, &outputs)),
            ("search_best.toml", toml::to_string(&best.config)?),
        ];
        (best.config.clone(), extra)
    } else {
        (cfg, Vec::new())
    };
    let pb = bar(cfg.epochs as u64, "train");
    let t0 = std::time::Instant::now();
    let mut tick = |e: usize| pb.set_position(e as u64);
    let (model, history) = match &start {
        None => tr::train_with_validation(&cfg, &data, val.as_ref(), &mut tick)?,
        Some((dir, start)) => {
            extra.push(("init.toml", tc::init_record(dir, start)?));
            let what = sets.first_dir();
            tc::continue_training(start, what, &cfg, &data, val.as_ref(), &mut tick)?
        }
    };
    pb.finish_and_clear();
    let secs = t0.elapsed().as_secs_f64();
    let model = StoredModel::new(model, data.meta.reference_pins.clone()).with_training(record);
    let dir = tr::save_model(&a.out, &model, &history, a.force, &extra)?;
    eprintln!("trained in {secs:.1} s; saved model to {}", dir.display());
    if history.member_lr_halvings.iter().any(|&h| h > 0) {
        let restarted: Vec<String> = (history.member_lr_halvings.iter().enumerate())
            .filter(|(_, &h)| h > 0)
            .map(|(m, h)| format!("member {} halved {h} time(s)", m + 1))
            .collect();
        eprintln!(
            "note: ensemble members diverged and restarted alone with their learning rates \
             halved ({}); the others kept their results; {} records the halvings",
            restarted.join(", "),
            dir.join("training.json").display()
        );
    } else if history.lr_halvings > 0 {
        eprintln!(
            "note: training diverged and was restarted with the learning rates halved {} time(s); \
             {} records the rates used",
            history.lr_halvings,
            dir.join("model.json").display()
        );
    }
    if let Some(val) = val {
        let what = val_sets.as_ref().unwrap_or(&sets).first_dir();
        let v = tr::validate(&model, &val, what)?;
        if !v.shows_edge_pose() {
            crate::say!(
                "validation: {} over {} samples",
                v.per_target_line(),
                v.samples
            );
        } else {
            crate::say!(
                "validation: position {:.3} mm, angle {:.3} deg over {} samples",
                v.position_mae_mm,
                v.angle_mae_deg,
                v.samples
            );
        }
        if let Some(w) = v.seen_warning() {
            eprintln!("warning: {w}");
        }
    }
    Ok(())
}

/// The search grid: a TOML file's keys over the built-in grid.
fn search_space(path: Option<&std::path::Path>, trials: Option<usize>) -> Result<SearchSpace> {
    let mut space = match path {
        Some(p) => {
            let text = fsutil::read_text(p)?;
            toml::from_str(&text).with_context(|| format!("search space {}", p.display()))?
        }
        None => SearchSpace::default(),
    };
    if let Some(t) = trials {
        space.trials = t;
    }
    Ok(space)
}

#[derive(Args)]
pub struct ValidateArgs {
    /// Model directory.
    #[arg(long)]
    model: PathBuf,
    /// Dataset directory.
    #[arg(long)]
    data: PathBuf,
    /// Print exactly one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// Write predicted-vs-true plots (report Fig. 4.4) into this folder
    /// (`predicted_vs_true.png` and `.svg`).
    #[arg(long)]
    plots: Option<PathBuf>,
    /// Score only the rows `train --val-fraction F --split-seed S` held
    /// out of this dataset (refused when the model folder records another
    /// dataset, another split or no held-out part).
    #[arg(long)]
    val_fraction: Option<f64>,
    /// Seed of the --val-fraction split, as given to `train`.
    #[arg(long, default_value_t = 1, requires = "val_fraction")]
    split_seed: u64,
    /// Replace existing plots in --plots.
    #[arg(long, requires = "plots")]
    force: bool,
    #[command(flatten)]
    pub(crate) views: crate::views::ViewsFlag,
}

/// The stem of the plots `validate --plots` writes (`.png`, `.svg`).
const PLOTS_STEM: &str = "predicted_vs_true";

/// Lock the plots folder `dir` and refuse its plots when they exist,
/// unless `force` (the folder's other files are left alone).
fn start_plots(dir: &Path, force: bool) -> Result<tactrace_store::OutputLock> {
    if dir.exists() && !dir.is_dir() {
        return Err(tactrace_store::StoreError::Format {
            path: dir.to_path_buf(),
            reason: "exists and is not a folder (--plots names a folder)".into(),
        }
        .into());
    }
    let lock = tactrace_store::OutputLock::acquire(dir)?;
    for ext in ["png", "svg"] {
        let file = dir.join(format!("{PLOTS_STEM}.{ext}"));
        fsutil::check_output_file(&file, force, "--plots")?;
    }
    Ok(lock)
}

pub fn validate(a: ValidateArgs) -> Result<()> {
    let plots = match &a.plots {
        Some(dir) => {
            Inputs::new()
                .add("--model", &a.model)
                .add("--data", &a.data)
                .check_outside("--plots", dir)?;
            Some((dir, start_plots(dir, a.force)?))
        }
        None => None,
    };
    let mut model = LoadedModel::load(&a.model)?;
    a.views.apply(&mut model)?;
    let data = read_dataset(&a.data)?;
    let held_out = a.val_fraction.map(|f| (f, a.split_seed));
    let v = tactrace_lab::train_image::validate_loaded(&model, &data, &a.data, held_out)?;
    if let Some(w) = v.seen_warning() {
        eprintln!("warning: {w}");
    }
    if v.rows_seen_in_training.is_none() {
        eprintln!(
            "note: {} does not record what the model was trained on (a model folder written \
             before tactrace kept training.json): whether these rows were held out is unknown",
            a.model.display()
        );
    }
    if let Some((dir, _lock)) = &plots {
        std::fs::create_dir_all(dir)
            .map_err(tactrace_store::write_err(dir.as_path()))
            .map_err(LabError::from)?;
        let title = match &model {
            LoadedModel::Pins(m) => {
                let kind = m.for_data(&data, &a.data).map_err(LabError::from)?.kind();
                figures::model_on_data_title(kind, &a.model, &a.data)
            }
            LoadedModel::Image(m) => format!(
                "{} on {}",
                m.model().kind_name(),
                a.data.file_name().unwrap_or_default().to_string_lossy()
            ),
        };
        let stem = dir.join(PLOTS_STEM);
        if !v.shows_edge_pose() {
            figures::predicted_vs_true_targets(&stem, &title, &target_panels(&v))
                .map_err(LabError::from)?;
        } else {
            let predicted = Predicted {
                truth: &v.truth,
                predictions: &v.predictions,
                mae: [v.position_mae_mm, v.angle_mae_deg],
            };
            figures::predicted_vs_true(&stem, &title, &predicted).map_err(LabError::from)?;
        }
    }
    if a.json {
        crate::say!("{}", serde_json::to_string(&v)?);
    } else if v.shows_edge_pose() {
        crate::say!(
            "position MAE {:.3} mm, angle MAE {:.3} deg, {} samples",
            v.position_mae_mm,
            v.angle_mae_deg,
            v.samples
        );
    } else {
        crate::say!("{} samples; mean absolute error per target:", v.samples);
        for t in &v.targets {
            let s = &v.per_target[&t.name];
            let wrapped = if s.circular {
                " (circular, wrapped)"
            } else {
                ""
            };
            crate::say!("  {}: {:.3} {}{wrapped}", t.name, s.mae, s.unit.as_str());
        }
    }
    Ok(())
}

/// One panel a target of `v` for the per-target figure.
fn target_panels(v: &tr::Validation) -> Vec<figures::TargetPanel> {
    v.targets
        .iter()
        .enumerate()
        .map(|(k, t)| figures::TargetPanel {
            name: t.name.clone(),
            unit: t.unit.as_str().to_string(),
            points: v
                .target_truth
                .iter()
                .zip(&v.target_predictions)
                .map(|(tr, p)| (tr[k], p[k]))
                .collect(),
            mae: v.per_target[&t.name].mae,
        })
        .collect()
}

/// `predict --data` of a model of other targets than the edge pose: one
/// CSV row a sample, every target predicted then true.
pub(crate) fn say_target_rows(v: &tr::Validation) -> Result<()> {
    let names: Vec<String> = v
        .targets
        .iter()
        .map(|t| format!("{}_{}", t.name, t.unit.as_str()))
        .collect();
    let truth: Vec<String> = names.iter().map(|n| format!("true_{n}")).collect();
    crate::say!("{},{}", names.join(","), truth.join(","));
    for (p, t) in v.target_predictions.iter().zip(&v.target_truth) {
        let cells: Vec<String> = p.iter().chain(t).map(|x| format!("{x:.4}")).collect();
        crate::say!("{}", cells.join(","));
    }
    Ok(())
}

/// One frame's prediction of every target of a model (`outputs`, in its
/// order), as a CSV header (`NAME_UNIT`) and row; refused when a value
/// is not a number.
pub(crate) fn say_prediction(image: &Path, outputs: &[ModelTarget], values: &[f64]) -> Result<()> {
    let names: Vec<String> = outputs
        .iter()
        .map(|t| format!("{}_{}", t.name, t.unit.as_str()))
        .collect();
    let named: Vec<(&str, f64)> = names
        .iter()
        .map(String::as_str)
        .zip(values.iter().copied())
        .collect();
    tactrace_lab::numbers::require_finite(
        &format!("the model's prediction for {}", image.display()),
        &named,
        "the model is degenerate, or the frame far from its training data",
    )?;
    let cells: Vec<String> = values.iter().map(|v| format!("{v:.4}")).collect();
    crate::say!("{}\n{}", names.join(","), cells.join(","));
    Ok(())
}

#[derive(Args)]
pub struct PredictArgs {
    /// Model directory (from `tactrace train`).
    #[arg(long)]
    pub(crate) model: PathBuf,
    /// One frame (a pin model needs --reference, or --sensor; an image
    /// model reads it as its training frames were made, with the sensor
    /// preprocessing its folder records; --sensor only for a folder that
    /// records none).
    #[arg(long, conflicts_with = "data")]
    pub(crate) image: Option<PathBuf>,
    /// The undeformed frame of the same sensor; default with --sensor: the
    /// model's own rest pins (those its training data was read against).
    #[arg(long, requires = "image")]
    pub(crate) reference: Option<PathBuf>,
    /// Sensor settings (`tactrace sensor inspect`): how to read the frame.
    #[arg(long, requires = "image", conflicts_with = "params")]
    pub(crate) sensor: Option<PathBuf>,
    /// A dataset directory: prints one CSV row per sample.
    #[arg(long)]
    pub(crate) data: Option<PathBuf>,
    /// Blob parameters TOML; default: the real256 preset.
    #[arg(long)]
    pub(crate) params: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) views: crate::views::ViewsFlag,
}

pub fn predict(a: PredictArgs) -> Result<()> {
    let mut loaded = LoadedModel::load(&a.model)?;
    a.views.apply(&mut loaded)?;
    let model = match loaded {
        LoadedModel::Pins(m) => m,
        LoadedModel::Image(m) => return crate::cmd_image::predict(&m, a),
    };
    match (a.image, a.reference, a.data) {
        (Some(image), reference, None) if reference.is_some() || a.sensor.is_some() => {
            let sensor = a.sensor.as_deref().map(SightFile::read).transpose()?;
            let sight = sensor.as_ref().map(SightFile::sight);
            let blob = crate::cmd_data::blob_params(a.params.as_deref(), "real256")?;
            let detector = import_reader::frame_detector(sight.as_ref(), &blob, &image)?;
            let (rest, what) = match &reference {
                Some(r) => (
                    import_reader::frame_pins(&detector, sight.is_some(), r)?,
                    r.clone(),
                ),
                None => (model.reference_pins().to_vec(), a.model.clone()),
            };
            let reader = tactrace_vision::PinReader::new(detector, rest).map_err(LabError::from)?;
            let net = model
                .for_pins(reader.tracker().reference(), &what)
                .map_err(LabError::from)?;
            let (disp, _) = import_reader::read_one(&reader, &image).with_context(|| {
                format!(
                    "{}: not a frame of the sensor whose rest pins are {}'s (or other \
                     settings are needed: --sensor, --params)",
                    image.display(),
                    what.display()
                )
            })?;
            if !tactrace_learn::names_the_edge(net.outputs()) {
                let values = net.predict_targets(&disp).map_err(LabError::from)?;
                return say_prediction(&image, net.outputs(), &values);
            }
            let [r, t] = net.predict(&disp).map_err(LabError::from)?;
            tactrace_lab::numbers::require_finite(
                &format!("the model's prediction for {}", image.display()),
                &[("r", r), ("theta", t)],
                "the model is degenerate, or the frame far from its training data",
            )?;
            crate::say!("r_mm,theta_deg\n{r:.4},{t:.4}");
        }
        (None, None, Some(dir)) => {
            let data = read_dataset(&dir)?;
            let v = tr::validate(&model, &data, &dir)?;
            if !v.shows_edge_pose() {
                // Not the edge task's r and theta: every target, by its
                // column and unit.
                say_target_rows(&v)?;
            } else {
                crate::say!("r_mm,theta_deg,true_r_mm,true_theta_deg");
                for (p, t) in v.predictions.iter().zip(&v.truth) {
                    crate::say!("{:.4},{:.4},{:.4},{:.4}", p[0], p[1], t[0], t[1]);
                }
            }
        }
        _ => {
            return Err(LabError::Config(
                "give either --image FRAME with --reference FRAME or --sensor SENSOR.toml, or --data DIR".into(),
            )
            .into())
        }
    }
    Ok(())
}
