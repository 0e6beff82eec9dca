//! `follow --replay`: the real-frame world. The arm is simulated; at each
//! tap the tool's true pose against the contour is turned into the labels
//! of a real labelled collection on a straight edge (its label convention,
//! [`LabelConvention`]) and the tap is answered by the collection's frame
//! whose labels are nearest (the scaled label distance of
//! [`tactrace_sensor::FrameBank`]: each label divided by its spread over
//! the bank). The loop sees only that frame, through the same detection,
//! pin order, model and controller as on a real rig; the model's
//! predictions, in the collection's labels, are mapped back into the
//! controller's frame by the same convention.
//!
//! What this world cannot show: the frames are of a straight edge, so the
//! sensor never feels curvature or a corner; a contour's bends reach the
//! loop only as changes of the edge pose between taps.
use crate::error::{LabError, Result};
use crate::follow::{
    follow_on_rig_recorded, perception_for, write_results_with, FollowOutcome, RunExtras,
    RunFolder, SimFollowConfig,
};
use crate::import::{read_rows, LabelColumns, Row};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tactrace_geometry::Contour;
use tactrace_sensor::{
    read_frame, Answer, EdgeLabels, FrameBank, LabelConvention, LabelScales, LabelledFrame,
};
use tactrace_servo::{ReplayRig, StepRecord};
use tactrace_store::{StoredModel, TrainingRecord};
use tactrace_vision::BlobParams;

/// Where the real collection is and which of its frames make the bank
/// (the `[replay]` table of a follow configuration).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReplayWorld {
    /// Folder of the frames.
    pub frames: PathBuf,
    /// CSV of labels, one row per frame.
    pub targets: PathBuf,
    /// The undeformed frame: its pins are the loop's reference.
    pub reference: PathBuf,
    pub image_column: String,
    pub r_column: String,
    pub theta_column: String,
    /// Vertical offset of each tap, mm (`None`: depth does not count).
    pub dz_column: Option<String>,
    /// Keep only the rows whose frame number N (the first number in the
    /// image name) has N % modulus == remainder.
    pub keep: Option<KeepRule>,
    /// Blob detection of the real frames.
    pub blob: BlobParams,
    /// A tap answered by a frame further than this (scaled label
    /// distance) counts as uncovered, and the run says so.
    pub far_distance: f64,
}

impl ReplayWorld {
    /// The Bristol layout of `dir` (frames/, targets.csv,
    /// frames/init_0.png; r = pose_2, theta = pose_6, depth pose_3), every
    /// row, the `real256` blob preset.
    pub fn bristol(dir: &Path) -> Result<Self> {
        Ok(Self {
            frames: dir.join("frames"),
            targets: dir.join("targets.csv"),
            reference: dir.join("frames/init_0.png"),
            image_column: "image_name".into(),
            r_column: "pose_2".into(),
            theta_column: "pose_6".into(),
            dz_column: Some("pose_3".into()),
            keep: None,
            blob: BlobParams::preset("real256")?,
            far_distance: 0.5,
        })
    }
}

/// What `follow --replay DIR` (and Python's `follow(replay=...)`) may set
/// over [`ReplayWorld::bristol`]: each `None` keeps the Bristol layout's.
#[derive(Debug, Clone, Default)]
pub struct ReplayOptions {
    /// The labels CSV (default DIR/targets.csv).
    pub targets: Option<PathBuf>,
    /// The undeformed frame (default DIR/frames/init_0.png).
    pub reference: Option<PathBuf>,
    pub image_column: Option<String>,
    pub r_column: Option<String>,
    pub theta_column: Option<String>,
    /// The depth column; `none` or empty: depth does not count.
    pub dz_column: Option<String>,
    /// `N%M==K` ([`KeepRule::parse`]).
    pub keep: Option<String>,
    /// Blob parameters of the real frames (default: the real256 preset).
    pub blob: Option<BlobParams>,
}

impl ReplayWorld {
    /// The world of the labelled collection `dir` with `options`; refused
    /// when `dir` has no frames folder or labels.
    pub fn with_options(dir: &Path, options: &ReplayOptions) -> Result<Self> {
        let mut w = Self::bristol(dir)?;
        let o = options.clone();
        w.targets = o.targets.unwrap_or(w.targets);
        w.reference = o.reference.unwrap_or(w.reference);
        w.image_column = o.image_column.unwrap_or(w.image_column);
        w.r_column = o.r_column.unwrap_or(w.r_column);
        w.theta_column = o.theta_column.unwrap_or(w.theta_column);
        if let Some(dz) = o.dz_column {
            let dz = dz.trim();
            w.dz_column =
                (!dz.is_empty() && !dz.eq_ignore_ascii_case("none")).then(|| dz.to_string());
        }
        w.keep = o.keep.as_deref().map(KeepRule::parse).transpose()?;
        w.blob = o.blob.unwrap_or(w.blob);
        if !w.frames.is_dir() || !w.targets.is_file() {
            return Err(LabError::Config(format!(
                "--replay {}: not a labelled collection: it needs frames/ and targets.csv \
                 (or --targets); found frames/: {}, labels: {}",
                dir.display(),
                w.frames.is_dir(),
                w.targets.is_file()
            )));
        }
        Ok(w)
    }
}

/// `N % modulus == remainder` on a frame's number.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeepRule {
    pub modulus: u64,
    pub remainder: u64,
}

impl KeepRule {
    /// Parse `N%M==K` (spaces allowed).
    pub fn parse(text: &str) -> Result<Self> {
        let bad = || {
            LabError::Config(format!(
                "--replay-keep `{text}`: expected `N%M==K` with 0 <= K < M (frame number N, \
                 e.g. N%5==0)"
            ))
        };
        let plain: String = text.chars().filter(|c| !c.is_whitespace()).collect();
        let rest = plain.strip_prefix("N%").ok_or_else(bad)?;
        let (m, k) = rest.split_once("==").ok_or_else(bad)?;
        let (modulus, remainder) = (m.parse().map_err(|_| bad())?, k.parse().map_err(|_| bad())?);
        if modulus == 0 || remainder >= modulus {
            return Err(bad());
        }
        Ok(Self { modulus, remainder })
    }

    /// Whether the frame named `image` is kept (a name without a number is not).
    pub fn keeps(&self, image: &str) -> bool {
        frame_number(image).is_some_and(|n| n % self.modulus == self.remainder)
    }
}

/// The first run of digits in a frame's name (`frame_17_0.png` -> 17).
pub fn frame_number(image: &str) -> Option<u64> {
    let start = image.find(|c: char| c.is_ascii_digit())?;
    let digits: String = image[start..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

/// The bank of the world: the kept rows' frames with their labels; every
/// frame file must exist.
pub fn load_bank(world: &ReplayWorld) -> Result<FrameBank> {
    let extra: Vec<&str> = world.dz_column.iter().map(String::as_str).collect();
    let cols = LabelColumns {
        image: &world.image_column,
        r: &world.r_column,
        theta: &world.theta_column,
        extra: &extra,
    };
    let rows: Vec<Row> = read_rows(&world.targets, &cols, None)?
        .into_iter()
        .filter(|r| world.keep.is_none_or(|k| k.keeps(&r.image)))
        .collect();
    if rows.is_empty() {
        return Err(LabError::Format {
            path: world.targets.clone(),
            reason: format!(
                "no labelled row is kept by --replay-keep N%{}=={}",
                world.keep.map_or(0, |k| k.modulus),
                world.keep.map_or(0, |k| k.remainder)
            ),
        });
    }
    let frames: Vec<LabelledFrame> = rows
        .iter()
        .map(|r| LabelledFrame {
            path: world.frames.join(&r.image),
            labels: EdgeLabels {
                r_mm: r.r as f64,
                theta_deg: r.theta as f64,
                dz_mm: r.extra.first().map_or(0.0, |&v| v as f64),
            },
        })
        .collect();
    let missing: Vec<&LabelledFrame> = frames.iter().filter(|f| !f.path.is_file()).collect();
    if let Some(first) = missing.first() {
        return Err(LabError::Format {
            path: world.frames.clone(),
            reason: format!(
                "{} of the {} labelled frames are missing, e.g. {}: give the folder of the \
                 frames the labels name (--replay DIR holds frames/ and targets.csv)",
                missing.len(),
                frames.len(),
                first.path.display()
            ),
        });
    }
    FrameBank::new(frames, world.dz_column.is_some()).map_err(|e| LabError::Format {
        path: world.targets.clone(),
        reason: e.to_string(),
    })
}

/// How far the answered frames were from the poses the loop reached.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayStats {
    /// Frames in the bank.
    pub bank_frames: usize,
    /// Taps answered.
    pub taps: usize,
    /// Distinct frames answered.
    pub distinct_frames: usize,
    /// The metric's scales (label units per unit distance).
    pub scales: LabelScales,
    /// Scaled label distance of the answered frames: mean, 95th
    /// percentile, largest.
    pub distance_mean: f64,
    pub distance_p95: f64,
    pub distance_max: f64,
    /// Mean absolute label differences, mm / deg / mm.
    pub mean_abs_dr_mm: f64,
    pub mean_abs_dtheta_deg: f64,
    pub mean_abs_ddz_mm: f64,
    /// Taps answered by a frame further than `far_distance`.
    pub far_taps: usize,
    pub far_distance: f64,
    /// Bank frames the model was trained on (by image name; `None`: the
    /// model folder does not say which frames it was trained on).
    pub bank_frames_seen_in_training: Option<usize>,
    /// Taps answered by such a frame.
    pub taps_answered_by_training_frames: Option<usize>,
}

impl ReplayStats {
    /// The statistics of `answers` from `bank`.
    pub fn of(answers: &[Answer], bank: &FrameBank, far_distance: f64) -> Self {
        let n = answers.len().max(1) as f64;
        let mut d: Vec<f64> = answers.iter().map(|a| a.distance).collect();
        d.sort_by(f64::total_cmp);
        let p95 = d
            .get(((d.len() as f64 * 0.95).ceil() as usize).saturating_sub(1))
            .copied()
            .unwrap_or(0.0);
        let got = |a: &Answer| bank.frames()[a.frame].labels;
        let mean_abs = |f: &dyn Fn(&EdgeLabels) -> f64| {
            answers
                .iter()
                .map(|a| (f(&a.wanted) - f(&got(a))).abs())
                .sum::<f64>()
                / n
        };
        let mut distinct: Vec<usize> = answers.iter().map(|a| a.frame).collect();
        distinct.sort_unstable();
        distinct.dedup();
        Self {
            bank_frames: bank.frames().len(),
            taps: answers.len(),
            distinct_frames: distinct.len(),
            scales: bank.scales(),
            distance_mean: d.iter().sum::<f64>() / n,
            distance_p95: p95,
            distance_max: d.last().copied().unwrap_or(0.0),
            mean_abs_dr_mm: mean_abs(&|l| l.r_mm),
            mean_abs_dtheta_deg: mean_abs(&|l| l.theta_deg),
            mean_abs_ddz_mm: mean_abs(&|l| l.dz_mm),
            far_taps: answers.iter().filter(|a| a.distance > far_distance).count(),
            far_distance,
            bank_frames_seen_in_training: None,
            taps_answered_by_training_frames: None,
        }
    }

    /// The statistics with the bank frames and answered taps that were
    /// frames the model trained on (`training`, from its folder).
    pub fn with_training(
        mut self,
        training: Option<&TrainingRecord>,
        answers: &[Answer],
        bank: &FrameBank,
    ) -> Self {
        let Some(seen) = training.and_then(TrainingRecord::real_frames_seen) else {
            return self;
        };
        let trained: Vec<bool> = bank
            .frames()
            .iter()
            .map(|f| {
                f.path
                    .file_name()
                    .is_some_and(|n| seen.contains(&*n.to_string_lossy()))
            })
            .collect();
        self.bank_frames_seen_in_training = Some(trained.iter().filter(|&&t| t).count());
        self.taps_answered_by_training_frames =
            Some(answers.iter().filter(|a| trained[a.frame]).count());
        self
    }

    /// One line for the run's summary.
    pub fn summary(&self) -> String {
        format!(
            "label distance of the answered real frames: mean {:.3}, p95 {:.3}, max {:.3} \
             (mean |dr| {:.2} mm, |dtheta| {:.2} deg, |ddz| {:.2} mm; {} distinct of {} frames)",
            self.distance_mean,
            self.distance_p95,
            self.distance_max,
            self.mean_abs_dr_mm,
            self.mean_abs_dtheta_deg,
            self.mean_abs_ddz_mm,
            self.distinct_frames,
            self.bank_frames
        )
    }

    /// The warnings, as one: taps that reached poses the labels do not
    /// cover, and bank frames the model was trained on.
    pub fn warning(&self) -> Option<String> {
        let far = (self.far_taps > 0).then(|| {
            format!(
                "{} of {} taps were answered by a real frame more than {} label spreads from \
                 the pose reached (up to {:.2}): the collection's labels do not cover the \
                 poses this run reached, and those taps say little",
                self.far_taps, self.taps, self.far_distance, self.distance_max
            )
        });
        let seen = self
            .bank_frames_seen_in_training
            .filter(|&k| k > 0)
            .map(|k| {
                format!(
                    "{k} of the bank's {} frames (answering {} of {} taps) are frames the model \
                 was trained on: the run is judged on frames it was fitted to; answer with \
                 held-out frames only (--replay-keep, or --targets listing them)",
                    self.bank_frames,
                    self.taps_answered_by_training_frames.unwrap_or(0),
                    self.taps
                )
            });
        let all: Vec<String> = far.into_iter().chain(seen).collect();
        (!all.is_empty()).then(|| all.join("; "))
    }
}

/// `answers.csv`: every tap's labels (of the pose reached), the frame that
/// answered, its labels and the label distance.
fn write_answers(path: &Path, answers: &[Answer], bank: &FrameBank) -> Result<()> {
    let mut text = String::from(
        "step,r_label_mm,theta_label_deg,dz_label_mm,frame,frame_r_mm,frame_theta_deg,frame_dz_mm,distance\n",
    );
    for (step, a) in answers.iter().enumerate() {
        let f = &bank.frames()[a.frame];
        let name = image_name(&f.path);
        let (w, g) = (a.wanted, f.labels);
        text.push_str(&format!(
            "{step},{:.4},{:.3},{:.4},{name},{:.4},{:.3},{:.4},{:.4}\n",
            w.r_mm, w.theta_deg, w.dz_mm, g.r_mm, g.theta_deg, g.dz_mm, a.distance
        ));
    }
    tactrace_store::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// The distinct frames that answered, in order of first use, for the
/// run's replay page.
struct Answered {
    /// Their files (PNG bytes).
    images: Vec<Vec<u8>>,
    /// Their image names.
    names: Vec<String>,
    /// Each tap's index among them.
    per_step: Vec<usize>,
    /// Each tap's label distance.
    distances: Vec<f64>,
}

fn answered_frames(answers: &[Answer], bank: &FrameBank) -> Result<Answered> {
    let mut slot = std::collections::HashMap::new();
    let mut out = Answered {
        images: Vec::new(),
        names: Vec::new(),
        per_step: Vec::with_capacity(answers.len()),
        distances: answers.iter().map(|a| a.distance).collect(),
    };
    for a in answers {
        let next = slot.len();
        let k = *slot.entry(a.frame).or_insert(next);
        if k == out.images.len() {
            let path = &bank.frames()[a.frame].path;
            out.images
                .push(std::fs::read(path).map_err(tactrace_store::read_err(path))?);
            out.names.push(image_name(path));
        }
        out.per_step.push(k);
    }
    Ok(out)
}

/// A frame's image name: its file name in the collection.
fn image_name(path: &Path) -> String {
    path.file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned())
}

/// The outcome of a run in the real-frame world.
pub struct ReplayOutcome {
    pub run: FollowOutcome,
    pub stats: ReplayStats,
}

/// Follow `shape` (named `name`) in the real-frame world `world` with
/// `model` (trained on the collection's frames, in its pin order and label
/// convention), into the run folder `out` (whose `config.toml` is `cfg`
/// with `world` as its `[replay]` table). The arm, workspace, tap and
/// loop settings are `cfg`'s; the label convention is that of the
/// calibrated sensor `cfg.calibrated_sensor` when given (`--sensor`), else
/// of `cfg.rig.sensor.calibration`, centred ([`LabelConvention::centred`]).
pub fn follow_replay(
    cfg: &SimFollowConfig,
    world: &ReplayWorld,
    model: &StoredModel,
    (name, shape): (&str, &Contour),
    (out, force): (&Path, bool),
    progress: &mut dyn FnMut(&StepRecord),
) -> Result<ReplayOutcome> {
    cfg.follow.validate()?;
    if !(world.far_distance.is_finite() && world.far_distance > 0.0) {
        return Err(LabError::Config("far_distance must be positive".into()));
    }
    let bank = load_bank(world)?;
    let reference = read_frame(&world.reference)?;
    let mut settings = cfg.servo_settings();
    settings.blob = world.blob.clone();
    let calibration = match crate::follow::read_calibrated(cfg)? {
        Some(sensor) => sensor.spec.sensor.calibration,
        None => cfg.rig.sensor.calibration.clone(),
    };
    let convention = LabelConvention::centred(calibration);
    let perception =
        perception_for(&reference, model, &settings)?.with_label_convention(convention.clone());
    let start = crate::follow::reachable_start(cfg, shape)?;
    let mut rig = ReplayRig::new(
        &cfg.rig,
        (bank, convention),
        shape.clone(),
        start,
        cfg.follow.seed,
    )?;
    let config = SimFollowConfig {
        replay: Some(world.clone()),
        ..cfg.clone()
    };
    let run = RunFolder::start(out, force, &config)?;
    let (arm, sensor) = rig.parts();
    let recorded =
        follow_on_rig_recorded(arm, sensor, &perception, &settings, run.path(), progress)?;
    let stats = ReplayStats::of(rig.answers(), rig.bank(), world.far_distance).with_training(
        model.training(),
        rig.answers(),
        rig.bank(),
    );
    write_answers(&run.path().join("answers.csv"), rig.answers(), rig.bank())?;
    let answered = answered_frames(rig.answers(), rig.bank())?;
    let extras = RunExtras {
        frames: Some(tactrace_report::replay_html::StepFrames {
            images: &answered.images,
            names: &answered.names,
            per_step: &answered.per_step,
            distances: &answered.distances,
        }),
        replay: Some(&stats),
        fields: Some(tactrace_report::replay_html::PinFields {
            reference_pins: perception.reference_pins(),
            fields: &recorded.fields,
        }),
    };
    let (metrics, l2_curve) = write_results_with(
        Some((name, shape)),
        &recorded.records,
        &recorded.summary,
        &cfg.follow,
        crate::follow::tactip_diameter_mm(),
        run.path(),
        &extras,
    )?;
    let dir = run.finish()?;
    Ok(ReplayOutcome {
        run: FollowOutcome {
            summary: recorded.summary,
            records: recorded.records,
            metrics,
            l2_curve,
            dir,
        },
        stats,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keep_rules_parse_and_select_by_frame_number() {
        let k = KeepRule::parse(" N % 5 == 1").unwrap();
        assert!(k.keeps("frame_11_0.png") && !k.keeps("frame_10_0.png"));
        assert!(!k.keeps("init.png"));
        for bad in ["N%0==0", "N%5==5", "M%5==0", "N%5=1", ""] {
            assert!(KeepRule::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(frame_number("frame_3762_0.png"), Some(3762));
    }

    fn labels(r: f64, t: f64) -> EdgeLabels {
        EdgeLabels {
            r_mm: r,
            theta_deg: t,
            dz_mm: 0.0,
        }
    }

    #[test]
    fn issue20_bank_frames_the_model_trained_on_are_counted_and_said() {
        let names = ["frame_1_0.png", "frame_2_0.png", "frame_3_0.png"];
        let frames = names
            .iter()
            .zip([labels(-1.0, 0.0), labels(0.0, 5.0), labels(1.0, 10.0)])
            .map(|(n, labels)| LabelledFrame {
                path: Path::new("frames").join(n),
                labels,
            })
            .collect();
        let bank = FrameBank::new(frames, false).unwrap();
        let answer = |frame| Answer {
            wanted: labels(0.0, 0.0),
            frame,
            distance: 0.1,
        };
        let answers = [answer(0), answer(1), answer(1), answer(2)];
        let data: tactrace_store::TapData = tactrace_store::TapData {
            inputs: vec![0.0; 4],
            targets: vec![0.0; 4],
            meta: serde_json::from_value(serde_json::json!({
                "source": "real", "origin": "", "seed": null, "samples": 2, "pins": 1,
                "targets": ["r", "theta"], "frames_with_missing_pins": 0,
                "reference_pins": [[0.0, 0.0]], "settings": null, "tactrace_version": "",
                "images": ["frame_2_0.png", "frame_9_0.png"]
            }))
            .unwrap(),
        };
        let record = TrainingRecord::all_rows(&data, None);
        let s = ReplayStats::of(&answers, &bank, 0.5);
        assert_eq!(s.bank_frames_seen_in_training, None, "unknown");
        assert!(s.warning().is_none());
        let s = s.with_training(Some(&record), &answers, &bank);
        assert_eq!(s.bank_frames_seen_in_training, Some(1));
        assert_eq!(s.taps_answered_by_training_frames, Some(2));
        let w = s.warning().unwrap();
        assert!(w.starts_with("1 of the bank's 3 frames (answering 2 of 4 taps) are frames the model was trained on"), "{w}");
    }

    /// Twenty answers at distances 0.05, 0.10, ..., 1.00 from two frames.
    #[test]
    fn the_statistics_are_those_of_the_answers() {
        let frames = [labels(-1.0, 0.0), labels(1.0, 10.0)]
            .map(|labels| LabelledFrame {
                path: "f.png".into(),
                labels,
            })
            .to_vec();
        let bank = FrameBank::new(frames, false).unwrap();
        let answers: Vec<Answer> = (1..=20)
            .map(|k| Answer {
                wanted: labels(-1.0 + 0.1 * k as f64, 0.0),
                frame: k % 2,
                distance: 0.05 * k as f64,
            })
            .collect();
        let s = ReplayStats::of(&answers, &bank, 0.5);
        assert!((s.distance_mean - 0.525).abs() < 1e-12, "{s:?}");
        assert!((s.distance_p95 - 0.95).abs() < 1e-12, "{s:?}");
        assert!((s.distance_max - 1.0).abs() < 1e-12, "{s:?}");
        assert_eq!((s.taps, s.distinct_frames, s.bank_frames), (20, 2, 2));
        assert_eq!(s.far_taps, 10, "0.55 .. 1.00");
        assert!(s.warning().is_some_and(|w| w.contains("10 of 20 taps")));
        // |dr|: wanted -1 + 0.1 k against -1 (k even) or +1 (k odd).
        let dr: f64 = (1..=20)
            .map(|k| {
                let got = if k % 2 == 0 { -1.0 } else { 1.0 };
                (-1.0 + 0.1 * k as f64 - got).abs()
            })
            .sum::<f64>()
            / 20.0;
        assert!((s.mean_abs_dr_mm - dr).abs() < 1e-12);
        assert!((s.mean_abs_dtheta_deg - 5.0).abs() < 1e-12);
    }
}
