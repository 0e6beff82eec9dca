//! Where tactrace's tests find the real TacTip data (`../shared/data`
//! beside the repository, not in it), and the one rule for when it is
//! absent: a test that needs it **fails** with a message saying how to get
//! the data, unless `TACTRACE_SKIP_REAL_DATA=1` is set, in which case it
//! says it is skipped (on the terminal, past the test harness's capture).
//! A missing folder can therefore never make a test pass silently.
//!
//! `TACTRACE_SHARED_DATA=DIR` names another folder holding the sets (the
//! Python tests read it too); `TACTRACE_REAL_DATA=DIR` points at another
//! copy of `tactip127-edge2d` alone, and wins for that set.
//!
//! Also the synthetic sensors whose truth is known ([`layouts`]), shared by
//! the tests of the vision crate and of the binary.
use std::io::Write;
use std::path::{Path, PathBuf};

pub mod layouts;

/// The environment variable that lets tests needing absent data skip.
pub const SKIP_VAR: &str = "TACTRACE_SKIP_REAL_DATA";
/// The environment variable that names another copy of the edge set.
pub const DATA_VAR: &str = "TACTRACE_REAL_DATA";
/// The environment variable that names another folder of the shared sets.
pub const SHARED_VAR: &str = "TACTRACE_SHARED_DATA";

/// The folder of the shared sets: [`SHARED_VAR`] when set (and not
/// empty), else `../shared/data` beside the repository.
pub fn shared_data_dir() -> PathBuf {
    match std::env::var_os(SHARED_VAR) {
        Some(d) if !d.is_empty() => PathBuf::from(d),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
    }
}

/// The real edge set (`tactip127-edge2d`: targets.csv, frames/), or `None`
/// when it is absent and skipping was asked for (the test should return).
///
/// # Panics
/// When the data is absent and [`SKIP_VAR`] is not `1`.
pub fn real_edge_set() -> Option<PathBuf> {
    let dir = match std::env::var_os(DATA_VAR) {
        Some(d) if !d.is_empty() => PathBuf::from(d),
        _ => shared_data_dir().join("tactip127-edge2d"),
    };
    let found = dir.join("targets.csv").is_file() && dir.join("frames/init_0.png").is_file();
    found_or_skipped(dir, found)
}

/// Another set of the shared data by its folder name (`tactip331-surface3d`,
/// `tactip331-edge2d-shear`, `tactip127-surface2d`), when `probe` (a file
/// inside it) exists; `None` when it is absent and skipping was asked for.
///
/// # Panics
/// When the data is absent and [`SKIP_VAR`] is not `1`.
pub fn shared_set(name: &str, probe: &str) -> Option<PathBuf> {
    let dir = shared_data_dir().join(name);
    let found = dir.join(probe).is_file();
    found_or_skipped(dir, found)
}

/// `dir` when `found`; else `None` after saying SKIPPED when skipping was
/// asked for, or a panic saying how to get the data.
fn found_or_skipped(dir: PathBuf, found: bool) -> Option<PathBuf> {
    if found {
        return Some(dir);
    }
    if std::env::var(SKIP_VAR).is_ok_and(|v| v == "1") {
        // Written to stderr itself, not by `eprintln!`, which the test
        // harness captures and shows only for a failing test.
        let line = format!(
            "SKIPPED ({SKIP_VAR}=1): real TacTip data not found at {}\n",
            dir.display()
        );
        let _ = std::io::stderr().write_all(line.as_bytes());
        return None;
    }
    panic!(
        "real TacTip data not found at {}: this test needs it (the README says where \
         ../shared comes from). Set {SHARED_VAR}=DIR to point at the folder of the sets \
         ({DATA_VAR}=DIR for the edge set alone), or {SKIP_VAR}=1 to skip the tests \
         that need it.",
        dir.display()
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One test, as it sets the process's environment: the shared folder
    /// follows [`SHARED_VAR`], and an absent set under it is skipped.
    #[test]
    fn the_shared_folder_follows_its_variable() {
        let empty = std::env::temp_dir().join(format!("tactrace-no-data-{}", std::process::id()));
        std::env::set_var(SHARED_VAR, &empty);
        std::env::set_var(SKIP_VAR, "1");
        std::env::remove_var(DATA_VAR);
        assert_eq!(shared_data_dir(), empty);
        assert_eq!(shared_set("tactip331-surface3d", "targets.csv"), None);
        assert_eq!(real_edge_set(), None);
        std::env::set_var(SKIP_VAR, "0");
        let refused = std::panic::catch_unwind(|| shared_set("tactip331-surface3d", "x"));
        assert!(refused.is_err(), "an absent set without skipping fails");
    }
}
