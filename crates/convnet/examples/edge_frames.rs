//! First figures of the image models on real frames: the shared 127-pin
//! edge set (binarised 256 x 256 frames, targets.csv with pose_2 = r mm and
//! pose_6 = theta deg), frames area-averaged to `--size` px, split by the
//! frame number N (ARCHITECTURE.md invariant 9): fit on N % 5 in {2, 3, 4},
//! choose settings on N % 5 = 1 (scored after every epoch), and only with
//! `--score` the reported part N % 5 = 0, once, at the end.
//!
//! `cargo run --release -p tactrace-convnet --example edge_frames -- \
//!     [--data DIR] [--model conv-dennn|conv-mlp|both] [--size 64] [--seed 0] \
//!     [--config JSON] [--set KEY=VALUE]... [--save DIR] [--load DIR] [--score] [--fit-select]`
//!
//! `--save DIR` writes each trained model to `DIR/<model>.json` and
//! `DIR/<model>.safetensors`; `--load DIR` trains nothing and scores the
//! models saved there, so the reported part is scored once, for the
//! settings adopted on the select part, without training again.
//!
//! `--ensemble DIR,DIR,...` trains nothing: it loads the `--model` saved in
//! each folder (e.g. one a seed) and scores the mean of their predictions;
//! `--tta R` scores the mean prediction over the frame moved by every
//! shift in `-R..=R` px in x and y (edge pixels repeated), for one loaded
//! model or an ensemble.
//!
//! `--fit-select` fits on N % 5 in {1, 2, 3, 4} (the fit and select
//! parts together, for a final fit with settings already chosen on the
//! select part; nothing is scored during training), so `--score` then
//! shows what the larger training set gives.
//!
//! `--augment K` adds K training copies of every fit frame, each jittered
//! at 256 px before area averaging ([`PoseKeepingJitter`]: `--edge-flip Q`,
//! the probability a blob's boundary pixel flips, default 0.1;
//! `--pin-drop P`, the probability a pin is erased, default 0.05;
//! `--max-pin-area A` px, default 80), each copy from a seed of the frame
//! number, the copy and `--augment-seed` (default 0).
//!
//! `--sim DIR` (repeatable) adds a dataset folder's frames and targets
//! (`tactrace twin --frames-size 64` of the fit part's labels with a
//! sensor calibrated on fit taps: simulated frames) to the fit frames;
//! `--sim-only` fits on them alone (the real fit frames left out), still
//! scored on the real select part. `--init DIR` starts from the `--model`
//! saved in DIR (`--save`) and fine-tunes it
//! ([`ConvModel::fine_tune_with`]: its networks and scalings kept, the
//! schedule of `--config` / `--set`). `--picture FILE` with `--sim DIR`
//! writes the first simulated frames beside the real fit frames of the
//! same labels, at the input size, to look at.
//!
//! `--mask-radius R` blacks out, in every frame (real and simulated), the
//! pixels whose centre lies R px (of the input size) or farther from the
//! frame's centre: the skin's rim and the stray blobs in the corners,
//! which the real frames show and the simulator does not draw (29 at
//! 64 px keeps every pin of the 127-pin set).
//!
//! `--config` is a [`ConvConfig`] as JSON (the printed one is a start);
//! `--set` changes one value: epochs, batch_size, chunk_size,
//! learning_rate, final_lr_fraction, weight_decay, shift_augment, input_noise, members,
//! coord_channels (true|false), weight_average (the moving average's
//! decay per step), dense_dropout, channel_dropout, beta, sweeps,
//! activation (sigmoid|tanh|relu), input_centring (global|mean_frame), conv (e.g. 16k5s2,32k3s2), dense
//! (e.g. 256 or 256,64 or none). Prints per epoch the training loss, the
//! select part's mean absolute errors, the wall time and this process's
//! CPU time (user + system, all threads).
#[path = "support/dataset_frames.rs"]
mod dataset_frames;

use std::error::Error;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tactrace_convnet::{
    Activation, ClampedPhase, ConvConfig, ConvModel, ConvSpec, Frames, ModelKind,
    PoseKeepingJitter, Targets,
};

struct Part {
    pixels: Vec<u8>,
    targets: Vec<f64>,
    count: usize,
}

impl Part {
    fn new() -> Self {
        Part {
            pixels: Vec::new(),
            targets: Vec::new(),
            count: 0,
        }
    }

    fn views(&self, size: usize) -> Result<(Frames<'_>, Targets<'_>), Box<dyn Error>> {
        Ok((
            Frames::new(&self.pixels, self.count, size, size)?,
            Targets::new(&self.targets, self.count, 2)?,
        ))
    }
}

/// This process's CPU time (user + system, all threads), seconds, from
/// /proc/self/stat (Linux; clock ticks of 1/100 s).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit_once(')').map_or("", |(_, rest)| rest);
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

/// `src` (`side x side`) area-averaged to `size x size` (an integer factor).
fn downsample(src: &[u8], side: usize, size: usize) -> Result<Vec<u8>, Box<dyn Error>> {
    if size == 0 || !side.is_multiple_of(size) {
        return Err(format!("{side} px frames cannot be area-averaged to {size} px").into());
    }
    let f = side / size;
    let mut out = vec![0u8; size * size];
    for (i, o) in out.iter_mut().enumerate() {
        let (y, x) = (i / size, i % size);
        let mut sum = 0u32;
        for dy in 0..f {
            let row = &src[(y * f + dy) * side + x * f..][..f];
            sum += row.iter().map(|&v| v as u32).sum::<u32>();
        }
        let n = (f * f) as u32;
        *o = ((sum + n / 2) / n) as u8;
    }
    Ok(out)
}

/// Training copies of the fit frames: how many a frame, how, which seed.
struct Augment {
    copies: usize,
    jitter: PoseKeepingJitter,
    seed: u64,
}

/// `--picture FILE`: frame `name` beside one jittered copy (seed 0),
/// each at full size and area-averaged to `size` (shown enlarged), as a
/// PNG, to look at what the network is given.
fn picture(
    dir: &Path,
    name: &str,
    aug: &Augment,
    size: usize,
    out: &Path,
) -> Result<(), Box<dyn Error>> {
    let img = image::open(dir.join("frames").join(name))?.to_luma8();
    let side = img.width() as usize;
    let copy = aug.jitter.apply(img.as_raw(), (side, side), 0);
    let f = side / size;
    let mut sheet = image::GrayImage::new(2 * side as u32, 2 * side as u32);
    for (col, frame) in [img.as_raw().clone(), copy].iter().enumerate() {
        let small = downsample(frame, side, size)?;
        for (i, (&full, y)) in frame.iter().zip(0..).enumerate() {
            let (y, x) = (y / side, i % side);
            let at = (col * side + x) as u32;
            sheet.put_pixel(at, y as u32, image::Luma([full]));
            let grey = small[(y / f) * size + x / f];
            sheet.put_pixel(at, (side + y) as u32, image::Luma([grey]));
        }
    }
    sheet.save(out)?;
    Ok(())
}

/// Black out every pixel of the `size x size` frames `pixels` whose
/// centre is `radius` px or farther from the frame's centre.
fn mask_outside(pixels: &mut [u8], size: usize, radius: f64) {
    let c = size as f64 / 2.0;
    for frame in pixels.chunks_exact_mut(size * size) {
        for (i, p) in frame.iter_mut().enumerate() {
            let (x, y) = ((i % size) as f64 + 0.5 - c, (i / size) as f64 + 0.5 - c);
            if x.hypot(y) >= radius {
                *p = 0;
            }
        }
    }
}

/// `--picture` with `--sim`: the first 8 simulated frames (top row of
/// each pair) above the real fit frame with the nearest labels (r mm,
/// theta deg), at `size` px enlarged 4 times, as a PNG.
fn sim_picture(
    parts: &[Part],
    sim: &dataset_frames::DatasetFrames,
    size: usize,
    out: &Path,
) -> Result<(), Box<dyn Error>> {
    let (zoom, shown) = (4usize, sim.count.min(8));
    let side = size * zoom;
    let mut sheet = image::GrayImage::new((shown * side) as u32, (2 * side) as u32);
    let real: Vec<&Part> = parts[2..5].iter().collect();
    for k in 0..shown {
        let t = &sim.targets[k * 2..k * 2 + 2];
        let mut best = (f64::INFINITY, &real[0].pixels[..0]);
        for p in &real {
            for (i, rt) in p.targets.chunks_exact(2).enumerate() {
                let d = (rt[0] - t[0]).abs() + (rt[1] - t[1]).abs() / 10.0;
                if d < best.0 {
                    best = (d, &p.pixels[i * size * size..(i + 1) * size * size]);
                }
            }
        }
        let simulated = &sim.pixels[k * size * size..(k + 1) * size * size];
        println!(
            "pair {k}: r {:.2} mm, theta {:.1} deg (label distance {:.3})",
            t[0], t[1], best.0
        );
        for (row, frame) in [simulated, best.1].iter().enumerate() {
            for y in 0..side {
                for x in 0..side {
                    let v = frame[(y / zoom) * size + x / zoom];
                    sheet.put_pixel(
                        (k * side + x) as u32,
                        (row * side + y) as u32,
                        image::Luma([v]),
                    );
                }
            }
        }
    }
    sheet.save(out)?;
    Ok(())
}

/// The five parts (index N % 5) of the set in `dir`, then a sixth: the
/// `aug` copies of the frames of the parts in `fit_parts`.
fn load(
    dir: &Path,
    size: usize,
    aug: &Augment,
    fit_parts: &[usize],
) -> Result<Vec<Part>, Box<dyn Error>> {
    let csv = std::fs::read_to_string(dir.join("targets.csv"))?;
    let mut lines = csv.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or("empty targets.csv")?
        .split(',')
        .collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or(format!("targets.csv has no column {name}"))
    };
    let (c_name, c_r, c_t) = (col("image_name")?, col("pose_2")?, col("pose_6")?);
    let mut parts: Vec<Part> = (0..6).map(|_| Part::new()).collect();
    for line in lines.filter(|l| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.split(',').collect();
        let name = cells[c_name];
        let number: usize = name
            .strip_prefix("frame_")
            .and_then(|s| s.split('_').next())
            .and_then(|s| s.parse().ok())
            .ok_or(format!("frame name {name} is not frame_N_0.png"))?;
        let img = image::open(dir.join("frames").join(name))?.to_luma8();
        let (w, h) = img.dimensions();
        if w != h {
            return Err(format!("{name}: {w} x {h} px is not square").into());
        }
        let (r, theta): (f64, f64) = (cells[c_r].trim().parse()?, cells[c_t].trim().parse()?);
        let side = w as usize;
        let add = |part: &mut Part, pixels: &[u8]| -> Result<(), Box<dyn Error>> {
            part.pixels.extend(downsample(pixels, side, size)?);
            part.targets.extend([r, theta]);
            part.count += 1;
            Ok(())
        };
        add(&mut parts[number % 5], img.as_raw())?;
        if fit_parts.contains(&(number % 5)) {
            for copy in 0..aug.copies {
                let seed = aug.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    ^ ((number as u64) << 8 | copy as u64);
                add(
                    &mut parts[5],
                    &aug.jitter.apply(img.as_raw(), (side, side), seed),
                )?;
            }
        }
    }
    Ok(parts)
}

fn parse_conv(v: &str) -> Result<Vec<ConvSpec>, Box<dyn Error>> {
    v.split(',')
        .filter(|s| !s.is_empty() && *s != "none")
        .map(|s| {
            let (c, rest) = s
                .split_once('k')
                .ok_or("conv layer as CkKsS, e.g. 16k5s2")?;
            let (k, st) = rest
                .split_once('s')
                .ok_or("conv layer as CkKsS, e.g. 16k5s2")?;
            Ok(ConvSpec {
                channels: c.parse()?,
                kernel: k.parse()?,
                stride: st.parse()?,
            })
        })
        .collect()
}

fn set(cfg: &mut ConvConfig, kv: &str) -> Result<(), Box<dyn Error>> {
    let (k, v) = kv.split_once('=').ok_or("--set KEY=VALUE")?;
    match k {
        "epochs" => cfg.epochs = v.parse()?,
        "batch_size" => cfg.batch_size = v.parse()?,
        "chunk_size" => cfg.chunk_size = v.parse()?,
        "learning_rate" => cfg.learning_rate = v.parse()?,
        "final_lr_fraction" => cfg.final_lr_fraction = v.parse()?,
        "weight_decay" => cfg.weight_decay = v.parse()?,
        "shift_augment" => cfg.shift_augment = v.parse()?,
        "input_noise" => cfg.input_noise = v.parse()?,
        "members" => cfg.members = v.parse()?,
        "coord_channels" => cfg.coord_channels = v.parse()?,
        "weight_average" => cfg.weight_average = Some(v.parse()?),
        "dense_dropout" => cfg.dense_dropout = v.parse()?,
        "channel_dropout" => cfg.channel_dropout = v.parse()?,
        "beta" => cfg.ep.beta = v.parse()?,
        "sweeps" => {
            cfg.ep.clamped_phase = ClampedPhase::Sweeps {
                iterations: v.parse()?,
            }
        }
        "activation" => cfg.activation = serde_json::from_str::<Activation>(&format!("\"{v}\""))?,
        "conv" => cfg.conv = parse_conv(v)?,
        "input_centring" => cfg.input_centring = serde_json::from_str(&format!("\"{v}\""))?,
        "dense" => {
            cfg.dense = v
                .split(',')
                .filter(|s| !s.is_empty() && *s != "none")
                .map(|s| s.parse())
                .collect::<Result<_, _>>()?
        }
        _ => return Err(format!("unknown --set key {k}").into()),
    }
    Ok(())
}

struct Args {
    data: Option<PathBuf>,
    kinds: Vec<ModelKind>,
    size: usize,
    seed: u64,
    config: Option<String>,
    sets: Vec<String>,
    save: Option<PathBuf>,
    load: Option<PathBuf>,
    score: bool,
    ensemble: Vec<PathBuf>,
    tta: usize,
    fit_select: bool,
    augment: Augment,
    picture: Option<PathBuf>,
    sim: Vec<PathBuf>,
    sim_only: bool,
    init: Option<PathBuf>,
    mask_radius: Option<f64>,
}

fn parse_args() -> Result<Args, Box<dyn Error>> {
    let mut a = Args {
        data: None,
        kinds: vec![ModelKind::ConvDennn, ModelKind::ConvMlp],
        size: 64,
        seed: 0,
        config: None,
        sets: Vec::new(),
        save: None,
        load: None,
        score: false,
        ensemble: Vec::new(),
        tta: 0,
        fit_select: false,
        augment: Augment {
            copies: 0,
            jitter: PoseKeepingJitter {
                edge_flip: 0.1,
                pin_drop: 0.05,
                max_pin_area: 80,
            },
            seed: 0,
        },
        picture: None,
        sim: Vec::new(),
        sim_only: false,
        init: None,
        mask_radius: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = || it.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--data" => a.data = Some(PathBuf::from(value()?)),
            "--model" => {
                a.kinds = match value()?.as_str() {
                    "conv-dennn" => vec![ModelKind::ConvDennn],
                    "conv-mlp" => vec![ModelKind::ConvMlp],
                    "both" => vec![ModelKind::ConvDennn, ModelKind::ConvMlp],
                    other => return Err(format!("unknown model {other}").into()),
                }
            }
            "--size" => a.size = value()?.parse()?,
            "--seed" => a.seed = value()?.parse()?,
            "--config" => a.config = Some(value()?),
            "--set" => a.sets.push(value()?),
            "--save" => a.save = Some(PathBuf::from(value()?)),
            "--load" => a.load = Some(PathBuf::from(value()?)),
            "--score" => a.score = true,
            "--fit-select" => a.fit_select = true,
            "--ensemble" => a.ensemble = value()?.split(',').map(PathBuf::from).collect(),
            "--tta" => a.tta = value()?.parse()?,
            "--picture" => a.picture = Some(PathBuf::from(value()?)),
            "--sim" => a.sim.push(PathBuf::from(value()?)),
            "--sim-only" => a.sim_only = true,
            "--init" => a.init = Some(PathBuf::from(value()?)),
            "--mask-radius" => a.mask_radius = Some(value()?.parse()?),
            "--augment" => a.augment.copies = value()?.parse()?,
            "--augment-seed" => a.augment.seed = value()?.parse()?,
            "--edge-flip" => a.augment.jitter.edge_flip = value()?.parse()?,
            "--pin-drop" => a.augment.jitter.pin_drop = value()?.parse()?,
            "--max-pin-area" => a.augment.jitter.max_pin_area = value()?.parse()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    Ok(a)
}

/// Train `kind` on the fit part, printing every epoch with the select
/// part's errors.
fn train(
    args: &Args,
    kind: ModelKind,
    parts: &[Part],
    fit: &Part,
) -> Result<ConvModel, Box<dyn Error>> {
    let mut cfg = match &args.config {
        Some(json) => serde_json::from_str(json)?,
        None => ConvConfig::new(kind),
    };
    cfg.kind = kind;
    for kv in &args.sets {
        set(&mut cfg, kv)?;
    }
    println!("{} config {}", kind.name(), serde_json::to_string(&cfg)?);
    let (wall, cpu0) = (Instant::now(), cpu_seconds());
    let mut report = |r: &tactrace_convnet::EpochReport| {
        let v = r
            .validation
            .as_ref()
            .map_or(vec![f64::NAN; 2], |v| v.mae.clone());
        println!(
            "{} epoch {:>3} lr {:.2e} loss {:.5} select {:.4} mm {:.3} deg  wall {:.0} s cpu {:.0} s",
            kind.name(),
            r.epoch,
            r.learning_rate,
            r.loss,
            v[0],
            v[1],
            wall.elapsed().as_secs_f64(),
            cpu_seconds() - cpu0
        );
    };
    let (ff, ft) = fit.views(args.size)?;
    let select = match args.fit_select {
        true => None,
        false => Some(parts[1].views(args.size)?),
    };
    let (model, _) = match &args.init {
        Some(dir) => {
            let start = load_model(dir, kind)?;
            start.fine_tune_with(&ff, &ft, &cfg, args.seed, select, &mut report)?
        }
        None => ConvModel::fit_with(&ff, &ft, &cfg, args.seed, select, &mut report)?,
    };
    Ok(model)
}

fn save_model(dir: &Path, kind: ModelKind, model: &ConvModel) -> Result<(), Box<dyn Error>> {
    std::fs::create_dir_all(dir)?;
    let (json, tensors) = model.to_bytes()?;
    std::fs::write(dir.join(format!("{}.json", kind.name())), json)?;
    std::fs::write(dir.join(format!("{}.safetensors", kind.name())), tensors)?;
    Ok(())
}

fn load_model(dir: &Path, kind: ModelKind) -> Result<ConvModel, Box<dyn Error>> {
    let json = std::fs::read_to_string(dir.join(format!("{}.json", kind.name())))?;
    let tensors = std::fs::read(dir.join(format!("{}.safetensors", kind.name())))?;
    let model = ConvModel::from_bytes(&json, &tensors)?;
    println!(
        "{} loaded from {}: {}",
        kind.name(),
        dir.display(),
        serde_json::to_string(model.config())?
    );
    Ok(model)
}

/// `frame` (`size x size`) moved by `(dx, dy)` px, edge pixels repeated.
fn shifted(frame: &[u8], size: usize, (dx, dy): (isize, isize)) -> Vec<u8> {
    let at = |v: usize, d: isize| (v as isize - d).clamp(0, size as isize - 1) as usize;
    (0..size * size)
        .map(|i| frame[at(i / size, dy) * size + at(i % size, dx)])
        .collect()
}

/// The mean prediction of `models` on `part`, each frame also moved by
/// every shift in `-tta..=tta` px; the mean absolute error per target.
fn ensemble_mae(
    models: &[ConvModel],
    part: &Part,
    size: usize,
    tta: usize,
) -> Result<Vec<f64>, Box<dyn Error>> {
    let r = tta as isize;
    let mut sum = vec![0.0; part.targets.len()];
    let mut n = 0.0;
    for dy in -r..=r {
        for dx in -r..=r {
            let pixels: Vec<u8> = part
                .pixels
                .chunks_exact(size * size)
                .flat_map(|f| shifted(f, size, (dx, dy)))
                .collect();
            let frames = Frames::new(&pixels, part.count, size, size)?;
            for m in models {
                for (s, p) in sum.iter_mut().zip(m.predict_batch(&frames)?) {
                    *s += p;
                }
                n += 1.0;
            }
        }
    }
    let mut mae = vec![0.0; 2];
    for (i, (s, t)) in sum.iter().zip(&part.targets).enumerate() {
        mae[i % 2] += (s / n - t).abs() / part.count as f64;
    }
    Ok(mae)
}

/// `--ensemble` / `--tta`: score saved models on the select part (and the
/// score part with `--score`), no training.
fn score_saved(args: &Args, parts: &[Part]) -> Result<(), Box<dyn Error>> {
    let dirs = match (&args.ensemble[..], &args.load) {
        ([], Some(d)) => vec![d.clone()],
        (e, _) => e.to_vec(),
    };
    for &kind in &args.kinds {
        let models = dirs
            .iter()
            .map(|d| load_model(d, kind))
            .collect::<Result<Vec<_>, _>>()?;
        let (wall, cpu0) = (Instant::now(), cpu_seconds());
        let mut which = vec![(1, "select part (N % 5 = 1)")];
        if args.score {
            which.push((0, "SCORE part (N % 5 = 0)"));
        }
        for (i, name) in which {
            let mae = ensemble_mae(&models, &parts[i], args.size, args.tta)?;
            println!(
                "{} ensemble of {}, shifts up to {} px, {name}: {:.4} mm / {:.3} deg; {:.1} s wall, {:.1} s CPU",
                kind.name(),
                models.len(),
                args.tta,
                mae[0],
                mae[1],
                wall.elapsed().as_secs_f64(),
                cpu_seconds() - cpu0
            );
        }
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let args = parse_args()?;
    let dir = match &args.data {
        Some(d) => d.clone(),
        None => tactrace_testdata::real_edge_set().ok_or("no data")?,
    };
    let (wall, cpu) = (Instant::now(), cpu_seconds());
    if let (Some(out), false) = (&args.picture, args.sim.is_empty()) {
        let mut parts = load(&dir, args.size, &args.augment, &[])?;
        let mut sim = dataset_frames::read(&args.sim[0])?;
        if let Some(r) = args.mask_radius {
            parts
                .iter_mut()
                .for_each(|p| mask_outside(&mut p.pixels, args.size, r));
            mask_outside(&mut sim.pixels, args.size, r);
        }
        return sim_picture(&parts, &sim, args.size, out);
    }
    if let Some(out) = &args.picture {
        return picture(&dir, "frame_1002_0.png", &args.augment, args.size, out);
    }
    let first = if args.fit_select { 1 } else { 2 };
    let fit_parts: Vec<usize> = (first..5).collect();
    let j = args.augment.jitter;
    PoseKeepingJitter::new(j.edge_flip, j.pin_drop, j.max_pin_area)?;
    let mut parts = load(&dir, args.size, &args.augment, &fit_parts)?;
    if let Some(r) = args.mask_radius {
        parts
            .iter_mut()
            .for_each(|p| mask_outside(&mut p.pixels, args.size, r));
    }
    let mut fit = Part::new();
    for p in parts[first..].iter().filter(|_| !args.sim_only) {
        fit.pixels.extend(&p.pixels);
        fit.targets.extend(&p.targets);
        fit.count += p.count;
    }
    for d in &args.sim {
        let mut sim = dataset_frames::read(d)?;
        if let Some(r) = args.mask_radius {
            mask_outside(&mut sim.pixels, args.size, r);
        }
        if sim.side != args.size || sim.dim != 2 {
            return Err(format!(
                "{}: frames of {} px and {} targets, not {} px and 2",
                d.display(),
                sim.side,
                sim.dim,
                args.size
            )
            .into());
        }
        println!("simulated frames: {} from {}", sim.count, d.display());
        fit.pixels.extend(&sim.pixels);
        fit.targets.extend(&sim.targets);
        fit.count += sim.count;
    }
    println!(
        "loaded {} frames at {s} x {s} px in {:.1} s (fit {} with {} copies, select {}, score {})",
        parts[..5].iter().map(|p| p.count).sum::<usize>(),
        wall.elapsed().as_secs_f64(),
        fit.count,
        parts[5].count,
        parts[1].count,
        parts[0].count,
        s = args.size
    );
    if args.augment.copies > 0 {
        let (a, j) = (&args.augment, &args.augment.jitter);
        println!(
            "augment: {} copies a fit frame, edge_flip {}, pin_drop {}, max_pin_area {} px, seed {}",
            a.copies, j.edge_flip, j.pin_drop, j.max_pin_area, a.seed
        );
    }
    if !args.ensemble.is_empty() || args.tta > 0 {
        return score_saved(&args, &parts);
    }
    for &kind in &args.kinds {
        let (wall, cpu0) = (Instant::now(), cpu_seconds());
        let model = match &args.load {
            Some(dir) => load_model(dir, kind)?,
            None => {
                let model = train(&args, kind, &parts, &fit)?;
                if let Some(dir) = &args.save {
                    save_model(dir, kind, &model)?;
                }
                model
            }
        };
        let (sf, st) = parts[1].views(args.size)?;
        let s = model.score(&sf, &st)?;
        let select = if args.fit_select {
            "select part (in the fit)"
        } else {
            "select part"
        };
        println!(
            "{} {select} (N % 5 = 1, {} frames): {:.4} mm / {:.3} deg; {:.0} s wall, {:.0} s CPU",
            kind.name(),
            parts[1].count,
            s.mae[0],
            s.mae[1],
            wall.elapsed().as_secs_f64(),
            cpu_seconds() - cpu0
        );
        if args.score {
            let (pf, pt) = parts[0].views(args.size)?;
            let s = model.score(&pf, &pt)?;
            println!(
                "{} SCORE part (N % 5 = 0, {} frames): {:.4} mm / {:.3} deg",
                kind.name(),
                parts[0].count,
                s.mae[0],
                s.mae[1]
            );
        }
    }
    println!(
        "total {:.0} s wall, {:.0} s CPU",
        wall.elapsed().as_secs_f64(),
        cpu_seconds() - cpu
    );
    Ok(())
}
