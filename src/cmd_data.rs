//! Data commands: `collect`, `import`, `sensor render`, `sensor pins`
//! (`sensor inspect` in cmd_inspect.rs).
use crate::inputs::Inputs;
use crate::progress::bar;
use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use tactrace_geometry::ShapeSpec;
use tactrace_lab::collect::{collect as run_collect, collect_calibrated, CollectConfig};
use tactrace_lab::hardware::{collect_hardware as collect_hardware_on, HardwareConfig, StopFlag};
use tactrace_lab::import_request::ImportRequest;
use tactrace_lab::render::{TapPose, TapRenderer};
use tactrace_lab::{import as imp, LabError};
use tactrace_servo::RigConfig;
use tactrace_store::collection::{bristol, CollectionEdits, Reference};
use tactrace_store::frame_file::png_bytes;
use tactrace_store::{dataset, fsutil, load_config, load_shape, LabelledCollection};
use tactrace_vision::BlobParams;

#[derive(Args)]
pub struct CollectArgs {
    /// Built-in shape (disk, flower, trine, teardrop) or a CSV of x,y points (mm).
    #[arg(long, default_value = "disk")]
    shape: String,
    /// Number of taps to collect.
    #[arg(long, default_value_t = 1000)]
    samples: usize,
    /// Seed of the random tap poses and the simulated noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output dataset directory.
    #[arg(long)]
    out: PathBuf,
    /// Keep every tap's frame as PNG under frames/.
    #[arg(long)]
    save_frames: bool,
    /// Also keep every tap's frame as an image for the image models
    /// (conv-dennn, conv-mlp): frames.npy, uint8 N x PX x PX, the rendered
    /// frame area-averaged, as `import --frames-size` writes (simulated
    /// edge collections only).
    #[arg(long, value_name = "PX", conflicts_with = "hardware",
          value_parser = clap::value_parser!(u16).range(4..=1024))]
    frames_size: Option<u16>,
    /// Rig configuration TOML (tables sensor, arm, workspace, tap, blob).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Collect on a real rig (UR5 + TacTip camera) described by this TOML
    /// (docs/hardware.md): its `[start]` is a point of the edge and
    /// `angle_deg` the direction of the edge's outward normal.
    #[arg(long, conflicts_with_all = ["config", "shape"])]
    hardware: Option<PathBuf>,
    /// A calibrated sensor folder (`tactrace calibrate`): collect its
    /// simulated taps, pins in its real reference's order and labels in
    /// its convention (r and theta spread over +-5 mm and +-45 deg of its
    /// labels), so a model trained on them runs on its real frames.
    #[arg(long, conflicts_with = "hardware")]
    sensor: Option<PathBuf>,
    /// Replace an existing output directory.
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    task: crate::cmd_task3d::CollectTaskArgs,
}

/// The simulated rig's configuration: the defaults, then the file.
pub fn rig_config(path: Option<&Path>) -> Result<RigConfig> {
    let rig: RigConfig = load_config(path, "rig configuration")?;
    rig.validate().map_err(tactrace_lab::LabError::from)?;
    Ok(rig)
}

pub fn collect(a: CollectArgs) -> Result<()> {
    a.task.refuse_3d_flags()?;
    if let Some(path) = &a.hardware {
        return collect_hardware(&a, path);
    }
    if a.task.is_3d() {
        if a.frames_size.is_some() {
            return Err(tactrace_lab::LabError::Config(
                "--frames-size keeps the taps of an edge collection (--task edge_2d) only".into(),
            )
            .into());
        }
        let (samples, seed, frames) = (a.samples, a.seed, a.save_frames);
        let out = (a.out.as_path(), a.force);
        return crate::cmd_task3d::collect(
            &a.task,
            (samples, seed, frames),
            a.config.as_deref(),
            out,
        );
    }
    Inputs::new()
        .file_arg("--shape", &a.shape)
        .opt("--config", a.config.as_deref())
        .opt("--sensor", a.sensor.as_deref())
        .check_apart("--out", &a.out)?;
    let spec = ShapeSpec::parse(&a.shape);
    let shape = load_shape(&spec)?;
    let rig = rig_config(a.config.as_deref())?;
    let cfg = CollectConfig {
        samples: a.samples,
        seed: a.seed,
        save_frames: a.save_frames,
        frames_size: a.frames_size.map(usize::from),
        ..CollectConfig::default()
    };
    let sensor = match &a.sensor {
        Some(dir) => Some(tactrace_store::SensorFolder::read(dir)?),
        None => None,
    };
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let pb = bar(a.samples as u64, "collect");
    let tick = |i: usize| pb.set_position(i as u64);
    let got = match &sensor {
        Some(s) => collect_calibrated(&rig, s, &shape, &cfg, &spec.name(), tick)?,
        None => run_collect(&rig, &shape, &cfg, &spec.name(), tick)?,
    };
    pb.finish_and_clear();
    let images = got.images.as_ref();
    let dir = dataset::write_dataset_with(&a.out, &got.data, &got.frames, images, a.force)?;
    eprintln!(
        "collected {} taps on {} into {} ({} with missing pins)",
        got.data.len(),
        spec.name(),
        dir.display(),
        got.data.meta.frames_with_missing_pins
    );
    Ok(())
}

/// `collect --hardware`: the same collection on the real rig.
fn collect_hardware(a: &CollectArgs, path: &Path) -> Result<()> {
    Inputs::new()
        .add("--hardware", path)
        .check_apart("--out", &a.out)?;
    let hw = HardwareConfig::read(path)?;
    let cfg = CollectConfig {
        samples: a.samples,
        seed: a.seed,
        save_frames: a.save_frames,
        ..CollectConfig::default()
    };
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    // SIGINT / SIGTERM stop the arm (stopl) and the collection: exit 130 / 143.
    let stop = StopFlag::on_signals().map_err(LabError::from)?;
    let pb = bar(a.samples as u64, "collect");
    let got = collect_hardware_on(&hw, &cfg, "real rig", &stop, |i| pb.set_position(i as u64))?;
    pb.finish_and_clear();
    let dir = dataset::write_dataset(&a.out, &got.data, &got.frames, a.force)?;
    eprintln!(
        "collected {} taps on the rig into {} ({} with missing pins)",
        got.data.len(),
        dir.display(),
        got.data.meta.frames_with_missing_pins
    );
    Ok(())
}

#[derive(Args)]
pub struct ImportArgs {
    /// Folder of frames.
    #[arg(long)]
    frames: PathBuf,
    #[command(flatten)]
    labels: LabelArgs,
    /// Blob detector parameters (TOML, OpenCV key names); default: the real256 preset.
    #[arg(long, conflicts_with = "sensor")]
    params: Option<PathBuf>,
    /// Sensor settings (`tactrace sensor inspect`): how to read the frames
    /// (grey, crop, dome mask, threshold, resize; the detector).
    #[arg(long)]
    sensor: Option<PathBuf>,
    /// Import only the first N rows.
    #[arg(long)]
    limit: Option<usize>,
    /// Also keep every row's frame as an image for the image models
    /// (conv-dennn, conv-mlp): `frames.npy`, uint8 N x PX x PX, the frame
    /// as the pin detector sees it, area-averaged to PX x PX (e.g. 64);
    /// with --like, the size that dataset's frames have.
    #[arg(long, value_name = "PX", value_parser = clap::value_parser!(u16).range(4..=1024))]
    frames_size: Option<u16>,
    /// Another split of a collection: import --frames and --targets with
    /// the blob detector, reference and targets this dataset was imported
    /// with (its meta.json's settings).
    #[arg(long, value_name = "DATASET", conflicts_with_all = [
        "params", "sensor", "reference", "target_list", "r_column", "theta_column", "image_column"])]
    like: Option<PathBuf>,
    /// Output dataset directory.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing output directory.
    #[arg(long)]
    force: bool,
}

/// A labels CSV, its columns and the reference frame of a labelled
/// collection (`import`, `twin`, `calibrate`, `sim-fit`; the Bristol
/// layout's column names by default).
#[derive(Args)]
pub struct LabelArgs {
    /// CSV of labels, one row per frame.
    #[arg(long)]
    pub targets: PathBuf,
    /// The undeformed frame whose pins define the order (for `twin`,
    /// `calibrate` and `sim-fit` also the simulated sensor's rest layout),
    /// or an imported dataset (DATASET: its rest pins and sensor settings,
    /// when no --sensor). Without it, `import`, `calibrate` and `sim-fit`
    /// estimate the rest layout from the taps (`import` records it in the
    /// dataset).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Column of --targets naming each row's frame file [default: image_name].
    #[arg(long)]
    pub image_column: Option<String>,
    /// Column of --targets with the edge position r, mm (shorthand for
    /// --target COLUMN:mm first) [default: pose_2].
    #[arg(long)]
    pub r_column: Option<String>,
    /// Column of --targets with the edge angle theta, degrees (shorthand
    /// for --target COLUMN:deg second) [default: pose_6].
    #[arg(long)]
    pub theta_column: Option<String>,
    /// A target column as COLUMN:UNIT, optionally followed by :circular
    /// and then by a role, :position or :angle; unit mm or deg
    /// (repeatable, in order; e.g. --target
    /// pose_2:mm --target pose_6:deg:circular); replaces
    /// --r-column/--theta-column. The roles say which targets the servo
    /// loop reads as the edge pose when there are other targets beside
    /// them (--target pose_2:mm:position --target pose_3:mm --target
    /// pose_6:deg:circular:angle).
    #[arg(long = "target", value_name = "COLUMN:UNIT[:circular][:ROLE]",
          conflicts_with_all = ["r_column", "theta_column"])]
    pub target_list: Vec<String>,
}

impl LabelArgs {
    /// The collection of the frames in `frames` these flags describe,
    /// with `edits` (rows, blob detector, tap columns) made.
    pub fn collection(&self, frames: &Path, edits: CollectionEdits) -> Result<LabelledCollection> {
        let edits = self.edits(edits);
        let frame = self.reference.clone().unwrap_or_default();
        let mut base = LabelledCollection::new(frames.to_path_buf(), self.targets.clone(), frame);
        if self.reference.is_none() {
            base = base.with_reference(Reference::Estimate { pins: None });
        }
        Ok(base
            .edited(&edits)
            .map_err(tactrace_store::StoreError::from)?)
    }
}

impl LabelArgs {
    /// `edits` with the label columns these flags give.
    fn edits(&self, edits: CollectionEdits) -> CollectionEdits {
        CollectionEdits {
            image_column: self.image_column.clone(),
            r_column: self.r_column.clone(),
            theta_column: self.theta_column.clone(),
            target_list: self.target_list.clone(),
            ..edits
        }
    }
}

/// Blob parameters from a file, or a named preset.
pub fn blob_params(path: Option<&Path>, preset: &str) -> Result<BlobParams> {
    match path {
        Some(p) => {
            let text = fsutil::read_text(p)?;
            BlobParams::from_toml(&text)
                .map_err(LabError::from)
                .with_context(|| format!("{}: invalid blob parameters", p.display()))
        }
        None => Ok(BlobParams::preset(preset).map_err(LabError::from)?),
    }
}

pub fn import(a: ImportArgs) -> Result<()> {
    Inputs::new()
        .add("--frames", &a.frames)
        .add("--targets", &a.labels.targets)
        .opt("--reference", a.labels.reference.as_deref())
        .opt("--params", a.params.as_deref())
        .opt("--like", a.like.as_deref())
        .opt("--sensor", a.sensor.as_deref())
        .check_apart("--out", &a.out)?;
    let plan = import_request(&a)?.plan()?;
    let _out = fsutil::check_output_dir(&a.out, a.force)?;
    let pb = bar(0, "import");
    let tick = || pb.inc(1);
    let frames_size = match (a.frames_size, &a.like) {
        (Some(px), _) => Some(px as usize),
        (None, Some(dir)) => dataset::read_dataset_frames_info(dir)?.map(|i| i.height),
        (None, None) => None,
    };
    let got = imp::import_with_frames(&plan.collection, frames_size, &tick)?;
    pb.finish_and_clear();
    plan.check(&got.data)?;
    if let Some(e) = &got.estimated_rest {
        eprintln!(
            "no --reference: estimated the rest layout ({} pins) from {} taps, residual {:.3} px \
             (recorded in the dataset)",
            e.pins.len(),
            e.frames,
            e.residual_px
        );
    }
    let dir = dataset::write_dataset_with(&a.out, &got.data, &[], got.images.as_ref(), a.force)?;
    let n = got.data.len();
    if let Some(images) = &got.images {
        eprintln!(
            "kept every frame as a {} x {} px image (frames.npy, from {} x {} px)",
            images.info.height,
            images.info.width,
            images.info.source_size[0],
            images.info.source_size[1]
        );
    }
    let t = got.data.meta.tracking;
    eprintln!(
        "imported {n} frames into {}: fully tracked {} of {} ({:.2}%), {} with missing pins, {} rejected (too few pins)",
        dir.display(),
        t.frames_fully_tracked,
        t.frames_total,
        100.0 * t.frames_fully_tracked as f64 / t.frames_total.max(1) as f64,
        got.frames_with_missing_pins,
        got.rejected.len()
    );
    for (name, why) in got.rejected.iter().take(10) {
        eprintln!("  rejected {name}: {why}");
    }
    for w in &got.warnings {
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// What `import`'s flags ask: the same request Python's `import_dataset`
/// makes (the blob detector `--params` or the real256 preset; the label
/// columns; `--sensor`, `--reference`, `--like`).
fn import_request(a: &ImportArgs) -> Result<ImportRequest> {
    let blob = blob_params(a.params.as_deref(), bristol::BLOB_PRESET)?;
    let l = &a.labels;
    Ok(ImportRequest {
        frames: a.frames.clone(),
        targets: l.targets.clone(),
        reference: l.reference.clone(),
        sensor: a.sensor.clone(),
        like: a.like.clone(),
        edits: l.edits(CollectionEdits {
            limit: a.limit,
            blob: Some(blob),
            ..CollectionEdits::default()
        }),
    })
}

/// `sensor render --sensor`: one tap of a calibrated sensor on a straight
/// edge at the labels `(r, theta, dz)` of its own convention, into `out`
/// (replaced only when `force`).
fn render_calibrated(
    dir: &Path,
    (r, theta, dz): (f64, f64, f64),
    (out, force): (&Path, bool),
) -> Result<()> {
    let sensor = tactrace_store::SensorFolder::read(dir)?;
    let renderer = TapRenderer::calibrated(&sensor)?;
    let frame = renderer.render(&TapPose {
        r_mm: r,
        theta_deg: theta,
        depth: Some(dz),
        ..TapPose::default()
    })?;
    fsutil::write_output_file(out, &png_bytes(&frame, "frame")?, force, "--out")?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

#[derive(Subcommand)]
pub enum SensorCommand {
    /// Inspect an unknown TacTip's frames: propose how to read them (grey,
    /// crop, dome mask, threshold, detector), its pin count and layout
    /// kind, and write them as a sensor file for `--sensor`.
    Inspect(crate::cmd_inspect::InspectArgs),
    /// Preprocess one camera frame as a sensor file says (grey, crop, dome
    /// mask, threshold, resize) into a PNG: the frame its detector sees.
    Preprocess(crate::cmd_inspect::PreprocessArgs),
    /// Render one simulated tap as a PNG (r, theta relative to the edge).
    Render {
        /// Built-in shape (disk, flower, trine, teardrop) or a CSV of x,y points (mm).
        #[arg(long, default_value = "disk")]
        shape: String,
        /// Edge position, mm (positive: sensor centre outside the object).
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
        r: f64,
        /// Sensor angle relative to the edge, degrees.
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
        theta: f64,
        /// Indentation depth, mm, from 0 to the contact model's deepest
        /// (`mechanics.max_depth_mm`, 8 mm by default); default: the rig's
        /// nominal tap, 6.25 mm (docs/sensor-model.md).
        #[arg(long, allow_hyphen_values = true)]
        depth: Option<f64>,
        /// Arc length of the edge point, mm.
        #[arg(long, default_value_t = 0.0)]
        arc: f64,
        /// Output PNG file.
        #[arg(long)]
        out: PathBuf,
        /// Replace an existing --out file.
        #[arg(long)]
        force: bool,
        /// Rig configuration TOML (its `sensor` table is the TacTip rendered).
        #[arg(long)]
        config: Option<PathBuf>,
        /// A calibrated sensor folder (`tactrace calibrate`): render its tap
        /// on a straight edge, --r and --theta in its own label convention
        /// (the labels it was calibrated with), --depth as its vertical
        /// offset label (default 0), in its reference frame's layout.
        #[arg(long, conflicts_with_all = ["config", "shape", "arc"])]
        sensor: Option<PathBuf>,
    },
    /// Detect the pins of a frame; prints CSV `x,y,size` (px, size = diameter)
    /// and warns on standard error when the count is not the one expected.
    Pins {
        /// The frame (PNG or any 8-bit image).
        image: PathBuf,
        /// Blob parameters TOML (OpenCV key names).
        #[arg(long)]
        params: Option<PathBuf>,
        /// Preset when no --params: opencv, report, real256, sim.
        #[arg(long, default_value = "real256")]
        preset: String,
        /// Number of pins the sensor has (0: no check).
        #[arg(long, default_value_t = 127)]
        expect: usize,
        /// A count other than --expect is an error (exit code 2), not a warning.
        #[arg(long)]
        strict: bool,
    },
}

pub fn sensor(c: SensorCommand) -> Result<()> {
    match c {
        SensorCommand::Inspect(a) => crate::cmd_inspect::inspect(a),
        SensorCommand::Preprocess(a) => crate::cmd_inspect::preprocess(a),
        SensorCommand::Render {
            shape,
            r,
            theta,
            depth,
            arc,
            out,
            force,
            config,
            sensor,
        } => {
            Inputs::new()
                .file_arg("--shape", &shape)
                .opt("--config", config.as_deref())
                .opt("--sensor", sensor.as_deref())
                .check_outside("--out", &out)?;
            fsutil::check_output_file(&out, force, "--out")?;
            if let Some(dir) = sensor {
                let labels = (r, theta, depth.unwrap_or(0.0));
                return render_calibrated(&dir, labels, (&out, force));
            }
            let contour = load_shape(&ShapeSpec::parse(&shape))?;
            let rig = rig_config(config.as_deref())?;
            let frame = TapRenderer::simulated(&rig, contour)?.render(&TapPose {
                r_mm: r,
                theta_deg: theta,
                depth,
                arc_mm: arc,
                shear: None,
            })?;
            fsutil::write_output_file(&out, &png_bytes(&frame, "frame")?, force, "--out")?;
            eprintln!("wrote {}", out.display());
            Ok(())
        }
        SensorCommand::Pins {
            image,
            params,
            preset,
            expect,
            strict,
        } => {
            let blob = blob_params(params.as_deref(), &preset)?;
            let frame = tactrace_sensor::read_frame(&image).map_err(LabError::from)?;
            let kps = tactrace_vision::detect_blobs(&frame, &blob);
            crate::say!("x,y,size");
            for k in &kps {
                crate::say!("{:.3},{:.3},{:.3}", k.x, k.y, k.size);
            }
            eprintln!("{} pins", kps.len());
            if expect == 0 || kps.len() == expect {
                return Ok(());
            }
            let why = format!(
                "found {} blobs where the sensor has {expect} pins: is it a frame of this \
                 sensor, seen with the right blob parameters (--preset, --params)? \
                 (--expect N sets the count, 0 skips the check)",
                kps.len()
            );
            if strict {
                return Err(LabError::Format {
                    path: image,
                    reason: why,
                }
                .into());
            }
            eprintln!("warning: {}: {why}", image.display());
            Ok(())
        }
    }
}
