//! Held-out parts that hold out whole taps. A twin (`tactrace twin`)
//! renders every label row several times under that row's image name, and
//! repeats the sensor's real calibration taps as `calibration-tap-I#K`
//! (round K). A split by row puts most copies of a held-out tap in
//! training too, and the held-out score then says how well the model
//! recalls what it has seen. The splits here deal whole taps instead; on
//! a dataset where no tap repeats (every real import) they are the row
//! splits, row for row.
use crate::dataset::TapData;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use std::collections::HashMap;

/// The tap a row's image name stands for: the name without a trailing
/// `#K` (the round of a repeated calibration tap).
pub fn tap_of(name: &str) -> &str {
    match name.rsplit_once('#') {
        Some((tap, k)) if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) => tap,
        _ => name,
    }
}

/// The rows of `data` grouped by the tap they show (groups in the order
/// of their first row, rows in order), or `None` when no tap repeats: no
/// image names for every row, or every name its own tap.
pub fn tap_groups(data: &TapData) -> Option<Vec<Vec<usize>>> {
    let names = &data.meta.images;
    if names.is_empty() || names.len() != data.len() {
        return None;
    }
    let mut index: HashMap<&str, usize> = HashMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (row, name) in names.iter().enumerate() {
        let g = *index.entry(tap_of(name)).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(row);
    }
    (groups.len() < data.len()).then_some(groups)
}

/// How a held-out part was drawn: by row (every dataset where no tap
/// repeats, and every model folder written before taps were kept
/// together), or by tap (every copy of a tap on one side).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SplitUnit {
    /// A seeded shuffle of the rows ([`TapData::split_rows`]).
    #[default]
    Row,
    /// A seeded shuffle of the taps ([`tap_groups`]), each tap's rows
    /// kept together.
    Tap,
}

impl SplitUnit {
    /// Whether this is [`SplitUnit::Row`] (the field a record leaves out).
    pub fn is_row(&self) -> bool {
        *self == SplitUnit::Row
    }
}

/// The two parts of a split that keeps `frac` of the taps in the first:
/// the groups of [`tap_groups`] shuffled from `seed` and cut as
/// [`TapData::split_rows`] cuts rows, each part's rows in the order its
/// groups were drawn. With no repeated tap this is `split_rows` itself.
pub fn split_taps(data: &TapData, frac: f64, seed: u64) -> (Vec<usize>, Vec<usize>, SplitUnit) {
    let Some(groups) = tap_groups(data) else {
        let (a, b) = data.split_rows(frac, seed);
        return (a, b, SplitUnit::Row);
    };
    let (a, b) = deal_groups(&groups, frac, seed);
    (a, b, SplitUnit::Tap)
}

/// The rows of `groups` in two parts: the groups shuffled from `seed`,
/// the first `round(groups * frac)` of them in the first part.
fn deal_groups(groups: &[Vec<usize>], frac: f64, seed: u64) -> (Vec<usize>, Vec<usize>) {
    let mut order: Vec<usize> = (0..groups.len()).collect();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
    let cut = ((groups.len() as f64 * frac).round() as usize).min(groups.len());
    let rows = |gs: &[usize]| gs.iter().flat_map(|&g| groups[g].iter().copied()).collect();
    (rows(&order[..cut]), rows(&order[cut..]))
}

/// Each of `rows`' fold, `0..folds`, dealing taps rather than rows: the
/// taps of `rows` (by `data`'s image names; [`tap_groups`] of those rows)
/// in the order `deal` gives them, so every copy of a tap shares a fold.
/// `deal(n)` is the caller's deal of `n` items into folds; with no
/// repeated tap among `rows` it is applied to the rows themselves.
pub fn fold_by_tap(
    data: &TapData,
    rows: &[usize],
    deal: impl Fn(usize) -> Vec<usize>,
) -> (Vec<usize>, SplitUnit) {
    let sub = data.subset(rows);
    let Some(groups) = tap_groups(&sub) else {
        return (deal(rows.len()), SplitUnit::Row);
    };
    let of_group = deal(groups.len());
    let mut fold = vec![0; rows.len()];
    for (g, members) in groups.iter().enumerate() {
        for &r in members {
            fold[r] = of_group[g];
        }
    }
    (fold, SplitUnit::Tap)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::DatasetMeta;

    fn named(names: &[String]) -> TapData {
        let n = names.len();
        let meta: DatasetMeta = serde_json::from_value(serde_json::json!({
            "source": "real", "origin": "", "seed": null, "samples": n, "pins": 1,
            "targets": ["r"], "frames_with_missing_pins": 0,
            "reference_pins": [[0.0, 0.0]], "settings": null, "tactrace_version": "",
            "images": names,
        }))
        .expect("meta");
        TapData {
            meta,
            inputs: (0..2 * n).map(|v| v as f32).collect(),
            targets: vec![0.0; n],
        }
    }

    /// A twin's rows: `taps` label rows rendered 3 times each, then 4
    /// calibration taps repeated in 2 rounds.
    fn twin(taps: usize) -> TapData {
        let mut names = Vec::new();
        for _ in 0..3 {
            names.extend((0..taps).map(|t| format!("image_{t}.png")));
        }
        for k in 0..2 {
            names.extend((0..4).map(|i| format!("calibration-tap-{i}#{k}")));
        }
        named(&names)
    }

    #[test]
    fn tap_of_strips_a_round_only() {
        assert_eq!(tap_of("calibration-tap-3#12"), "calibration-tap-3");
        assert_eq!(tap_of("a#b.png"), "a#b.png");
        assert_eq!(tap_of("a#"), "a#");
        assert_eq!(tap_of("image_1.png"), "image_1.png");
    }

    #[test]
    fn no_held_out_tap_is_seen_in_training() {
        let d = twin(100);
        for seed in 0..5 {
            let (tr, va, unit) = split_taps(&d, 0.8, seed);
            assert_eq!(unit, SplitUnit::Tap);
            assert_eq!(tr.len() + va.len(), d.len());
            let tap = |r: &usize| tap_of(&d.meta.images[*r]).to_string();
            let seen: std::collections::HashSet<String> = tr.iter().map(tap).collect();
            assert!(va.iter().all(|r| !seen.contains(&tap(r))), "seed {seed}");
            // 104 taps: 21 held out (round(104 * 0.2)); 3 rows a label tap, 2 a calibration tap
            let held_taps: std::collections::HashSet<String> = va.iter().map(tap).collect();
            assert_eq!(held_taps.len(), 104 - 83);
            assert!((va.len() as f64 / d.len() as f64 - 0.2).abs() < 0.05);
        }
    }

    #[test]
    fn without_repeated_taps_the_row_split_is_kept_row_for_row() {
        let names: Vec<String> = (0..57).map(|i| format!("frame_{i}.png")).collect();
        let d = named(&names);
        assert!(tap_groups(&d).is_none());
        for seed in [0, 1, 3, 99] {
            let (tr, va, unit) = split_taps(&d, 0.75, seed);
            assert_eq!(unit, SplitUnit::Row);
            assert_eq!((tr, va), d.split_rows(0.75, seed));
        }
        let mut unnamed = d.clone();
        unnamed.meta.images.clear();
        assert_eq!(split_taps(&unnamed, 0.6, 2).2, SplitUnit::Row);
    }

    #[test]
    fn folds_keep_every_copy_of_a_tap_together() {
        let d = twin(20);
        let rows: Vec<usize> = (0..d.len()).step_by(2).chain([1]).collect();
        let deal = |n: usize| (0..n).map(|i| (i * 7) % 4).collect::<Vec<_>>();
        let (fold, unit) = fold_by_tap(&d, &rows, deal);
        assert_eq!(unit, SplitUnit::Tap);
        assert_eq!(fold.len(), rows.len());
        let mut of_tap = HashMap::new();
        for (i, &r) in rows.iter().enumerate() {
            let f = *of_tap.entry(tap_of(&d.meta.images[r])).or_insert(fold[i]);
            assert_eq!(f, fold[i], "row {r}");
        }
        assert!((0..4).all(|f| fold.contains(&f)));
        let plain = named(&(0..9).map(|i| format!("f{i}")).collect::<Vec<_>>());
        let (f2, u2) = fold_by_tap(&plain, &[0, 2, 4, 6], deal);
        assert_eq!((f2, u2), (deal(4), SplitUnit::Row));
    }
}
