//! Held-out rows that are copies of training rows. A twin (`tactrace
//! twin`) renders every label row `renders` times under that row's image
//! name, and repeats the sensor's real calibration taps
//! (`calibration-tap-I#K`, round K). `train --val-fraction` deals whole
//! taps on such a dataset (`tactrace_store::tap_split`), but a held-out
//! part given by hand (`--val`) or a row split of an older model can
//! still hold copies of training taps, and their validation score then
//! says how well the model recalls rows it has seen. Counted here so that
//! `train` can say so.
use std::collections::HashSet;
use tactrace_store::tap_split::tap_of;
use tactrace_store::TapData;

/// How many rows of `val` show a tap that a row of `train` shows too (by
/// image name; 0 when either part names no image for every row, as a
/// simulated collection's).
pub fn held_out_copies(train: &TapData, val: &TapData) -> usize {
    let named = |d: &TapData| d.meta.images.len() == d.len() && !d.meta.images.is_empty();
    if !(named(train) && named(val)) {
        return 0;
    }
    let seen: HashSet<&str> = train.meta.images.iter().map(|n| tap_of(n)).collect();
    (val.meta.images.iter())
        .filter(|n| seen.contains(tap_of(n)))
        .count()
}

/// The warning of a held-out part with copies of training taps
/// ([`held_out_copies`]); `None` when it has none.
pub fn held_out_copies_warning(train: &TapData, val: &TapData) -> Option<String> {
    let k = held_out_copies(train, val);
    (k > 0).then(|| {
        format!(
            "warning: {k} of the {} held-out rows show a tap that training rows show too \
             (a twin's renders of one label row, or a repeated tap): their validation score \
             is optimistic. Hold out label rows instead: split the labels file, make each \
             part's dataset, and give the held-out one as --val",
            val.len()
        )
    })
}

/// What `train` says of the part `--val-fraction` held out of `data`
/// (`split`, giving `train` and `val`): how it was dealt when by tap, and
/// the warning of [`held_out_copies_warning`] when copies remain.
pub fn held_out_lines(
    data: &TapData,
    split: &tactrace_store::HeldOut,
    train: &TapData,
    val: &TapData,
) -> Vec<String> {
    let taps = held_out_taps_line(data, split);
    taps.into_iter()
        .chain(held_out_copies_warning(train, val))
        .collect()
}

/// What `train` says of a held-out part dealt by tap: how many rows, and
/// that they are every copy of so many taps; `None` for a split by row.
fn held_out_taps_line(data: &TapData, split: &tactrace_store::HeldOut) -> Option<String> {
    if split.unit != tactrace_store::tap_split::SplitUnit::Tap {
        return None;
    }
    let groups = tactrace_store::tap_split::tap_groups(data)?;
    let held: std::collections::HashSet<usize> = split.rows.iter().copied().collect();
    let taps = groups.iter().filter(|g| held.contains(&g[0])).count();
    Some(format!(
        "held out {} rows: every copy of {taps} of the {} taps (the dataset shows some taps \
         more than once, as a twin's renders: no held-out tap is seen in training)",
        split.rows.len(),
        groups.len()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named(names: &[&str]) -> TapData {
        let mut d = crate::test_data::edge_data(
            vec![0.0; 2 * names.len()],
            vec![0.0; 2 * names.len()],
            &[[0.0, 0.0]],
        );
        d.meta.images = names.iter().map(|n| n.to_string()).collect();
        d
    }

    #[test]
    fn renders_and_rounds_of_one_tap_are_copies() {
        let train = named(&["a.png", "b.png", "calibration-tap-3#0"]);
        let val = named(&[
            "a.png",
            "c.png",
            "calibration-tap-3#1",
            "calibration-tap-4#1",
        ]);
        assert_eq!(held_out_copies(&train, &val), 2);
        let w = held_out_copies_warning(&train, &val).unwrap();
        assert!(w.contains("2 of the 4 held-out rows"), "{w}");
        let apart = named(&["c.png", "d#x.png"]);
        assert_eq!(held_out_copies_warning(&train, &apart), None);
    }

    /// 40 rows: 10 taps rendered 4 times, the rows told apart by their
    /// inputs (so the record's row hashes differ).
    fn twin_like() -> TapData {
        let names: Vec<String> = (0..40).map(|i| format!("t{}.png", i % 10)).collect();
        let mut d = named(&names.iter().map(String::as_str).collect::<Vec<_>>());
        d.inputs = (0..d.inputs.len()).map(|v| v as f32).collect();
        d
    }

    #[test]
    fn a_twins_held_out_part_has_no_copies_and_says_so() {
        let d = twin_like();
        let split = crate::train::training_split(&d, None, Some((0.3, 5))).unwrap();
        let held = split.record.split.as_ref().unwrap();
        assert_eq!(held.unit, tactrace_store::tap_split::SplitUnit::Tap);
        assert_eq!(held.rows.len(), 12);
        let val = split.val.as_ref().unwrap();
        assert_eq!(held_out_copies(&split.train, val), 0);
        let lines = held_out_lines(&d, held, &split.train, val);
        assert_eq!(lines.len(), 1, "{lines:?}");
        assert!(
            lines[0].contains("every copy of 3 of the 10 taps"),
            "{}",
            lines[0]
        );
    }

    #[test]
    fn an_older_record_split_by_row_is_drawn_again_by_row() {
        let d = twin_like();
        let (tr, va) = d.split_rows(0.7, 5);
        let held = tactrace_store::HeldOut {
            val_fraction: 0.3,
            split_seed: 5,
            rows: va.clone(),
            unit: Default::default(),
        };
        let record = tactrace_store::TrainingRecord::new(&d, None, tr, Some(held));
        // Written before the unit was kept: the field is absent.
        let text = serde_json::to_string(&record).unwrap();
        assert!(!text.contains("\"unit\""), "{text}");
        let read: tactrace_store::TrainingRecord = serde_json::from_str(&text).unwrap();
        let path = std::path::Path::new("twin");
        let rows = crate::train::held_out_rows(Some(&read), &d, path, (0.3, 5)).unwrap();
        assert_eq!(rows, va);
        // With no record the split is by tap: other rows.
        let now = crate::train::held_out_rows(None, &d, path, (0.3, 5)).unwrap();
        assert_ne!(now, va);
    }

    #[test]
    fn rows_without_names_are_never_copies() {
        let train = named(&["a.png"]);
        let mut val = named(&["a.png"]);
        val.meta.images.clear();
        assert_eq!(held_out_copies(&train, &val), 0);
    }
}
