//! The files of a search: `config.toml` (what was asked, written first),
//! `trials.jsonl` (one whole line per finished trial, flushed: what a
//! resumed search reads back), and at the end `trials.csv`, `best.toml`
//! and `convergence.{png,svg}`.
use super::{SearchSettings, TrialScore};
use crate::error::{LabError, Result};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use tactrace_learn::ModelTarget;
use tactrace_report::figures::{self, GenerationCost};
use tactrace_store::fsutil::partial_path;
use tactrace_store::{write_atomic, StagedDir};

/// One finished trial, a line of `trials.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialRecord {
    /// Index, from 0.
    pub trial: usize,
    /// The settings tried, by name.
    pub settings: Vec<(String, f64)>,
    /// The optimiser's values (a choice's index), written as decimal
    /// strings that parse back to the same bits (serde_json's default
    /// float parsing can be one ulp off, and a resumed search must see
    /// exactly the values the stopped one saw).
    #[serde(with = "exact_floats")]
    pub values: Vec<f64>,
    pub score: TrialScore,
    /// Wall time of its training and scoring (a batch's time shared
    /// among its trials).
    pub seconds: f64,
}

/// `Vec<f64>` as a list of shortest round-trip decimal strings.
mod exact_floats {
    use serde::{de::Error, Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|x| x.to_string()))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let text = Vec::<String>::deserialize(d)?;
        text.iter()
            .map(|t| t.parse::<f64>().map_err(D::Error::custom))
            .collect()
    }
}

const TRIALS: &str = "trials.jsonl";
const CONFIG: &str = "config.toml";

/// `config.toml`: the settings with the version that wrote them.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct ConfigFile {
    tactrace_version: String,
    search: SearchSettings,
}

/// The folder being written (`<out>.partial`) and the trials in it.
pub struct SearchFolder {
    stage: StagedDir,
    trials: Vec<TrialRecord>,
    log: File,
}

impl SearchFolder {
    /// Start `out` afresh, or with `resume` read back the trials of the
    /// search stopped in `<out>.partial` (refused when it was asked
    /// otherwise). A fresh start over a stopped search's trials is refused
    /// unless `force`, so they are never lost by forgetting `--resume`.
    pub fn open(out: &Path, settings: &SearchSettings, force: bool, resume: bool) -> Result<Self> {
        let partial = partial_path(out);
        let stopped = partial.join(TRIALS).is_file();
        if !resume && stopped && !force {
            return Err(LabError::Config(format!(
                "{} holds a stopped search's trials: continue it with --resume, \
                 or start again with --force",
                partial.display()
            )));
        }
        if resume && !stopped {
            return Err(LabError::Config(format!(
                "--resume: no stopped search in {} (no {TRIALS})",
                partial.display()
            )));
        }
        let stage = if resume {
            StagedDir::resume_partial(out, force)?
        } else {
            StagedDir::new_keeping_partial(out, force)?
        };
        let dir = stage.path().to_path_buf();
        let trials = if resume {
            check_same(&dir.join(CONFIG), settings)?;
            read_trials(&dir.join(TRIALS))?
        } else {
            Vec::new()
        };
        let config = ConfigFile {
            tactrace_version: env!("CARGO_PKG_VERSION").into(),
            search: settings.clone(),
        };
        let text = toml::to_string(&config).map_err(|e| LabError::Config(e.to_string()))?;
        write_atomic(&dir.join(CONFIG), text.as_bytes())?;
        // Rewritten whole: a torn last line of a killed run is dropped.
        let mut body = String::new();
        for t in &trials {
            body += &json_line(t)?;
        }
        write_atomic(&dir.join(TRIALS), body.as_bytes())?;
        let path = dir.join(TRIALS);
        let log = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .map_err(tactrace_store::write_err(&path))?;
        Ok(SearchFolder { stage, trials, log })
    }

    /// The trials so far, in order.
    pub fn trials(&self) -> &[TrialRecord] {
        &self.trials
    }

    /// Append a finished trial (one whole line, flushed and synced).
    pub fn append(&mut self, t: &TrialRecord) -> Result<()> {
        let path = self.stage.path().join(TRIALS);
        let line = json_line(t)?;
        self.log
            .write_all(line.as_bytes())
            .and_then(|()| self.log.sync_data())
            .map_err(tactrace_store::write_err(&path))?;
        self.trials.push(t.clone());
        Ok(())
    }

    /// The best finite trial (the first of equals).
    pub fn best(&self) -> Option<usize> {
        self.trials
            .iter()
            .filter(|t| t.score.score.is_finite())
            .min_by(|a, b| {
                a.score
                    .score
                    .total_cmp(&b.score.score)
                    .then(a.trial.cmp(&b.trial))
            })
            .map(|t| t.trial)
    }

    /// Write the table, the best configuration and the figure, and move
    /// the folder into place.
    pub fn finish(
        self,
        settings: &SearchSettings,
        best: usize,
        targets: &[ModelTarget],
    ) -> Result<PathBuf> {
        let dir = self.stage.path();
        write_atomic(&dir.join("trials.csv"), &trials_csv(&self.trials, targets)?)?;
        let t = &self.trials[best];
        let cfg = settings.space.apply(&settings.base, &t.values)?;
        let body = toml::to_string(&cfg).map_err(|e| LabError::Config(e.to_string()))?;
        let text = format!(
            "# tactrace {} search, seed {}: trial {best} of {}, inner validation \
             {} (score {:.4}).\n# Train it with `tactrace train --config best.toml`.\n{body}",
            env!("CARGO_PKG_VERSION"),
            settings.seed,
            self.trials.len(),
            describe_mae(targets, &t.score.val_mae),
            t.score.score
        );
        write_atomic(&dir.join("best.toml"), text.as_bytes())?;
        let title = format!("TPE search of a {}", settings.base.kind_name());
        let failed: Vec<usize> = self
            .trials
            .iter()
            .filter(|t| !t.score.score.is_finite())
            .map(|t| t.trial + 1)
            .collect();
        figures::convergence(
            &dir.join("convergence"),
            (&title, "trials"),
            &convergence(&self.trials),
            &failed,
        )?;
        Ok(self.stage.commit()?)
    }
}

fn json_line(t: &TrialRecord) -> Result<String> {
    let line = serde_json::to_string(t).map_err(|e| LabError::Config(e.to_string()))?;
    Ok(line + "\n")
}

/// A resumed search must be asked what the stopped one was (more trials
/// allowed).
fn check_same(path: &Path, settings: &SearchSettings) -> Result<()> {
    let text = tactrace_store::read_text(path)?;
    let was: ConfigFile = toml::from_str(&text).map_err(|e| LabError::Format {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let mut now = settings.clone();
    now.trials = was.search.trials;
    if now != was.search {
        return Err(LabError::Config(format!(
            "--resume: {} was started with other settings (model, space, seed, data, \
             fraction or batch); resume with the same ones",
            path.display()
        )));
    }
    Ok(())
}

/// The trials of `trials.jsonl`, in order; a last line cut short by a
/// kill is dropped, any other bad line is an error.
fn read_trials(path: &Path) -> Result<Vec<TrialRecord>> {
    let text = tactrace_store::read_text(path)?;
    let complete = text.ends_with('\n');
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        match serde_json::from_str::<TrialRecord>(line) {
            Ok(t) if t.trial == k => out.push(t),
            Ok(t) => {
                return Err(LabError::Format {
                    path: path.to_path_buf(),
                    reason: format!("line {} holds trial {}, not {k}", k + 1, t.trial),
                })
            }
            Err(_) if k + 1 == lines.len() && !complete => break,
            Err(e) => {
                return Err(LabError::Format {
                    path: path.to_path_buf(),
                    reason: format!("line {}: {e}", k + 1),
                })
            }
        }
    }
    Ok(out)
}

/// Every target's error in its unit: `pose_2 0.1234 mm, pose_6 3.2100 deg`
/// (a name that ends in its unit, `r_mm`, without it: `r 0.1234 mm`).
pub fn describe_mae(targets: &[ModelTarget], mae: &[f64]) -> String {
    let parts: Vec<String> = targets
        .iter()
        .zip(mae)
        .map(|(t, m)| {
            let unit = t.unit.as_str();
            let name = t.name.strip_suffix(&format!("_{unit}")).unwrap_or(&t.name);
            format!("{name} {m:.4} {unit}")
        })
        .collect();
    parts.join(", ")
}

/// A target's error column: `mae_NAME_UNIT` (`mae_pose_2_mm`; a name that
/// ends in its unit keeps it once: `mae_r_mm`).
fn mae_column(t: &ModelTarget) -> String {
    let unit = t.unit.as_str();
    if t.name.ends_with(&format!("_{unit}")) {
        format!("mae_{}", t.name)
    } else {
        format!("mae_{}_{unit}", t.name)
    }
}

/// `trials.csv`: one row per trial, its settings by name, every target's
/// inner validation error ([`mae_column`]), the score, the best so far,
/// the time and the status (`ok`, `diverged`, `failed: REASON`).
fn trials_csv(trials: &[TrialRecord], targets: &[ModelTarget]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| LabError::Config(format!("trials.csv: {e}"));
    let mut header = vec!["trial".to_string()];
    if let Some(t) = trials.first() {
        header.extend(t.settings.iter().map(|(n, _)| n.clone()));
    }
    header.extend(targets.iter().map(mae_column));
    header.extend(["score", "best_so_far", "seconds", "status"].map(String::from));
    w.write_record(&header).map_err(csv_err)?;
    let mut best = f64::INFINITY;
    for t in trials {
        best = best.min(t.score.score);
        let mut row = vec![t.trial.to_string()];
        row.extend(t.settings.iter().map(|(_, v)| v.to_string()));
        row.extend(t.score.val_mae.iter().map(f64::to_string));
        row.extend([
            t.score.score.to_string(),
            best.to_string(),
            format!("{:.2}", t.seconds),
            t.score.status(),
        ]);
        w.write_record(&row).map_err(csv_err)?;
    }
    w.into_inner()
        .map_err(|e| LabError::Config(format!("trials.csv: {}", e.error())))
}

/// Each trial's score and the best so far (failed trials left out: the
/// figure marks them apart).
fn convergence(trials: &[TrialRecord]) -> Vec<GenerationCost> {
    let mut best = f64::INFINITY;
    let mut out = Vec::new();
    for t in trials {
        best = best.min(t.score.score);
        if t.score.score.is_finite() {
            out.push(GenerationCost {
                evaluations: t.trial + 1,
                generation_best: t.score.score,
                best_so_far: best,
            });
        }
    }
    out
}
