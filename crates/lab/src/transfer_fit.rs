//! `tactrace sim-fit`: the simulator's physical parameters fitted by what
//! a model trained on its taps makes of real frames (docs/sensor-model.md,
//! "Transfer fit").
//!
//! A field fit (eqs. S4-S8 against measured pin fields, `fit_slip`,
//! `fit_joint`) weighs every pixel of misfit alike, but a network trained on
//! simulated taps is hurt only by the misfit along the directions it reads
//! the labels from: a better field fit did not transfer better. Here each
//! candidate parameter set simulates the twin of the given labelled taps,
//! a PDenNN is trained on it exactly as `tactrace train --model pdennn
//! --val-fraction 0.15` does, and the candidate's cost is that model's mean
//! absolute error on the real frames, position / 1 mm + angle / 5 deg
//! (the target ratio). CMA-ES ([`tactrace_optim::Cmaes`], seeded)
//! searches the parameters of [`TRANSFER_PARAMS`] in units of their
//! scales. Only physical and label-convention parameters move: no per-pin
//! correction, so the result is a plain simulated sensor.
use crate::error::{LabError, Result};
use crate::import::import;
use crate::sim_sight::{lay_out, resolve_reference, sim_sight, LayoutReport, SimSight};
use crate::train::{holdout, resolve_config, train_with_validation, validate_net};
use crate::twin::simulate_twin_rows;
use std::path::{Path, PathBuf};
use tactrace_learn::{ModelKind, Preset};
use tactrace_optim::{Cmaes, CmaesConfig, Evaluation, Executor};
use tactrace_sensor::TacTipConfig;
use tactrace_store::collection::Reference;
use tactrace_store::fsutil::{write_atomic, StagedDir};
use tactrace_store::{CsvText, LabelledCollection, TapData};

/// A parameter the transfer fit moves: its rig-file key (under
/// `[sensor]`), getter, setter, search scale (one unit of the search) and
/// least value (a proposal below it is scored, and recorded, at it).
pub struct TransferParam {
    pub key: &'static str,
    pub get: fn(&TacTipConfig) -> f64,
    pub set: fn(&mut TacTipConfig, f64),
    pub scale: f64,
    pub min: f64,
}

macro_rules! param {
    ($table:ident . $field:ident, $scale:expr) => {
        param!($table.$field, $scale, f64::NEG_INFINITY)
    };
    ($table:ident . $field:ident, $scale:expr, $min:expr) => {
        TransferParam {
            key: concat!(stringify!($table), ".", stringify!($field)),
            get: |c| c.$table.$field,
            set: |c, v| c.$table.$field = v,
            scale: $scale,
            min: $min,
        }
    };
}

/// The parameters [`fit_transfer`] searches, with their scales: the label
/// convention's offsets, scales, pivot (eq. L3) and tap depth, the contact mechanics (eqs. S4-S8a),
/// the stick-slip law (eq. S7), the mount's compliance (eq. S4a), the gel
/// flow's screening (eq. S6a) and the pins' jitter (the sensor's noise).
pub const TRANSFER_PARAMS: [TransferParam; 24] = [
    param!(calibration.shear_angle_offset_deg, 3.0),
    param!(calibration.edge_offset_mm, 0.5),
    param!(calibration.angle_offset_deg, 3.0),
    param!(calibration.edge_scale, 0.05, 0.5),
    param!(calibration.angle_scale, 0.05, 0.5),
    param!(calibration.tap_depth_mm, 0.5, 0.5),
    param!(calibration.depth_per_offset, 0.2),
    param!(calibration.pivot_x_mm, 0.5),
    param!(calibration.pivot_y_mm, 0.5),
    param!(mechanics.stick_gain, 0.3, 0.0),
    param!(mechanics.shear_limit_mm, 0.3, 0.01),
    param!(mechanics.slip_load_exponent, 0.3),
    param!(mechanics.slip_profile_mm, 4.0, 1.0),
    param!(mechanics.stick_share, 0.2),
    param!(mechanics.edge_gain_in, 0.3, 0.0),
    param!(mechanics.edge_gain_out, 0.3, 0.0),
    param!(mechanics.flow_core_mm, 0.3, 0.01),
    param!(mechanics.kernel_width_mm, 1.0, 0.5),
    param!(mechanics.layer_thickness_mm, 2.0, 0.5),
    param!(mechanics.lift_gain, 0.1, 0.0),
    param!(mechanics.rim_clamp_mm, 3.0, 1.0),
    param!(mechanics.compliance_mm, 0.2, 0.0),
    param!(mechanics.flow_screening_per_mm, 0.02, 0.0),
    param!(nuisance.pin_jitter_px, 0.2, 0.0),
];

/// What to fit on and how long to search.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct TransferFitConfig {
    /// The real taps (every row is a cost tap): frames, labels, depth and
    /// shear columns, reference frame and blob detector.
    pub collection: LabelledCollection,
    /// The twins' first rendering seed.
    pub render_seed: u64,
    /// CMA-ES generations.
    pub generations: usize,
    /// Candidates per generation (`None`: CMA-ES's default, 4 + 3 ln n).
    pub population: Option<usize>,
    /// Initial step, in units of each parameter's scale.
    pub sigma: f64,
    /// Seed of the search.
    pub seed: u64,
    /// Held-out fraction of each twin when training (as `train
    /// --val-fraction`), split with seed 1 as `train` does by default.
    pub val_fraction: f64,
    /// Degrees of angle error that cost as much as 1 mm of position error
    /// (the targets: 5).
    pub deg_per_mm: f64,
    /// Twins per candidate, rendered with seeds `render_seed`,
    /// `render_seed + 1`, ...: the cost is their mean, so that no candidate
    /// wins by one render's noise.
    pub renders: usize,
}

/// One evaluated candidate.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Candidate {
    pub generation: usize,
    pub values: Vec<f64>,
    /// Position and angle mean absolute error on the real frames (mm, deg);
    /// `None` when the candidate failed (`failure` says why).
    pub mae: Option<[f64; 2]>,
    pub cost: f64,
    /// Why the candidate has no score: not a valid sensor, or a training
    /// on its twin that diverged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

impl Candidate {
    /// `ok` or `failed: REASON` (the table's status column).
    pub fn status(&self) -> String {
        match &self.failure {
            Some(reason) => format!("failed: {reason}"),
            None => "ok".into(),
        }
    }
}

/// What one candidate gave: its errors on the real frames, or why it has
/// none.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TransferScore {
    /// Position and angle mean absolute error (mm, deg).
    pub mae: Option<[f64; 2]>,
    /// Why there is none (not a valid sensor, a diverged training).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

/// The search's outcome: the best sensor, its start, every candidate.
pub struct TransferFit {
    pub start: Candidate,
    pub best: Candidate,
    pub config: TacTipConfig,
    pub candidates: Vec<Candidate>,
    /// Real frames the cost was measured on.
    pub real_frames: usize,
    /// What the import of those frames warned of (a pressed reference, ...).
    pub warnings: Vec<String>,
    /// Both pin layouts' fits to the rest pins (the start is laid out as
    /// the better one when the rest pins were estimated from taps).
    pub layout: LayoutReport,
}

/// Cost of a candidate: position MAE / 1 mm + angle MAE / `deg_per_mm`
/// deg.
pub fn transfer_cost(mae: [f64; 2], deg_per_mm: f64) -> f64 {
    mae[0] + mae[1] / deg_per_mm
}

/// The parameter values of the search's point `unit` (in units of each
/// parameter's scale from `start`), each held at its least value.
pub fn search_point(start: &[f64], unit: &[f64]) -> Vec<f64> {
    TRANSFER_PARAMS
        .iter()
        .zip(start)
        .zip(unit)
        .map(|((p, s), u)| (s + p.scale * u).max(p.min))
        .collect()
}

/// `base` with the search vector `values` (in parameter units) written in.
pub fn with_values(base: &TacTipConfig, values: &[f64]) -> TacTipConfig {
    let mut c = base.clone();
    for (p, v) in TRANSFER_PARAMS.iter().zip(values) {
        (p.set)(&mut c, *v);
    }
    c
}

/// One candidate's scoring as an evaluation: the twins of the labelled
/// taps rendered with the candidate's parameters, a PDenNN trained on
/// each, its mean absolute error on the real frames (none when the
/// candidate is not a valid sensor or a training diverged: a failed
/// candidate, not a failed fit). Pure: the seeds are in the settings.
pub struct TransferTrial {
    context: TransferContext,
    /// The collection, its rest layout estimated when it had none.
    collection: LabelledCollection,
    /// How the simulated taps are read (the collection's rest pins).
    sight: SimSight,
    /// The sensor the candidates' values are set on: the given one, laid
    /// out first like rest pins estimated from taps (an undeformed
    /// frame's pins must fit it as it is, so a pressed frame is refused).
    base: TacTipConfig,
    /// Which pin layout fitted the rest pins better.
    layout: LayoutReport,
    real: TapData,
    /// What the import of the real frames warned of.
    warnings: Vec<String>,
}

/// What a remote worker rebuilds a [`TransferTrial`] from: the fit's
/// settings (the collection's files must be visible to it) and the base
/// sensor.
#[derive(serde::Serialize, serde::Deserialize)]
struct TransferContext {
    config: TransferFitConfig,
    base: TacTipConfig,
}

impl TransferTrial {
    /// The evaluation of `cfg` around `base` (the real frames imported,
    /// the simulator laid out like their rest pins: [`crate::sim_sight`]).
    pub fn new(cfg: &TransferFitConfig, base: &TacTipConfig) -> Result<Self> {
        let (collection, _) = resolve_reference(cfg.collection.clone())?;
        let imported = import(&collection, &|| {})?;
        let sight = sim_sight(&collection)?;
        let (laid_out, layout) = lay_out(base, &sight)?;
        let used = match collection.reference() {
            Reference::Frame(_) => base.clone(),
            _ => laid_out,
        };
        Ok(TransferTrial {
            context: TransferContext {
                config: cfg.clone(),
                base: base.clone(),
            },
            collection,
            sight,
            base: used,
            layout,
            real: imported.data,
            warnings: imported.warnings,
        })
    }

    /// The evaluation a remote worker rebuilds from its context JSON.
    pub fn from_context(context: &str) -> Result<Self> {
        let c: TransferContext = crate::remote::parse_context(Self::NAME, context)?;
        Self::new(&c.config, &c.base)
    }
}

impl Evaluation for TransferTrial {
    const NAME: &'static str = "tactrace.sim_fit.transfer";
    /// The parameter values, in [`TRANSFER_PARAMS`] order.
    type Config = Vec<f64>;
    type Score = TransferScore;
    type Error = LabError;

    fn evaluate(&self, values: &Vec<f64>) -> Result<TransferScore> {
        let failed = |why: String| TransferScore {
            mae: None,
            failure: Some(why),
        };
        let sensor = with_values(&self.base, values);
        if let Err(e) = sensor.validate() {
            return Ok(failed(format!("not a valid sensor: {e}")));
        }
        let twin = (&self.collection, &self.sight);
        match transfer_mae(&self.context.config, twin, &sensor, &self.real) {
            Ok(mae) => Ok(TransferScore {
                mae: Some(mae),
                failure: None,
            }),
            Err(e) if !e.is_bad_input() => Ok(failed(e.to_string())),
            Err(e) => Err(e),
        }
    }

    fn context(&self) -> Option<String> {
        crate::remote::context_json(Self::NAME, &self.context)
    }
}

/// Fit [`TRANSFER_PARAMS`] of `base` (module docs), laid out first like
/// the collection's rest pins when they were estimated from taps
/// ([`TransferTrial::new`]), each generation's candidates scored through
/// `executor`; `progress` is told of every
/// candidate as it is scored, with the best so far (none while every
/// candidate failed). A fit none of whose candidates gave a score is
/// [`LabError::AllFailed`].
pub fn fit_transfer(
    cfg: &TransferFitConfig,
    base: &TacTipConfig,
    executor: &impl Executor,
    progress: &mut dyn FnMut(&Candidate, Option<&Candidate>),
) -> Result<TransferFit> {
    let trial = TransferTrial::new(cfg, base)?;
    let start_values: Vec<f64> = TRANSFER_PARAMS
        .iter()
        .map(|p| (p.get)(&trial.base))
        .collect();
    let candidate = |generation: usize, values: Vec<f64>, score: TransferScore| Candidate {
        generation,
        values,
        mae: score.mae,
        cost: score
            .mae
            .map_or(f64::NAN, |m| transfer_cost(m, cfg.deg_per_mm)),
        failure: score.failure,
    };
    let mut first = executor.run(&trial, std::slice::from_ref(&start_values))?;
    let start = candidate(0, start_values.clone(), first.remove(0));
    let mut best: Option<Candidate> = start.cost.is_finite().then(|| start.clone());
    progress(&start, best.as_ref());
    let mut search = Cmaes::new(&CmaesConfig {
        start: vec![0.0; TRANSFER_PARAMS.len()],
        sigma: cfg.sigma,
        population: cfg.population,
        seed: cfg.seed,
    })?;
    let mut candidates = vec![start.clone()];
    for generation in 1..=cfg.generations {
        let points: Vec<Vec<f64>> = search
            .ask()
            .iter()
            .map(|unit| search_point(&start_values, unit))
            .collect();
        let maes = executor.run(&trial, &points)?;
        let mut costs = Vec::new();
        for (values, mae) in points.into_iter().zip(maes) {
            let c = candidate(generation, values, mae);
            if c.cost.is_finite() && best.as_ref().is_none_or(|b| c.cost < b.cost) {
                best = Some(c.clone());
            }
            progress(&c, best.as_ref());
            costs.push(c.cost);
            candidates.push(c);
        }
        search.tell(&costs)?;
    }
    let Some(best) = best else {
        return Err(all_failed(&candidates));
    };
    Ok(TransferFit {
        config: with_values(&trial.base, &best.values),
        start,
        best,
        candidates,
        real_frames: trial.real.len(),
        warnings: trial.warnings,
        layout: trial.layout,
    })
}

/// The error of a fit none of whose `candidates` gave a score (exit 1).
fn all_failed(candidates: &[Candidate]) -> LabError {
    let last = candidates.iter().rev().find_map(|c| c.failure.as_ref());
    LabError::AllFailed {
        what: "sim-fit candidates".into(),
        tried: candidates.len(),
        reason: format!(
            "the last because {}",
            last.map_or("it gave no number", String::as_str)
        ),
        kept: None,
    }
}

/// Twins of the labels with `sensor`, a PDenNN trained on each as
/// `tactrace train --model pdennn --val-fraction F` does, their mean MAE
/// on `real`.
fn transfer_mae(
    cfg: &TransferFitConfig,
    (collection, sight): (&LabelledCollection, &SimSight),
    sensor: &TacTipConfig,
    real: &TapData,
) -> Result<[f64; 2]> {
    let renders = cfg.renders.max(1);
    let mut sum = [0.0; 2];
    for k in 0..renders {
        let seed = cfg.render_seed + k as u64;
        let twin = simulate_twin_rows(collection, sight, sensor, seed, (None, &|| {}))?.data;
        let (train, val) = holdout(&twin, cfg.val_fraction, 1)?;
        let model_cfg = resolve_config(ModelKind::PDenNN, Preset::Default, None, None)?;
        let (model, _) = train_with_validation(&model_cfg, &train, Some(&val), &mut |_| {})?;
        let v = validate_net(&model, real)?;
        sum[0] += v.position_mae_mm / renders as f64;
        sum[1] += v.angle_mae_deg / renders as f64;
    }
    Ok(sum)
}

/// Write the fit into `out` (appears only when complete; an existing
/// folder only with `force`): `sensor.toml`, a rig file whose `[sensor]`
/// table is the best sensor (for `--config` of `twin`, `collect`,
/// `follow`...); `search.csv`, every candidate; `convergence.{svg,png}`,
/// each generation's best and the best so far; `summary.json`, the
/// configuration, seed, version, start and best.
pub fn write_transfer_fit(
    fit: &TransferFit,
    cfg: &TransferFitConfig,
    out: &Path,
    force: bool,
) -> Result<PathBuf> {
    let stage = StagedDir::new(out, force)?;
    let dir = stage.path();
    let rig = toml::Table::from_iter([(
        "sensor".to_string(),
        toml::Value::try_from(&fit.config).map_err(|e| LabError::Config(e.to_string()))?,
    )]);
    let head = format!(
        "# tactrace {} sim-fit: best of {} candidates, seed {}; real frames {}: position {} mm, angle {} deg\n",
        env!("CARGO_PKG_VERSION"),
        fit.candidates.len(),
        cfg.seed,
        fit.real_frames,
        fmt_mae(&fit.best, 0),
        fmt_mae(&fit.best, 1),
    );
    let body = toml::to_string(&rig).map_err(|e| LabError::Config(e.to_string()))?;
    write_atomic(&dir.join("sensor.toml"), (head + &body).as_bytes())?;
    search_csv(&fit.candidates).write(&dir.join("search.csv"))?;
    let failed: Vec<usize> = (0..fit.candidates.len())
        .filter(|&k| !fit.candidates[k].cost.is_finite())
        .map(|k| k + 1)
        .collect();
    tactrace_report::figures::convergence(
        &dir.join("convergence"),
        ("sim-fit: CMA-ES over the simulator's physics", "candidates"),
        &history(&fit.candidates),
        &failed,
    )?;
    let summary = serde_json::json!({
        "tactrace_version": env!("CARGO_PKG_VERSION"),
        "config": cfg,
        "parameters": TRANSFER_PARAMS.iter().map(|p| p.key).collect::<Vec<_>>(),
        "scales": TRANSFER_PARAMS.iter().map(|p| p.scale).collect::<Vec<_>>(),
        "real_frames": fit.real_frames,
        "start": fit.start,
        "best": fit.best,
    });
    let text =
        serde_json::to_string_pretty(&summary).map_err(|e| LabError::Config(e.to_string()))?;
    write_atomic(&dir.join("summary.json"), text.as_bytes())?;
    Ok(stage.commit()?)
}

/// Per generation: candidates so far, the generation's best cost, the
/// best so far (invalid candidates count as evaluated, never as best).
fn history(candidates: &[Candidate]) -> Vec<tactrace_report::figures::GenerationCost> {
    let mut out: Vec<tactrace_report::figures::GenerationCost> = Vec::new();
    let mut best = f64::INFINITY;
    for (k, c) in candidates.iter().enumerate() {
        let cost = if c.cost.is_finite() {
            c.cost
        } else {
            f64::INFINITY
        };
        best = best.min(cost);
        match out.last_mut() {
            Some(g) if k > 0 && candidates[k - 1].generation == c.generation => {
                g.evaluations = k + 1;
                g.generation_best = g.generation_best.min(cost);
                g.best_so_far = best;
            }
            _ => out.push(tactrace_report::figures::GenerationCost {
                evaluations: k + 1,
                generation_best: cost,
                best_so_far: best,
            }),
        }
    }
    out.retain(|g| g.generation_best.is_finite());
    out
}

fn fmt_mae(c: &Candidate, k: usize) -> String {
    c.mae.map_or("-".into(), |m| format!("{:.3}", m[k]))
}

/// One row per candidate: generation, cost, position and angle MAE, then
/// the parameters by key, then its status (`ok`, `failed: REASON`).
fn search_csv(candidates: &[Candidate]) -> CsvText {
    let mut csv = CsvText::new();
    let head = ["generation", "cost", "position_mae_mm", "angle_mae_deg"];
    csv.row(
        head.into_iter()
            .chain(TRANSFER_PARAMS.iter().map(|p| p.key))
            .chain(["status"]),
    );
    for c in candidates {
        let lead = [
            c.generation.to_string(),
            c.cost.to_string(),
            fmt_mae(c, 0),
            fmt_mae(c, 1),
        ];
        let values = c.values.iter().map(f64::to_string);
        csv.row(lead.into_iter().chain(values).chain([c.status()]));
    }
    csv
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_parameter_key_names_the_field_it_sets() {
        let base = TacTipConfig::default();
        for (k, p) in TRANSFER_PARAMS.iter().enumerate() {
            let mut values: Vec<f64> = TRANSFER_PARAMS.iter().map(|q| (q.get)(&base)).collect();
            values[k] += 0.125;
            let moved = with_values(&base, &values);
            assert_eq!((p.get)(&moved), (p.get)(&base) + 0.125, "{}", p.key);
            let text = toml::to_string(&moved).unwrap();
            let (table, field) = p.key.split_once('.').unwrap();
            let doc: toml::Table = toml::from_str(&text).unwrap();
            let v = doc[table][field].as_float().unwrap();
            assert_eq!(v, (p.get)(&moved), "{}", p.key);
        }
    }

    #[test]
    fn a_search_point_moves_by_scales_and_stops_at_each_least_value() {
        let base = TacTipConfig::default();
        let start: Vec<f64> = TRANSFER_PARAMS.iter().map(|p| (p.get)(&base)).collect();
        let up = search_point(&start, &vec![1.0; start.len()]);
        for ((p, s), v) in TRANSFER_PARAMS.iter().zip(&start).zip(&up) {
            assert_eq!(*v, s + p.scale, "{}", p.key);
        }
        let far_down = search_point(&start, &vec![-1e6; start.len()]);
        let bounded: Vec<_> = TRANSFER_PARAMS
            .iter()
            .zip(&far_down)
            .filter(|(p, _)| p.min.is_finite())
            .collect();
        for (p, v) in &bounded {
            assert_eq!(**v, p.min, "{}", p.key);
        }
        // The least values make a valid sensor, so no candidate is lost.
        let mut lowest = base.clone();
        for (p, v) in bounded {
            (p.set)(&mut lowest, *v);
        }
        lowest
            .validate()
            .expect("the least values are a valid sensor");
    }

    #[test]
    fn cost_weighs_one_mm_as_the_given_degrees() {
        assert_eq!(
            transfer_cost([1.0, 0.0], 5.0),
            transfer_cost([0.0, 5.0], 5.0)
        );
        assert_eq!(transfer_cost([0.5, 2.5], 5.0), 1.0);
        assert_eq!(transfer_cost([0.5, 1.5], 3.0), 1.0);
    }
}
