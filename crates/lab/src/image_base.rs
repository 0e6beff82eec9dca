//! `train` of a residual image model (`input = "pin_model_and_pixels"`,
//! docs/learning.md, "The residual on a pin model"): the `[base]` table of
//! its configuration, the pin model fitted on every training row (stored
//! in the model's `base/`), and the training rows' base predictions made
//! out of fold: the rows dealt into `folds` folds by a seeded shuffle, each
//! fold's predictions from a pin model fitted on the other folds, so the
//! network learns its corrections against a base as good as it is on taps
//! it has not seen. With `fit_on = "first_dataset"` (`train --train real
//! --train sim`) only the first dataset's rows fit the pin models and are
//! dealt into the folds; every other row's base prediction comes from the
//! pin model fitted on all of those rows, which never saw it.
use crate::error::{LabError, Result};
use crate::train::{check_trainable, data_targets, resolve_config, train};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use tactrace_convnet::ConvConfig;
use tactrace_learn::{ModelConfig, ModelKind, PoseModel, Preset};
use tactrace_store::{BaseFolds, TapData};

/// Most folds.
const MAX_FOLDS: usize = 50;

/// Added to the training seed for the deal of the rows into folds.
const FOLD_STREAM: u64 = 0x6a09_e667_f3bc_c909;

/// The `[base]` table of a residual model's configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaseSettings {
    /// The pin model: "pdennn" (default), "pcadennn", "disdennn" or
    /// "mlp", with its default settings.
    #[serde(default = "pdennn")]
    pub model: String,
    /// Folds of the training rows for their out-of-fold base predictions
    /// (2 ..= 50; default 5).
    #[serde(default = "five")]
    pub folds: usize,
    /// Keys of the pin model's configuration over its kind's defaults, as
    /// `train --config` takes them (`[base.settings]`; none by default).
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub settings: toml::Table,
    /// The training rows the pin models are fitted on (`fit_on`; every
    /// row by default, and then left out).
    #[serde(default, skip_serializing_if = "BaseRows::is_all")]
    pub fit_on: BaseRows,
    /// The folder of a residual model whose base (pin model, folds and
    /// out-of-fold predictions) is taken instead of fitted again, when
    /// it is this table's base on the same training rows
    /// (crate::image_base_reuse); none by default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<String>,
}

/// Which training rows fit a residual model's pin models (`[base]
/// fit_on`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BaseRows {
    /// Every training row, of every dataset given (the default).
    #[default]
    All,
    /// The rows of the first dataset given (`train --train real --train
    /// sim`: the real taps); the other rows' base predictions from the
    /// pin model fitted on those rows.
    FirstDataset,
}

impl BaseRows {
    fn is_all(&self) -> bool {
        *self == BaseRows::All
    }

    /// The rows that fit the pin models, given whether each row is of the
    /// first dataset (`in_first`); refused when that leaves no row, or no
    /// other row for `FirstDataset` to predict.
    pub fn rows(self, in_first: &[bool]) -> Result<Vec<usize>> {
        let n = in_first.len();
        let rows: Vec<usize> = match self {
            BaseRows::All => (0..n).collect(),
            BaseRows::FirstDataset => (0..n).filter(|&r| in_first[r]).collect(),
        };
        if self == BaseRows::FirstDataset && (rows.is_empty() || rows.len() == n) {
            return Err(LabError::Config(format!(
                "[base] fit_on = \"first_dataset\": {} of the {n} training rows are of the \
                 first dataset; it takes two datasets (train --train A --train B), both with \
                 training rows",
                rows.len()
            )));
        }
        Ok(rows)
    }
}

fn pdennn() -> String {
    "pdennn".into()
}

fn five() -> usize {
    5
}

impl Default for BaseSettings {
    fn default() -> Self {
        BaseSettings {
            model: pdennn(),
            folds: five(),
            settings: toml::Table::new(),
            fit_on: BaseRows::All,
            from: None,
        }
    }
}

impl BaseSettings {
    /// The pin model's kind, refused when unknown.
    pub fn kind(&self) -> Result<ModelKind> {
        Ok(match self.model.as_str() {
            "pdennn" => ModelKind::PDenNN,
            "pcadennn" => ModelKind::PcaDenNN,
            "disdennn" => ModelKind::DisDenNN,
            "mlp" => ModelKind::Mlp,
            other => {
                return Err(LabError::Config(format!(
                    "[base] model = \"{other}\": a pin model (pdennn, pcadennn, disdennn, mlp)"
                )))
            }
        })
    }

    /// The pin model's configuration (its kind's defaults, then
    /// `settings`), checked with the folds.
    pub fn config(&self) -> Result<ModelConfig> {
        if !(2..=MAX_FOLDS).contains(&self.folds) {
            return Err(LabError::Config(format!(
                "[base] folds = {}: not in 2..={MAX_FOLDS}",
                self.folds
            )));
        }
        let text = toml::to_string(&self.settings).expect("a table serialises");
        resolve_config(self.kind()?, Preset::Default, Some(&text), None)
    }
}

/// The `[base]` table of the configuration text `text`, split from the
/// rest (returned as text for the image model's own keys): the base
/// settings of a residual model (`cfg_reads_base`; the defaults when the
/// table is absent), refused for any other model.
pub fn split_base_table(text: &str) -> Result<(String, Option<BaseSettings>)> {
    let mut table = tactrace_store::parse_toml(text, "model config")?;
    let base = match table.remove("base") {
        Some(v) => Some(
            v.try_into::<BaseSettings>()
                .map_err(|e| LabError::Config(format!("[base]: {}", e.to_string().trim_end())))?,
        ),
        None => None,
    };
    let rest = toml::to_string(&table).expect("a table serialises");
    Ok((rest, base))
}

/// The base settings of `cfg` given its file's `[base]` table `given`:
/// the table (or its defaults) for a residual model, `None` for another
/// model, which refuses a `[base]` table.
pub fn base_settings(
    cfg: &ConvConfig,
    given: Option<BaseSettings>,
) -> Result<Option<BaseSettings>> {
    match (cfg.input.reads_base(), given) {
        (true, given) => {
            let settings = given.unwrap_or_default();
            settings.config()?;
            Ok(Some(settings))
        }
        (false, None) => Ok(None),
        (false, Some(_)) => Err(LabError::Config(
            "[base] is read by input = \"pin_model_and_pixels\" only".into(),
        )),
    }
}

/// Each of `n` rows' fold, `0..folds`: a shuffle of the rows from `seed`
/// dealt round-robin, so the folds differ in size by one at most.
pub fn deal_folds(n: usize, folds: usize, seed: u64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(
        seed.wrapping_add(FOLD_STREAM),
    ));
    let mut fold = vec![0; n];
    for (p, &r) in order.iter().enumerate() {
        fold[r] = p % folds.max(1);
    }
    fold
}

/// The rows that fit the pin model of fold `f`: those dealt into another
/// of the `folds` folds (a row marked `folds`, fitting no pin model, is
/// never one).
pub fn rows_outside(fold_of_row: &[usize], folds: usize, f: usize) -> Vec<usize> {
    (0..fold_of_row.len())
        .filter(|&r| fold_of_row[r] != f && fold_of_row[r] < folds)
        .collect()
}

/// The pin model of `settings` fitted on the rows of `data` that
/// `settings.fit_on` names (all of them, or those with `in_first[r]`),
/// and each row's out-of-fold prediction (`rows x T`, targets' order and
/// units): a fitting row's from the pin model of the other folds, any
/// other row's from the whole pin model; with the record of the deal
/// (`settings`, `seed`; the other rows' fold is `folds`). Every copy of a
/// tap (a twin's renders) is dealt into one fold, so no fold's prediction
/// comes from a pin model that saw its tap; with no repeated tap the deal
/// is of rows.
pub fn fit_base(
    settings: &BaseSettings,
    data: &TapData,
    seed: u64,
    in_first: &[bool],
) -> Result<(PoseModel, Vec<f64>, BaseFolds)> {
    assert_eq!(in_first.len(), data.len(), "one flag a row");
    let cfg = settings.config()?;
    let fitting = settings.fit_on.rows(in_first)?;
    let whole = data.subset(&fitting);
    check_trainable(&cfg, &whole, 0)?;
    let t = data_targets(data)?.len();
    let mut fold_of_row = vec![settings.folds; data.len()];
    let by_tap = tactrace_store::tap_split::fold_by_tap;
    let (deal, _) = by_tap(data, &fitting, |n| deal_folds(n, settings.folds, seed));
    for (&r, &f) in fitting.iter().zip(&deal) {
        fold_of_row[r] = f;
    }
    let mut predictions = vec![0.0; data.len() * t];
    let mut predict = |model: &PoseModel, fold: usize| -> Result<()> {
        let d = data.dim();
        for r in (0..data.len()).filter(|&r| fold_of_row[r] == fold) {
            let values = model.predict_targets(&data.inputs[r * d..(r + 1) * d])?;
            predictions[r * t..(r + 1) * t].copy_from_slice(&values);
        }
        Ok(())
    };
    for f in 0..settings.folds {
        let fit_rows = rows_outside(&fold_of_row, settings.folds, f);
        let part = data.subset(&fit_rows);
        check_trainable(&cfg, &part, fitting.len() - fit_rows.len())?;
        let (model, _) = train(&cfg, &part, &mut |_| ())?;
        predict(&model, f)?;
    }
    let (model, _) = train(&cfg, &whole, &mut |_| ())?;
    predict(&model, settings.folds)?;
    let record = BaseFolds {
        model: settings.model.clone(),
        folds: settings.folds,
        seed,
        fold_of_row,
        first_dataset_only: settings.fit_on == BaseRows::FirstDataset,
        predictions: predictions.clone(),
        reused_from: None,
    };
    Ok((model, predictions, record))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_data::edge_data;

    /// `n` rows of 4 pin values (two pins) whose targets are linear in
    /// them, with a little seeded scatter.
    fn data(n: usize) -> TapData {
        let inputs: Vec<f32> = (0..4 * n)
            .map(|i| ((i * 7919) % 101) as f32 / 50.0 - 1.0)
            .collect();
        let targets = inputs
            .chunks_exact(4)
            .flat_map(|p| [p[0] - 0.5 * p[1], 10.0 * p[2] + 3.0 * p[3]])
            .collect();
        edge_data(inputs, targets, &[[0.0, 0.0], [5.0, 0.0]])
    }

    fn quick() -> BaseSettings {
        let settings: toml::Table = toml::from_str("epochs = 15").unwrap();
        BaseSettings {
            model: "disdennn".into(),
            folds: 3,
            settings,
            fit_on: BaseRows::All,
            from: None,
        }
    }

    #[test]
    fn the_folds_are_seeded_and_even() {
        let a = deal_folds(23, 5, 7);
        assert_eq!(a, deal_folds(23, 5, 7));
        assert_ne!(a, deal_folds(23, 5, 8));
        let sizes: Vec<usize> = (0..5)
            .map(|f| a.iter().filter(|&&k| k == f).count())
            .collect();
        assert!(sizes.iter().all(|&s| s == 4 || s == 5), "{sizes:?}");
        for (f, size) in sizes.iter().enumerate() {
            assert!(rows_outside(&a, 5, f).iter().all(|&r| a[r] != f));
            assert_eq!(rows_outside(&a, 5, f).len(), 23 - size);
        }
    }

    /// A row's out-of-fold prediction does not move when that row's own
    /// target is spoilt (no pin model that predicts it saw it), while the
    /// rows of the other folds, whose pin models did see it, move.
    #[test]
    fn out_of_fold_predictions_never_see_their_own_rows() {
        let clean = data(45);
        let (_, before, folds) = fit_base(&quick(), &clean, 3, &[true; 45]).unwrap();
        assert_eq!(folds.fold_of_row.len(), 45);
        assert_eq!((folds.folds, folds.seed), (3, 3));
        let spoilt_row = 10;
        let mut spoilt = clean.clone();
        spoilt.targets[2 * spoilt_row] += 50.0;
        let (_, after, _) = fit_base(&quick(), &spoilt, 3, &[true; 45]).unwrap();
        let own = folds.fold_of_row[spoilt_row];
        for r in 0..45 {
            let moved = (before[2 * r] - after[2 * r]).abs();
            if folds.fold_of_row[r] == own {
                assert_eq!(moved, 0.0, "row {r}, in the spoilt row's fold, moved");
            } else {
                assert!(moved > 1e-4, "row {r} of another fold did not move");
            }
        }
    }

    /// An ensemble base (the 331 surface's recipe) keeps its members,
    /// and its out-of-fold predictions still never see their own rows.
    #[test]
    fn an_ensemble_base_keeps_its_members_and_its_folds_apart() {
        let mut settings = quick();
        settings
            .settings
            .insert("ensemble".into(), toml::Value::Integer(2));
        let clean = data(36);
        let (model, before, folds) = fit_base(&settings, &clean, 5, &[true; 36]).unwrap();
        assert_eq!(model.ensemble(), 2);
        let mut spoilt = clean.clone();
        spoilt.targets[2 * 7] += 50.0;
        let (_, after, _) = fit_base(&settings, &spoilt, 5, &[true; 36]).unwrap();
        moved_outside_its_fold_only(&before, &after, &folds.fold_of_row, 7);
    }

    /// With `fit_on = "first_dataset"` the later rows fit nothing: a
    /// spoilt target of one of them moves no prediction at all, while a
    /// spoilt first-dataset row moves the other folds and the later rows
    /// (predicted by the whole pin model), never its own fold.
    #[test]
    fn a_base_of_the_first_dataset_never_sees_the_later_rows() {
        let mut settings = quick();
        settings.fit_on = BaseRows::FirstDataset;
        let in_first: Vec<bool> = (0..45).map(|r| r % 3 != 2).collect();
        let clean = data(45);
        let (_, before, folds) = fit_base(&settings, &clean, 3, &in_first).unwrap();
        assert!(folds.first_dataset_only);
        for (r, (&fold, &first)) in folds.fold_of_row.iter().zip(&in_first).enumerate() {
            assert_eq!(fold == 3, !first, "row {r}");
        }
        let mut later = clean.clone();
        later.targets[2 * 5] += 50.0;
        let (_, after, _) = fit_base(&settings, &later, 3, &in_first).unwrap();
        assert_eq!(before, after, "a later row's target moved a prediction");
        let mut first = clean.clone();
        first.targets[2 * 4] += 50.0;
        let (_, after, _) = fit_base(&settings, &first, 3, &in_first).unwrap();
        moved_outside_its_fold_only(&before, &after, &folds.fold_of_row, 4);
    }

    /// Panics unless, with row `spoilt`'s target spoilt, exactly the rows
    /// outside its fold moved their first predicted target (two a row).
    fn moved_outside_its_fold_only(
        before: &[f64],
        after: &[f64],
        fold_of_row: &[usize],
        spoilt: usize,
    ) {
        let own = fold_of_row[spoilt];
        for (r, &fold) in fold_of_row.iter().enumerate() {
            let moved = (before[2 * r] - after[2 * r]).abs();
            assert!((fold == own) == (moved == 0.0), "row {r}: moved {moved}");
        }
    }

    /// Every row by default, whatever dataset it is of: the first-dataset
    /// flags change nothing; `first_dataset` needs rows of both kinds.
    #[test]
    fn every_row_fits_the_base_by_default() {
        let clean = data(30);
        let mixed: Vec<bool> = (0..30).map(|r| r < 20).collect();
        let (_, all, folds) = fit_base(&quick(), &clean, 2, &[true; 30]).unwrap();
        let (_, flagged, _) = fit_base(&quick(), &clean, 2, &mixed).unwrap();
        assert_eq!(all, flagged);
        assert!(!folds.first_dataset_only && folds.fold_of_row.iter().all(|&f| f < 3));
        let mut first = quick();
        first.fit_on = BaseRows::FirstDataset;
        for flags in [[true; 30], [false; 30]] {
            let refused = fit_base(&first, &clean, 2, &flags).unwrap_err();
            assert!(refused.to_string().contains("two datasets"), "{refused}");
        }
    }

    #[test]
    fn the_base_table_is_read_checked_and_only_for_a_residual_model() {
        let (rest, base) = split_base_table("epochs = 3\n[base]\nfolds = 4\n").unwrap();
        assert_eq!(rest.trim(), "epochs = 3");
        assert_eq!(base.as_ref().map(|b| b.folds), Some(4));
        let mut cfg = ConvConfig::new(tactrace_convnet::ModelKind::ConvMlp);
        assert!(base_settings(&cfg, base.clone()).is_err());
        cfg.input = tactrace_convnet::InputKind::PinModelAndPixels;
        assert_eq!(
            base_settings(&cfg, None).unwrap(),
            Some(BaseSettings::default())
        );
        let (_, first) = split_base_table("[base]\nfit_on = \"first_dataset\"\n").unwrap();
        assert_eq!(first.map(|b| b.fit_on), Some(BaseRows::FirstDataset));
        let default = toml::to_string(&BaseSettings::default()).unwrap();
        assert!(!default.contains("fit_on"), "{default}");
        for bad in [
            "[base]\nfit_on = \"real\"",
            "[base]\nfolds = 1",
            "[base]\nmodel = \"conv-mlp\"",
            "[base]\nfold = 3",
        ] {
            let given = split_base_table(bad).and_then(|(_, b)| base_settings(&cfg, b));
            assert!(given.is_err(), "{bad}");
        }
    }
}
