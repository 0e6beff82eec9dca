//! The files of a tuning: `config.toml` and `base.toml` (what was asked),
//! `tuned.toml` (the best controller so far, a follow configuration),
//! `history.csv` (with each generation's failed candidates) and
//! `convergence.{svg,png}` (rewritten every generation),
//! and at the end `held_out.md` / `held_out.json` (the judgement).
use super::{RunScore, TuneConfig};
use crate::error::{LabError, Result};
use crate::follow::SimFollowConfig;
use serde::Serialize;
use std::path::{Path, PathBuf};
use tactrace_control::PbtsConfig;
use tactrace_report::figures::{self, GenerationCost};
use tactrace_store::fsutil::partial_path;
use tactrace_store::{write_atomic, StagedDir};

/// One held-out contour and seed, with the base and the tuned controller.
#[derive(Debug, Clone, Serialize)]
pub struct HeldOutRow {
    pub before: RunScore,
    pub after: RunScore,
}

/// A finished tuning.
#[derive(Debug, Clone)]
pub struct TuneOutcome {
    /// The finished output folder.
    pub dir: PathBuf,
    /// The best controller found (also in `tuned.toml`).
    pub tuned: PbtsConfig,
    /// Training cost of the base controller and of the best.
    pub start_cost: f64,
    pub best_cost: f64,
    pub history: Vec<GenerationCost>,
    pub held_out: Vec<HeldOutRow>,
}

/// `tuned.toml`: a follow configuration holding only the controller.
#[derive(Serialize)]
struct TunedFile<'a> {
    controller: &'a PbtsConfig,
}

/// The output folder being written.
pub(super) struct Outputs {
    stage: StagedDir,
    seed: u64,
}

impl Outputs {
    /// Start `out`; refuse to replace an interrupted tuning's best so far
    /// (`OUT.partial/tuned.toml`) unless `force`.
    pub(super) fn start(
        out: &Path,
        force: bool,
        cfg: &TuneConfig,
        base: &SimFollowConfig,
    ) -> Result<Self> {
        // Locked first: a live tuning's OUT.partial is not an interrupted one.
        let _out = tactrace_store::check_output_dir(out, force)?;
        let kept = partial_path(out).join("tuned.toml");
        if kept.exists() && !force {
            return Err(LabError::Config(format!(
                "{} holds the best settings of an interrupted tuning: use it \
                 (follow --config, or tune --base to search on from it), move it away, \
                 or pass --force to replace it",
                kept.display()
            )));
        }
        let stage = StagedDir::new_keeping_partial(out, force)?;
        let text = tactrace_store::resolved_config_toml(crate::VERSION, cfg)?;
        write_atomic(&stage.path().join("config.toml"), text.as_bytes())?;
        let text = tactrace_store::resolved_config_toml(crate::VERSION, base)?;
        write_atomic(&stage.path().join("base.toml"), text.as_bytes())?;
        Ok(Self {
            stage,
            seed: cfg.seed,
        })
    }

    /// After a generation: the best so far (none while every candidate
    /// failed), the history (with each generation's failed candidates,
    /// `failed`, the start first) and the figure.
    pub(super) fn generation(
        &mut self,
        best: Option<&(PbtsConfig, f64)>,
        history: &[GenerationCost],
        failed: &[usize],
    ) -> Result<()> {
        let dir = self.stage.path();
        if let Some((best, cost)) = best {
            let body = toml::to_string(&TunedFile { controller: best })
                .map_err(|e| LabError::Config(format!("tuned settings: {e}")))?;
            let generations = history.len() - 1;
            let text = format!(
                "# tactrace {} tune, seed {}: the best controller after {generations} \
                 generation(s), training cost {cost:.4}.\n# Use it with `tactrace follow \
                 --config tuned.toml`.\n{body}",
                crate::VERSION,
                self.seed
            );
            write_atomic(&dir.join("tuned.toml"), text.as_bytes())?;
        }
        let mut csv = tactrace_store::CsvText::new();
        csv.row([
            "generation",
            "runs",
            "generation_best",
            "best_so_far",
            "failed",
        ]);
        for (g, (h, f)) in history.iter().zip(failed).enumerate() {
            csv.row([
                g.to_string(),
                h.evaluations.to_string(),
                format!("{:.6}", h.generation_best),
                format!("{:.6}", h.best_so_far),
                f.to_string(),
            ]);
        }
        csv.write(&dir.join("history.csv"))?;
        let scored: Vec<GenerationCost> = history
            .iter()
            .copied()
            .filter(|h| h.generation_best.is_finite())
            .collect();
        let failed_at: Vec<usize> = history
            .iter()
            .zip(failed)
            .filter(|(_, &f)| f > 0)
            .map(|(h, _)| h.evaluations)
            .collect();
        figures::convergence(
            &dir.join("convergence"),
            ("CMA-ES tuning", "simulated runs"),
            &scored,
            &failed_at,
        )?;
        Ok(())
    }

    /// The held-out judgement, then the folder becomes `out`.
    pub(super) fn finish(
        mut self,
        best: &(PbtsConfig, f64),
        history: &[GenerationCost],
        failed: &[usize],
        held_out: Vec<HeldOutRow>,
    ) -> Result<TuneOutcome> {
        self.generation(Some(best), history, failed)?;
        let dir = self.stage.path();
        let json = serde_json::to_string_pretty(&held_out).expect("rows serialise");
        write_atomic(&dir.join("held_out.json"), json.as_bytes())?;
        write_atomic(
            &dir.join("held_out.md"),
            held_out_table(&held_out).as_bytes(),
        )?;
        let dir = self.stage.commit()?;
        Ok(TuneOutcome {
            dir,
            tuned: best.0.clone(),
            start_cost: history[0].best_so_far,
            best_cost: best.1,
            history: history.to_vec(),
            held_out,
        })
    }
}

/// The held-out rows as a Markdown table, base -> tuned, with their means.
pub fn held_out_table(rows: &[HeldOutRow]) -> String {
    let mut s = String::from(
        "| contour | seed | mean L2 (mm) | max track error (mm) | coverage | closed | taps |\n\
         |---|---|---|---|---|---|---|\n",
    );
    let pair = |f: &dyn Fn(&RunScore) -> String, r: &HeldOutRow| {
        format!("{} -> {}", f(&r.before), f(&r.after))
    };
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            r.before.shape,
            r.before.seed,
            pair(&|x| format!("{:.2}", x.metrics.mean_l2_mm), r),
            pair(&|x| format!("{:.2}", x.metrics.max_track_error_mm), r),
            pair(&|x| format!("{:.1} %", 100.0 * x.metrics.coverage), r),
            pair(&|x| x.metrics.closed.to_string(), r),
            pair(&|x| x.metrics.steps.to_string(), r),
        ));
    }
    let n = rows.len().max(1) as f64;
    let mean = |f: &dyn Fn(&RunScore) -> f64, after: bool| {
        rows.iter()
            .map(|r| f(if after { &r.after } else { &r.before }))
            .sum::<f64>()
            / n
    };
    let both = |f: &dyn Fn(&RunScore) -> f64, scale: f64, digits: usize| {
        format!(
            "{:.digits$} -> {:.digits$}",
            scale * mean(f, false),
            scale * mean(f, true)
        )
    };
    s.push_str(&format!(
        "| **mean** | | {} | {} | {} % | | {} |\n",
        both(&|x| x.metrics.mean_l2_mm, 1.0, 2),
        both(&|x| x.metrics.max_track_error_mm, 1.0, 2),
        both(&|x| x.metrics.coverage, 100.0, 1),
        both(&|x| x.metrics.steps as f64, 1.0, 0),
    ));
    s
}
