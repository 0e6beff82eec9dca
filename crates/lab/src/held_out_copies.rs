//! Held-out rows that are copies of training rows. A twin (`tactrace
//! twin`) renders every label row `renders` times under that row's image
//! name, and repeats the sensor's real calibration taps
//! (`calibration-tap-I#K`, round K); `train --val-fraction` draws rows,
//! not taps, so most held-out rows of a twin have a copy of their tap in
//! training, and their validation score says how well the model recalls
//! rows it has seen. Counted here so that `train` can say so.
use std::collections::HashSet;
use tactrace_store::TapData;

/// The tap a row's image name stands for: the name without a trailing
/// `#K` (the round of a repeated calibration tap).
fn tap_of(name: &str) -> &str {
    match name.rsplit_once('#') {
        Some((tap, k)) if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) => tap,
        _ => name,
    }
}

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

    #[test]
    fn rows_without_names_are_never_copies() {
        let train = named(&["a.png"]);
        let mut val = named(&["a.png"]);
        val.meta.images.clear();
        assert_eq!(held_out_copies(&train, &val), 0);
    }
}
