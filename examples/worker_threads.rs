//! Where a remote worker's evaluation runs, timed: a batch the command
//! sends to its Ray driver (one JSON line: name, context, configurations;
//! kept by a stand-in `--python`, see docs/results.md, "Searching on
//! Ray") evaluated configuration by configuration through
//! `tactrace_lab::remote::evaluate`, once called from this process's main
//! thread (as a Ray task's Python thread calls it) and once from a thread
//! of the rayon pool (as the local executor runs an evaluation),
//! alternately (each first on every other configuration), so that both
//! see the same load. Prints each way's wall
//! and CPU seconds (the process's user + system time) summed over the
//! batch.
//!
//! ```sh
//! RAYON_NUM_THREADS=1 cargo run --release --example worker_threads -- BATCH.jsonl
//! ```
use std::time::Instant;

/// The process's user + system CPU time so far, seconds (clock ticks of
/// /proc/self/stat, 100 a second).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("procfs");
    let after = &stat[stat.rfind(')').expect("comm") + 2..];
    let fields: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = fields[11].parse::<f64>().unwrap() + fields[12].parse::<f64>().unwrap();
    ticks / 100.0
}

/// One evaluation timed: (wall, CPU) seconds.
fn timed(run: impl FnOnce() -> String) -> (f64, f64) {
    let (c0, w0) = (cpu_seconds(), Instant::now());
    let score = run();
    assert!(!score.is_empty());
    (w0.elapsed().as_secs_f64(), cpu_seconds() - c0)
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .expect("usage: worker_threads BATCH.jsonl");
    let text = std::fs::read_to_string(&path).expect("the batch file");
    let batch: serde_json::Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    let name = batch["name"].as_str().unwrap().to_string();
    let context = batch["context"].as_str().unwrap().to_string();
    if let Some(cwd) = batch["cwd"].as_str() {
        std::env::set_current_dir(cwd).unwrap();
    }
    let configs: Vec<String> = batch["configs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap().to_string())
        .collect();
    let eval = |config: &str| tactrace_lab::remote::evaluate(&name, &context, config).unwrap();
    // The evaluation is built (the dataset read) by the first call: untimed.
    eval(&configs[0]);
    let (mut caller, mut pool) = ((0.0, 0.0), (0.0, 0.0));
    for (i, config) in configs.iter().enumerate() {
        // Each way goes first on every other configuration.
        for way in [i % 2, 1 - i % 2] {
            if way == 0 {
                let (w, c) = timed(|| eval(config));
                caller = (caller.0 + w, caller.1 + c);
            } else {
                let (w, c) = timed(|| {
                    let mut score = String::new();
                    rayon::scope(|_| score = eval(config));
                    score
                });
                pool = (pool.0 + w, pool.1 + c);
            }
        }
    }
    println!(
        "{} evaluations, rayon threads {}",
        configs.len(),
        rayon::current_num_threads()
    );
    println!(
        "caller's thread: {:.2} s wall, {:.2} s CPU",
        caller.0, caller.1
    );
    println!("a pool thread:   {:.2} s wall, {:.2} s CPU", pool.0, pool.1);
    println!("caller / pool wall: {:.3}", caller.0 / pool.0);
}
