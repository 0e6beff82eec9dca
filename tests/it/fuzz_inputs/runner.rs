//! Running the `tactrace` binary with a hard time limit and a memory cap,
//! and judging its outcome: a clean exit (0, 1, 2) with a human message.
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// A child still running after this long is a hang.
pub const TIME_LIMIT: Duration = Duration::from_secs(20);
/// Address-space cap of a child, KiB (an allocation past it aborts).
const MEMORY_KIB: u64 = 4 * 1024 * 1024;

/// What one run did.
pub struct Outcome {
    /// Exit code, or None when killed by a signal or the time limit.
    pub code: Option<i32>,
    pub signal: Option<i32>,
    pub timed_out: bool,
    pub stderr: String,
    pub elapsed: Duration,
}

/// Run `tactrace args` in `dir`; stdout and stderr go to files there.
pub fn run(dir: &Path, args: &[String]) -> Outcome {
    let bin = Path::new(env!("CARGO_BIN_EXE_tactrace"));
    run_program(bin, dir, args, TIME_LIMIT)
}

/// Run any `program` the way [`run`] runs tactrace, killed after `limit`.
pub fn run_program(program: &Path, dir: &Path, args: &[String], limit: Duration) -> Outcome {
    let (out, err) = (dir.join("stdout.txt"), dir.join("stderr.txt"));
    let start = Instant::now();
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {MEMORY_KIB}; exec \"$0\" \"$@\""))
        .arg(program)
        .args(args)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).expect("stdout file"))
        .stderr(std::fs::File::create(&err).expect("stderr file"))
        .spawn()
        .expect("spawn tactrace");
    let (status, timed_out) = wait_limited(&mut child, limit);
    let stderr = String::from_utf8_lossy(&std::fs::read(&err).unwrap_or_default()).into_owned();
    Outcome {
        code: status.and_then(|s| s.code()),
        signal: status.and_then(signal_of),
        timed_out,
        stderr,
        elapsed: start.elapsed(),
    }
}

/// Wait for the child, killing it at the time limit.
fn wait_limited(child: &mut std::process::Child, limit: Duration) -> (Option<ExitStatus>, bool) {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().expect("wait for tactrace") {
            return (Some(s), false);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return (None, true);
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[cfg(unix)]
fn signal_of(s: ExitStatus) -> Option<i32> {
    std::os::unix::process::ExitStatusExt::signal(&s)
}

#[cfg(not(unix))]
fn signal_of(_: ExitStatus) -> Option<i32> {
    None
}

/// Why an outcome is a failure, or None when it is a clean exit.
pub fn verdict(o: &Outcome) -> Option<String> {
    if o.timed_out {
        return Some(format!("hang: still running after {:?}", o.elapsed));
    }
    if let Some(sig) = o.signal {
        return Some(format!("killed by signal {sig}"));
    }
    match o.code {
        Some(0) => None,
        Some(1 | 2) => message_problem(&o.stderr),
        Some(c) => Some(format!("exit code {c}")),
        None => Some("no exit code".into()),
    }
}

/// A failing run must say what went wrong like a person would.
fn message_problem(stderr: &str) -> Option<String> {
    if stderr.contains("panicked at") {
        return Some("a panic message on stderr".into());
    }
    let Some(line) = stderr.lines().find(|l| l.starts_with("error: ")) else {
        return Some("no `error: ...` line on stderr".into());
    };
    if let Some(what) = debug_struct(stderr) {
        return Some(format!("a Rust debug value in the message: `{what}`"));
    }
    if line.trim() == "error:" || stderr.lines().count() > 25 {
        return Some("an empty or very long error message".into());
    }
    None
}

/// The first `Name { field: ` or `Some(`-style debug rendering in `s`.
fn debug_struct(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    for (i, w) in s.match_indices(" { ") {
        let name_start = s[..i]
            .rfind(|c: char| !c.is_alphanumeric() && c != '_')
            .map_or(0, |k| k + 1);
        let name = &s[name_start..i];
        let rest = &s[i + w.len()..];
        let field = rest.split(':').next().unwrap_or("");
        let is_field =
            !field.is_empty() && field.chars().all(|c| c.is_ascii_lowercase() || c == '_');
        if name.starts_with(|c: char| c.is_ascii_uppercase()) && is_field && bytes.len() > i {
            return Some(format!("{name} {{ {field}: .."));
        }
    }
    ["Some(", "Ok(", "Err(", "Os { code"]
        .into_iter()
        .find(|p| s.contains(p))
        .map(str::to_owned)
}
