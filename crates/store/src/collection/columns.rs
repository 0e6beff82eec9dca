//! The label columns of a collection's labels file (`import`, `twin`,
//! `calibrate`, `sim-fit`, `follow --replay`), found by header name with messages a newcomer can
//! act on: a column named twice is refused (which one holds the labels is
//! ambiguous), and a column that is missing is reported with every column
//! of the header, wrapped, and the closest names to the one asked for.

/// Longest column name shown whole in a message (a JSON or binary file
/// read as a CSV has one huge "column").
const NAME_CHARS: usize = 24;
/// Most columns listed (a binary file can have thousands of "fields").
const MAX_LISTED: usize = 200;
/// Width of a wrapped line of the column list.
const LINE_WIDTH: usize = 76;

/// The index of each of `names` in `headers` (names compared trimmed), or
/// why they cannot be read: a name that is missing, or that the header
/// holds more than once. `needed` lists every column asked for (for the
/// message).
pub(crate) fn column_indices(
    headers: &csv::StringRecord,
    names: &[&str],
) -> std::result::Result<Vec<usize>, String> {
    let needed = names
        .iter()
        .map(|c| format!("`{c}`"))
        .collect::<Vec<_>>()
        .join(", ");
    names
        .iter()
        .map(|&name| {
            let at: Vec<usize> = headers
                .iter()
                .enumerate()
                .filter(|(_, h)| h.trim() == name)
                .map(|(k, _)| k)
                .collect();
            match at.as_slice() {
                [k] => Ok(*k),
                [] => Err(missing(headers, name, &needed)),
                several => Err(duplicated(name, several)),
            }
        })
        .collect()
}

/// A column named more than once (at the 0-based `at`).
fn duplicated(name: &str, at: &[usize]) -> String {
    let places: Vec<String> = at.iter().map(|k| (k + 1).to_string()).collect();
    format!(
        "the column `{name}` appears {} times in the header (columns {}): which one holds \
         the labels is ambiguous; rename the others",
        at.len(),
        places.join(", ")
    )
}

/// A column that is not in the header: the header in full and the
/// closest names.
fn missing(headers: &csv::StringRecord, name: &str, needed: &str) -> String {
    let close = closest(headers, name);
    let hint = if close.is_empty() {
        String::new()
    } else {
        let list: Vec<String> = close.iter().map(|c| format!("`{c}`")).collect();
        format!(" (did you mean {}?)", list.join(" or "))
    };
    format!(
        "not a CSV with the label columns {needed}: no column `{name}`{hint}\n\
         its {} columns:\n{}\nname the columns with --image-column and, for an edge, --r-column and --theta-column, \
         or for any labels --target COLUMN:UNIT, once a label",
        headers.len(),
        listing(headers)
    )
}

/// Every column of `headers` (at most [`MAX_LISTED`]), each cut at
/// [`NAME_CHARS`] characters, wrapped to lines of [`LINE_WIDTH`] indented
/// by two spaces.
pub(crate) fn listing(headers: &csv::StringRecord) -> String {
    let mut names: Vec<String> = headers
        .iter()
        .take(MAX_LISTED)
        .map(|h| {
            let h = h.trim();
            match h.char_indices().nth(NAME_CHARS) {
                Some((end, _)) => format!("`{}...`", &h[..end]),
                None => format!("`{h}`"),
            }
        })
        .collect();
    if headers.len() > MAX_LISTED {
        names.push(format!("... ({} fields in all)", headers.len()));
    }
    let mut lines = vec![String::from(" ")];
    for (k, n) in names.iter().enumerate() {
        let sep = if k + 1 < names.len() { "," } else { "" };
        let last = lines.last_mut().expect("one line at least");
        if last.len() + 1 + n.len() + sep.len() > LINE_WIDTH && last.len() > 2 {
            lines.push(String::from(" "));
        }
        let last = lines.last_mut().expect("one line at least");
        last.push(' ');
        last.push_str(n);
        last.push_str(sep);
    }
    lines.join("\n")
}

/// The columns nearest `name` (case and `-`/`_`/space ignored, then by
/// edit distance; at most three, all at the least distance), only those
/// near enough to be a slip.
fn closest(headers: &csv::StringRecord, name: &str) -> Vec<String> {
    let fold = |s: &str| -> String {
        s.trim()
            .chars()
            .filter(|c| !matches!(c, '_' | '-' | ' '))
            .flat_map(char::to_lowercase)
            .collect()
    };
    let want = fold(name);
    let limit = (want.chars().count() / 3).max(2);
    let mut near: Vec<(usize, String)> = headers
        .iter()
        .map(|h| (edit_distance(&fold(h), &want), h.trim().to_string()))
        .filter(|(d, h)| *d <= limit && !h.is_empty() && h.chars().count() <= NAME_CHARS)
        .collect();
    near.sort();
    near.dedup_by(|a, b| a.1 == b.1);
    // Only the nearest: `pose2` suggests `pose_2`, not every `pose_k`.
    let best = near.first().map_or(0, |n| n.0);
    near.into_iter()
        .take_while(|n| n.0 == best)
        .take(3)
        .map(|(_, h)| h)
        .collect()
}

/// Levenshtein distance between `a` and `b` (by characters).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(row[j + 1] + 1);
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(names: &[&str]) -> csv::StringRecord {
        csv::StringRecord::from(names.to_vec())
    }

    #[test]
    fn a_column_named_twice_is_refused_naming_it() {
        let h = header(&["image_name", "pose_2", "pose_6", "pose_2"]);
        let err = column_indices(&h, &["image_name", "pose_2", "pose_6"]).unwrap_err();
        assert!(
            err.contains("`pose_2` appears 2 times") && err.contains("columns 2, 4"),
            "{err}"
        );
        // A duplicate the labels do not use is no ambiguity.
        assert_eq!(
            column_indices(&h, &["image_name", "pose_6"]).unwrap(),
            vec![0, 2]
        );
    }

    #[test]
    fn a_missing_column_lists_every_column_and_the_closest() {
        let names: Vec<String> = ["image_name", "data_name", "obj_id", "pose_id"]
            .iter()
            .map(|s| s.to_string())
            .chain((1..=6).map(|k| format!("pose_{k}")))
            .chain((1..=6).map(|k| format!("move_{k}")))
            .collect();
        let h = csv::StringRecord::from(names.clone());
        let err = column_indices(&h, &["image_name", "pose2", "pose_6"]).unwrap_err();
        for n in &names {
            assert!(err.contains(&format!("`{n}`")), "{n} missing: {err}");
        }
        assert!(err.contains("(did you mean `pose_2`?)"), "{err}");
        assert!(err.contains("its 16 columns"), "{err}");
        let listed: Vec<&str> = err.lines().filter(|l| l.starts_with("  ")).collect();
        assert!(listed.len() >= 2, "wrapped: {err}");
        assert!(listed.iter().all(|l| l.len() <= LINE_WIDTH), "{err}");
        // Nothing near: no guess.
        let err = column_indices(&h, &["zzzzzzzzzz"]).unwrap_err();
        assert!(!err.contains("did you mean"), "{err}");
    }

    #[test]
    fn edit_distance_counts_single_edits() {
        assert_eq!(edit_distance("pose2", "pose2"), 0);
        assert_eq!(edit_distance("pose2", "pose_2"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
    }
}
