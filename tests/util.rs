//! Helpers for end-to-end tests: run the real binary in a temp dir.
#![allow(dead_code)]
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The outcome of one `tactrace` invocation.
pub struct Run {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

/// A fresh temporary directory for one test (`tempfile`), removed on drop;
/// `.0` is its path.
pub struct TempDir(pub PathBuf, tempfile::TempDir);

impl TempDir {
    pub fn new(name: &str) -> Self {
        let dir = tempfile::Builder::new()
            .prefix(&format!("tactrace-test-{name}-"))
            .tempdir()
            .expect("a temporary directory");
        Self(dir.path().to_path_buf(), dir)
    }
    pub fn join(&self, s: &str) -> PathBuf {
        self.0.join(s)
    }
}

/// Run `tactrace args...` with `dir` as the working directory.
pub fn tactrace(dir: &Path, args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("binary runs");
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// The real TacTip data folder; see `tactrace_testdata` for what happens
/// when it is absent.
pub fn real_data() -> Option<PathBuf> {
    tactrace_testdata::real_edge_set()
}

/// The real set's frames folder, labels file and reference frame, as
/// arguments.
pub fn real_paths(data: &Path) -> [String; 3] {
    let frames = data.join("frames");
    [
        frames.display().to_string(),
        data.join("targets.csv").display().to_string(),
        frames.join("init_0.png").display().to_string(),
    ]
}

/// Run `tactrace args...` in `dir`, read the first `lines` lines of its
/// standard output, then close the pipe (`tactrace ... | head -n LINES`).
pub fn tactrace_head(dir: &Path, args: &[&str], lines: usize) -> Run {
    use std::io::{BufRead, BufReader, Read};
    let mut child = Command::new(env!("CARGO_BIN_EXE_tactrace"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("binary runs");
    let mut stdout = String::new();
    {
        let mut out = BufReader::new(child.stdout.take().expect("piped stdout"));
        for _ in 0..lines {
            if out.read_line(&mut stdout).expect("stdout readable") == 0 {
                break;
            }
        }
        // Dropping the reader closes the pipe.
    }
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("piped stderr")
        .read_to_string(&mut stderr)
        .expect("stderr readable");
    let status = child.wait().expect("binary ends");
    Run {
        code: status.code().unwrap_or(-1),
        stdout,
        stderr,
    }
}
