//! Mutation fuzz of every file the CLI reads (issue 10): frames, contour and
//! targets CSVs, TOML configs, datasets and model files. Valid seeds are
//! made by the CLI itself in a temp dir, mutated with a seeded ChaCha RNG,
//! and each mutant is fed to the commands that read it, with a hard time
//! limit and a memory cap. A run must end with exit code 0, 1 or 2 and,
//! when it fails, a human `error: ...` message: never a panic (101), a
//! signal, a hang or a Rust debug value.
//!
//! `TACTRACE_FUZZ_CASES=N` sets the number of inputs (default 1500),
//! `TACTRACE_FUZZ_SEED=S` the seed (default 1). Failing inputs are kept
//! under the folder printed in the failure message, with the command.
mod image_mut;
mod kinds;
mod mutate;
mod runner;
mod seeds;
mod tree_mut;

use kinds::{Kind, KINDS};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

const DEFAULT_CASES: usize = 1500;

/// One mutated input that made the CLI misbehave.
struct Finding {
    kind: &'static str,
    mutation: &'static str,
    args: Vec<String>,
    why: String,
    stderr: String,
    kept: PathBuf,
}

/// Per-kind counters: inputs run and exit codes seen.
#[derive(Default)]
struct Tally {
    inputs: usize,
    codes: BTreeMap<String, usize>,
    /// The slowest run, seconds.
    slowest: f64,
}

/// What all workers share.
struct Shared {
    base: PathBuf,
    seed: u64,
    next: Mutex<usize>,
    tallies: Mutex<BTreeMap<&'static str, Tally>>,
    findings: Mutex<Vec<Finding>>,
}

fn env_number(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(v) => v
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("{name}={v} is not a number")),
        Err(_) => default,
    }
}

#[test]
fn mutated_inputs_never_panic_or_hang() {
    let cases = env_number("TACTRACE_FUZZ_CASES", DEFAULT_CASES as u64) as usize;
    let seed = env_number("TACTRACE_FUZZ_SEED", 1);
    let root = tempfile::tempdir().expect("temp dir");
    let base = root.path().join("base");
    std::fs::create_dir_all(&base).expect("base dir");
    seeds::make(&base);
    eprintln!(
        "fuzz: seed {seed}, {cases} inputs over {} file kinds",
        KINDS.len()
    );
    let shared = Shared {
        base,
        seed,
        next: Mutex::new(0),
        tallies: Mutex::new(BTreeMap::new()),
        findings: Mutex::new(Vec::new()),
    };
    let start = Instant::now();
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get().min(2));
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| worker(&shared, cases, root.path()));
        }
    });
    report(&shared, cases, start.elapsed().as_secs_f64());
}

/// The judge itself: a hang, a signal, a panic and a debug value in the
/// message are failures; a plain `error:` line with exit code 2 is not.
#[test]
fn the_judge_fails_hangs_signals_panics_and_debug_text() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sh = |script: &str, limit: u64| {
        let args = ["-c".to_string(), script.to_string()];
        let limit = std::time::Duration::from_secs(limit);
        runner::run_program(Path::new("/bin/sh"), dir.path(), &args, limit)
    };
    let hang = sh("sleep 30", 1);
    assert!(hang.timed_out && hang.elapsed.as_secs() < 10);
    assert!(runner::verdict(&hang).is_some_and(|v| v.starts_with("hang")));
    let abort = sh("kill -ABRT $$", 10);
    assert_eq!(abort.signal, Some(6));
    for bad in [
        "echo \"thread 'main' panicked at src/x.rs:1:1:\" >&2; exit 101",
        "echo 'error: panicked at src/x.rs:1:1' >&2; exit 1",
        "echo 'error: bad pose Pose { x: 1.0, y: 2.0 }' >&2; exit 2",
        "echo 'error: not a number: Some(3)' >&2; exit 2",
        "echo 'nothing useful' >&2; exit 2",
        "exit 3",
    ] {
        assert!(runner::verdict(&sh(bad, 10)).is_some(), "{bad}");
    }
    let fine = sh(
        "echo 'error: x.csv: line 3: `nan` is not a number' >&2; exit 2",
        10,
    );
    assert_eq!(runner::verdict(&fine), None, "{}", fine.stderr);
}

/// Take case numbers until the budget is spent.
fn worker(shared: &Shared, cases: usize, root: &Path) {
    loop {
        let i = {
            let mut next = shared.next.lock().expect("counter");
            *next += 1;
            *next - 1
        };
        if i >= cases {
            return;
        }
        run_case(shared, i, root);
    }
}

/// Mutate one input for case `i`, run its command, judge the outcome.
fn run_case(shared: &Shared, i: usize, root: &Path) {
    let kind = &KINDS[i % KINDS.len()];
    let mut rng =
        ChaCha8Rng::seed_from_u64(shared.seed.wrapping_mul(1_000_003).wrapping_add(i as u64));
    let case = tempfile::Builder::new()
        .prefix("case")
        .tempdir_in(root)
        .expect("case dir");
    let mutation = write_mutant(&shared.base, case.path(), kind, &mut rng);
    let template = kind.commands[(i / KINDS.len()) % kind.commands.len()];
    let args = expand(template, &shared.base, case.path());
    let outcome = runner::run(case.path(), &args);
    let verdict = runner::verdict(&outcome);
    tally(shared, kind.name, &outcome);
    if let Some(why) = verdict {
        let kept = keep(shared, case.path(), i, kind.name);
        let stderr = outcome
            .stderr
            .lines()
            .take(12)
            .collect::<Vec<_>>()
            .join("\n");
        let args = expand(template, &kept.join("../base"), &kept);
        let f = Finding {
            kind: kind.name,
            mutation,
            args,
            why,
            stderr,
            kept,
        };
        shared.findings.lock().expect("findings").push(f);
    }
}

/// Copy the kind's folder (if any) and write the mutated seed into `case`.
fn write_mutant(base: &Path, case: &Path, kind: &Kind, rng: &mut ChaCha8Rng) -> &'static str {
    if let Some((from, to)) = kind.copy_dir {
        copy_files(&base.join(from), &case.join(to));
    }
    let seed = std::fs::read(base.join(kind.seed)).expect("seed file");
    let (bytes, mutation) = mutate::mutate(&seed, kind.format, rng);
    let target = case.join(kind.target);
    std::fs::create_dir_all(target.parent().expect("parent")).expect("target dir");
    std::fs::write(&target, bytes).expect("write mutant");
    mutation
}

/// Copy the plain files of `from` (not sub-folders) into `to`.
fn copy_files(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("copy dir");
    for entry in std::fs::read_dir(from).expect("seed dir") {
        let p = entry.expect("entry").path();
        if p.is_file() {
            std::fs::copy(&p, to.join(p.file_name().expect("name"))).expect("copy seed");
        }
    }
}

/// Fill `{base}` and `{case}` into a command template.
fn expand(template: &[&str], base: &Path, case: &Path) -> Vec<String> {
    let (b, c) = (base.display().to_string(), case.display().to_string());
    template
        .iter()
        .map(|a| a.replace("{base}", &b).replace("{case}", &c))
        .collect()
}

fn tally(shared: &Shared, kind: &'static str, o: &runner::Outcome) {
    let code = match (o.code, o.signal, o.timed_out) {
        (_, _, true) => "hang".to_string(),
        (Some(c), _, _) => c.to_string(),
        (None, Some(s), _) => format!("signal {s}"),
        _ => "?".into(),
    };
    let mut t = shared.tallies.lock().expect("tallies");
    let k = t.entry(kind).or_default();
    k.inputs += 1;
    k.slowest = k.slowest.max(o.elapsed.as_secs_f64());
    *k.codes.entry(code).or_default() += 1;
}

/// The folder failing inputs are kept in (with a copy of the seeds).
fn crash_root(seed: u64) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("fuzz-crashes-seed{seed}"))
}

/// Keep a failing case (and the seeds once) for reproduction.
fn keep(shared: &Shared, case: &Path, i: usize, kind: &str) -> PathBuf {
    let root = crash_root(shared.seed);
    if !root.join("base").exists() {
        copy_tree(&shared.base, &root.join("base"));
    }
    let dest = root.join(format!("case{i:05}-{kind}"));
    let _ = std::fs::remove_dir_all(&dest);
    copy_tree(case, &dest);
    dest
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("keep dir");
    for entry in std::fs::read_dir(from).expect("read dir").flatten() {
        let p = entry.path();
        let dest = to.join(entry.file_name());
        if p.is_dir() {
            copy_tree(&p, &dest);
        } else {
            let _ = std::fs::copy(&p, &dest);
        }
    }
}

/// Print the per-kind counts, then fail with every finding.
fn report(shared: &Shared, cases: usize, secs: f64) {
    let tallies = shared.tallies.lock().expect("tallies");
    let ran: usize = tallies.values().map(|t| t.inputs).sum();
    eprintln!(
        "fuzz: ran {ran} inputs in {secs:.1} s (seed {})",
        shared.seed
    );
    for (kind, t) in tallies.iter() {
        let (n, codes, slow) = (t.inputs, &t.codes, t.slowest);
        eprintln!("  {kind:<18} {n:>5} inputs, slowest {slow:.2} s, exit codes {codes:?}");
    }
    assert_eq!(ran, cases, "every input must run");
    let findings = shared.findings.lock().expect("findings");
    for f in findings.iter() {
        eprintln!(
            "\nFAIL [{}] ({}): {}\n  kept in {}\n  reproduce: tactrace {}\n  stderr:\n{}",
            f.kind,
            f.mutation,
            f.why,
            f.kept.display(),
            f.args.join(" "),
            f.stderr
        );
    }
    assert!(
        findings.is_empty(),
        "{} of {ran} inputs made tactrace misbehave (seed {}); inputs kept under {}",
        findings.len(),
        shared.seed,
        crash_root(shared.seed).display()
    );
}
