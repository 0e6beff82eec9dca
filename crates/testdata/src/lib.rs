//! Where tactrace's tests find the real TacTip data (`../shared/data`, not
//! in the repository), and the one rule for when it is absent: a test that
//! needs it **fails** with a message saying how to get the data, unless
//! `TACTRACE_SKIP_REAL_DATA=1` is set, in which case it says it is skipped.
//! A missing folder can therefore never make a test pass silently.
//!
//! `TACTRACE_REAL_DATA=DIR` points at another copy of `tactip127-edge2d`.
//!
//! Also the synthetic sensors whose truth is known ([`layouts`]), shared by
//! the tests of the vision crate and of the binary.
use std::path::{Path, PathBuf};

pub mod layouts;

/// The environment variable that lets tests needing absent data skip.
pub const SKIP_VAR: &str = "TACTRACE_SKIP_REAL_DATA";
/// The environment variable that names another data folder.
pub const DATA_VAR: &str = "TACTRACE_REAL_DATA";

/// The real edge set (`tactip127-edge2d`: targets.csv, frames/), or `None`
/// when it is absent and skipping was asked for (the test should return).
///
/// # Panics
/// When the data is absent and [`SKIP_VAR`] is not `1`.
pub fn real_edge_set() -> Option<PathBuf> {
    let dir = match std::env::var_os(DATA_VAR) {
        Some(d) => PathBuf::from(d),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/tactip127-edge2d"),
    };
    if dir.join("targets.csv").is_file() && dir.join("frames/init_0.png").is_file() {
        return Some(dir);
    }
    if std::env::var(SKIP_VAR).is_ok_and(|v| v == "1") {
        eprintln!(
            "SKIPPED ({SKIP_VAR}=1): real TacTip data not found at {}",
            dir.display()
        );
        return None;
    }
    panic!(
        "real TacTip data not found at {}: this test needs it (the README says where \
         ../shared comes from). Set {DATA_VAR}=DIR to point at it, or {SKIP_VAR}=1 to \
         skip the tests that need it.",
        dir.display()
    );
}

/// Another set of the shared data by its folder name (`tactip331-surface3d`,
/// `tactip331-edge2d-shear`, `tactip127-surface2d`), when `probe` (a file
/// inside it) exists; `None` when it is absent and skipping was asked for.
///
/// # Panics
/// When the data is absent and [`SKIP_VAR`] is not `1`.
pub fn shared_set(name: &str, probe: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(name);
    if dir.join(probe).is_file() {
        return Some(dir);
    }
    if std::env::var(SKIP_VAR).is_ok_and(|v| v == "1") {
        eprintln!(
            "SKIPPED ({SKIP_VAR}=1): real TacTip data not found at {}",
            dir.display()
        );
        return None;
    }
    panic!(
        "real TacTip data not found at {}: this test needs it (the README says where \
         ../shared comes from), or set {SKIP_VAR}=1 to skip the tests that need it.",
        dir.display()
    );
}
