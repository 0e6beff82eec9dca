//! What a new user meets first: the docs (no machine paths, no issue
//! numbers, no links to missing files), the getting-started guide run as
//! written, shell completions, the licence and citation files. (Every
//! documented command line is also parsed with clap: the binary's unit
//! test `doc_commands`.)
use crate::util;
use std::path::{Path, PathBuf};
use std::process::Command;
use util::{real_data, tactrace, TempDir};

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// README.md, ARCHITECTURE.md, CHANGELOG.md, fuzz/README.md, docs/*.md and
/// docs/results/*.md.
fn markdown_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = [
        "README.md",
        "ARCHITECTURE.md",
        "CHANGELOG.md",
        "fuzz/README.md",
    ]
    .iter()
    .map(|f| repo().join(f))
    .collect();
    let mut docs: Vec<PathBuf> = ["docs", "docs/results"]
        .iter()
        .flat_map(|dir| std::fs::read_dir(repo().join(dir)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

/// The user docs: README.md and every page under docs/.
fn user_docs() -> Vec<PathBuf> {
    markdown_files()
        .into_iter()
        .filter(|p| {
            let docs = repo().join("docs");
            *p == repo().join("README.md") || p.starts_with(&docs)
        })
        .collect()
}

/// "issue 12", "issues 10", "issue #2", any case.
fn issue_references(text: &str) -> Vec<String> {
    let lower = text.to_ascii_lowercase();
    let mut found = Vec::new();
    for (at, _) in lower.match_indices("issue") {
        let rest = lower[at + 5..].trim_start_matches('s');
        let rest = rest.trim_start_matches([' ', '\n', '#']);
        if rest.starts_with(|c: char| c.is_ascii_digit()) {
            let shown: String = text[at..].chars().take(16).collect();
            found.push(shown.replace('\n', " "));
        }
    }
    found
}

/// The targets of `[text](target)` links, and every `*.md` path named in
/// the text, that are neither web addresses nor anchors.
fn local_references(text: &str) -> Vec<String> {
    let mut refs = Vec::new();
    for (at, _) in text.match_indices("](") {
        let rest = &text[at + 2..];
        if let Some(end) = rest.find(')') {
            refs.push(rest[..end].to_owned());
        }
    }
    // Paths and capitalised names (ERRATA.md); not the lower-case names of
    // files a run writes (report.md).
    for word in text.split(|c: char| c.is_whitespace() || "`()[],;:\"'".contains(c)) {
        let word = word.trim_end_matches('.');
        let capital = word.starts_with(|c: char| c.is_ascii_uppercase());
        if word.ends_with(".md") && !word.contains("://") && (word.contains('/') || capital) {
            refs.push(word.to_owned());
        }
    }
    refs.retain(|r| !(r.starts_with("http") || r.starts_with('#') || r.starts_with("mailto:")));
    refs
}

/// Issue 20: four docs cited an ERRATA.md missing from the repository, and
/// user docs held machine paths (/work/...) and "issue N" references. No
/// document links to or names a missing file (the shared data folder
/// beside the repository excepted), and the user docs say what they mean.
#[test]
fn docs_have_no_machine_paths_issue_numbers_or_missing_files() {
    let mut problems = Vec::new();
    for file in markdown_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        let name = file.strip_prefix(repo()).unwrap().display().to_string();
        if text.contains("/work/") {
            problems.push(format!("{name}: a machine path (/work/...)"));
        }
        for r in local_references(&text) {
            let target = r.split('#').next().unwrap_or(&r);
            if target.is_empty() || target.starts_with("../shared/") {
                continue;
            }
            let here = file.parent().unwrap().join(target);
            if !here.exists() && !repo().join(target).exists() {
                problems.push(format!("{name}: names a missing file: {r}"));
            }
        }
    }
    for file in user_docs() {
        let text = std::fs::read_to_string(&file).unwrap();
        let name = file.strip_prefix(repo()).unwrap().display().to_string();
        for r in issue_references(&text) {
            problems.push(format!("{name}: an issue number: {r:?}"));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    // The checks themselves.
    assert_eq!(issue_references("fixed in Issue #12.").len(), 1);
    assert_eq!(
        issue_references("issues\n10 and the issueN_* tests").len(),
        1
    );
    assert!(
        local_references("see ERRATA.md and [x](docs/a.md#b)").contains(&"ERRATA.md".to_owned())
    );
    assert!(user_docs()
        .iter()
        .any(|p| p.ends_with("docs/getting-started.md")));
}

/// Issue 20: no LICENSE files although Cargo.toml declares MIT OR
/// Apache-2.0, no CITATION.cff, no CHANGELOG.
#[test]
fn licence_citation_and_changelog_are_present() {
    let read = |f: &str| std::fs::read_to_string(repo().join(f)).unwrap_or_default();
    assert!(read("Cargo.toml").contains("license = \"MIT OR Apache-2.0\""));
    let mit = read("LICENSE-MIT");
    assert!(
        mit.starts_with("MIT License") && mit.contains("Copyright (c) the tactrace developers")
    );
    let apache = read("LICENSE-APACHE");
    assert!(apache.contains("Apache License") && apache.contains("Version 2.0, January 2004"));
    assert!(apache.contains("END OF TERMS AND CONDITIONS"));
    let cff = read("CITATION.cff");
    for needle in [
        "cff-version: 1.2.0",
        "A Bio-Inspired System for Human-Like Contour Following",
        "10.5523/bris.110f0tkyy28pa2joru2pxxbrxd",
        "- MIT",
        "- Apache-2.0",
    ] {
        assert!(cff.contains(needle), "CITATION.cff lacks {needle}");
    }
    let changelog = read("CHANGELOG.md");
    assert!(changelog.starts_with("# Changelog") && changelog.contains("## [Unreleased]"));
}

/// Issue 20: `sensors/` (where `calibrate --out sensors/mine` writes) was
/// not git-ignored.
#[test]
fn sensor_folders_are_git_ignored() {
    let ignore = std::fs::read_to_string(repo().join(".gitignore")).unwrap();
    let rules: Vec<&str> = ignore.lines().map(str::trim).collect();
    for folder in ["sensors", "runs", "data", "models"] {
        assert!(
            rules.contains(&format!("/{folder}").as_str())
                || rules.contains(&format!("/{folder}/").as_str()),
            "{folder}/ is not ignored"
        );
    }
}

/// Issue 20: no shell completions. `tactrace completions bash` prints a
/// script bash accepts; an unknown shell is bad input (exit 2).
#[test]
fn completions_print_a_script_bash_accepts() {
    let t = TempDir::new("completions");
    for shell in ["bash", "zsh", "fish"] {
        let r = tactrace(&t.0, &["completions", shell]);
        assert_eq!(r.code, 0, "{shell}: {}", r.stderr);
        assert!(
            r.stdout.contains("sim-fit") && r.stdout.contains("completions"),
            "{shell}"
        );
    }
    let script = t.join("tactrace.bash");
    std::fs::write(&script, tactrace(&t.0, &["completions", "bash"]).stdout).unwrap();
    let check = Command::new("bash")
        .arg("-n")
        .arg(&script)
        .output()
        .expect("bash runs");
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let r = tactrace(&t.0, &["completions", "tcsh"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
}

/// The guide's section on frames without an undeformed one (run by its
/// own test, not as part of the main path).
const NO_REST_SECTION: &str = "## No undeformed frame, or another TacTip";

/// The shell blocks of docs/getting-started.md, in order, of the sections
/// (`## ` headings) for which `keep` holds.
fn guide_blocks(keep: impl Fn(&str) -> bool) -> String {
    let text = std::fs::read_to_string(repo().join("docs/getting-started.md")).unwrap();
    let mut script = String::from("set -eu\n");
    let (mut in_sh, mut section) = (false, "");
    for line in text.lines() {
        if line.starts_with("## ") {
            section = line;
        }
        if let Some(lang) = line.trim_start().strip_prefix("```") {
            in_sh = !in_sh && lang.trim() == "sh";
            continue;
        }
        if in_sh && keep(section) {
            script.push_str(line);
            script.push('\n');
        }
    }
    script
}

/// The guide's main path: every shell block but those of
/// [`NO_REST_SECTION`].
fn guide_script() -> String {
    guide_blocks(|section| section != NO_REST_SECTION)
}

/// `bash -c script` in `dir` with the binary on the `PATH`: its stdout
/// and stderr, after asserting that it succeeded.
fn run_script(dir: &Path, script: &str) -> (String, String) {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_tactrace"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("bash")
        .arg("-c")
        .arg(script)
        .current_dir(dir)
        .env("PATH", path)
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{script}\n{stdout}\n{stderr}");
    (stdout, stderr)
}

/// `mydata/` for the guide: every `stride`-th labelled tap of the real
/// edge set (it is sorted by angle: a stride keeps every angle), its
/// frames folder linked (nothing copied).
fn my_data(data: &Path, dir: &Path, stride: usize) {
    let mine = dir.join("mydata");
    std::fs::create_dir_all(&mine).unwrap();
    std::os::unix::fs::symlink(data.join("frames"), mine.join("frames")).unwrap();
    let text = std::fs::read_to_string(data.join("targets.csv")).unwrap();
    let mut lines = text.lines();
    let mut rows = vec![lines.next().unwrap()];
    rows.extend(lines.step_by(stride));
    std::fs::write(mine.join("targets.csv"), rows.join("\n") + "\n").unwrap();
}

/// Issue 20: there was no short page for one's own data. The guide's
/// commands, run as written by bash on every other row of the public edge set
/// laid out as `mydata/`, import, train, validate on the held-out rows
/// (plots titled with the model and the data, with the MAE), calibrate,
/// and follow the disk in the real-frame world with a page that names the
/// answering frames.
#[test]
fn the_getting_started_guide_runs_as_written() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("guide");
    my_data(&data, &t.0, 2);
    let script = guide_script();
    assert!(script.matches("tactrace ").count() >= 7, "{script}");
    assert!(!script.contains("sensor inspect"), "{script}");
    let (stdout, _) = run_script(&t.0, &script);
    // The targets by their columns' names, not "position" and "angle".
    assert!(stdout.contains("  pose_2: "), "{stdout}");
    assert!(stdout.contains("  pose_6: "), "{stdout}");
    let plot =
        std::fs::read_to_string(t.join("runs/mine-validation/predicted_vs_true.svg")).unwrap();
    assert!(
        plot.contains("PDenNN mine on mine-test: pose_2, MAE"),
        "validation plot title"
    );
    let run = t.join("runs/mine-disk");
    let metrics = std::fs::read_to_string(run.join("metrics.json")).unwrap();
    assert!(metrics.contains("\"closed\": true"), "{metrics}");
    let page = std::fs::read_to_string(run.join("replay.html")).unwrap();
    let held_out = std::fs::read_to_string(t.join("test.csv")).unwrap();
    let first_name = page
        .split("\"image_names\":[\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .expect("the page names its frames");
    assert!(
        held_out.contains(first_name),
        "{first_name} is not a held-out frame"
    );
    let l2 = std::fs::read_to_string(run.join("l2_error.svg")).unwrap();
    assert!(l2.contains("arc length along the contour (mm)"));
}

/// The guide's "No undeformed frame, or another TacTip" run as written
/// (after its step 2, which splits the rows) on every tenth row of the
/// public edge set: `sensor inspect` proposes the settings and draws its
/// picture, `import` estimates the rest layout and says so, `--like`
/// reads the held-out rows against the same rest pins, and a model
/// trained on one split is scored on the other by the columns' names.
#[test]
fn the_guide_without_an_undeformed_frame_runs_as_written() {
    let Some(data) = real_data() else { return };
    let t = TempDir::new("guide-no-rest");
    my_data(&data, &t.0, 10);
    let script = guide_blocks(|section| section.starts_with("## 2.") || section == NO_REST_SECTION);
    assert!(
        script.contains("sensor inspect") && script.contains("--like"),
        "{script}"
    );
    let (stdout, stderr) = run_script(&t.0, &script);
    assert!(
        stderr.contains("no --reference: estimated the rest layout (127 pins)"),
        "{stderr}"
    );
    assert!(t.join("sensor.toml").is_file() && t.join("found.png").is_file());
    let pins = |split: &str| util::reference_pins(&t.join("data").join(split));
    assert_eq!(pins("norest-train"), pins("norest-test"));
    assert!(
        stdout.contains("  pose_2: ") && stdout.contains("  pose_6: "),
        "{stdout}"
    );
}
