//! Every crate's integration tests are modules of one test binary,
//! `tests/it/main.rs` (ARCHITECTURE.md). A test file directly in a
//! `tests/` folder would be a binary of its own again, and a file in
//! `tests/it/` that no module declares would never be compiled: its tests
//! would be skipped without a word. Both are caught here.

use std::path::{Path, PathBuf};

/// The crates whose Rust tests cargo builds: the root and `crates/*`
/// but the Python package's (no Rust tests: pytest tests it).
fn crate_dirs(root: &Path) -> Vec<PathBuf> {
    let mut dirs = vec![root.to_path_buf()];
    let crates = std::fs::read_dir(root.join("crates")).expect("crates/");
    for entry in crates {
        let path = entry.expect("an entry of crates/").path();
        if path.join("Cargo.toml").is_file() && !path.ends_with("py") {
            dirs.push(path);
        }
    }
    dirs.sort();
    dirs
}

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries
        .map(|e| e.expect("a directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "rs"))
        .collect();
    files.sort();
    files
}

/// Whether a module file's `text` declares `mod name;` (or `pub mod name;`).
fn declares(text: &str, name: &str) -> bool {
    text.lines().any(|line| {
        let line = line.trim();
        line == format!("mod {name};") || line == format!("pub mod {name};")
    })
}

/// The files of `dir` (a module folder under `tests/it/`) and of its
/// sub-folders that their module file (`parent`) does not declare.
fn undeclared(dir: &Path, parent: &Path, found: &mut Vec<PathBuf>) {
    let text = std::fs::read_to_string(parent).unwrap_or_default();
    for file in rust_files(dir) {
        let stem = file.file_stem().and_then(|s| s.to_str()).unwrap_or("");
        if file == parent || stem == "mod" {
            continue;
        }
        if !declares(&text, stem) {
            found.push(file);
        }
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for sub in entries.map(|e| e.expect("a directory entry").path()) {
        let module = sub.join("mod.rs");
        if sub.is_dir() && module.is_file() {
            let name = sub.file_name().and_then(|s| s.to_str()).unwrap_or("");
            if !declares(&text, name) {
                found.push(module.clone());
            }
            undeclared(&sub, &module, found);
        }
    }
}

#[test]
fn every_crates_integration_tests_are_one_binary_and_all_declared() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let (mut loose, mut missing, mut binaries) = (Vec::new(), Vec::new(), 0);
    for krate in crate_dirs(root) {
        let tests = krate.join("tests");
        loose.extend(rust_files(&tests));
        let main = tests.join("it").join("main.rs");
        if main.is_file() {
            binaries += 1;
            undeclared(&tests.join("it"), &main, &mut missing);
        }
    }
    assert!(loose.is_empty(), "test files outside tests/it/: {loose:?}");
    assert!(missing.is_empty(), "files no module declares: {missing:?}");
    assert!(binaries >= 15, "{binaries} crates with tests/it/main.rs");
}
