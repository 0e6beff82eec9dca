//! The Ray executor: a batch handed to the Python package's
//! `tactrace.ray_executor` (one process per executor, started at the first
//! batch), which hands the configurations to its Ray workers (one actor
//! per `cpus_per_task` CPUs of the cluster, kept for the executor's life)
//! and answers with the scores in order.
//!
//! The pipe carries one JSON line each way. First the process says
//! `{"ready": {...}}` (or `{"error": {...}}`); then per batch the command
//! writes `{"name", "context", "cwd", "configs": [text...]}` and reads
//! `{"scores": [text...]}` or `{"error": {"kind", "message",
//! "bad_input"}}`. Configurations and scores stay JSON text end to end:
//! Python never parses them, so no float is rounded on the way.
use super::RemoteError;
use serde::Deserialize;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};
use tactrace_optim::{Evaluation, Executor, RunError};

/// Where and how to run on Ray.
#[derive(Debug, Clone)]
pub struct RaySettings {
    /// The cluster's address (`HOST:PORT` of the head, or `auto`).
    pub address: String,
    /// The Python interpreter with ray and the tactrace package.
    pub python: PathBuf,
    /// CPUs each task asks of Ray (and rayon threads it runs on).
    pub cpus_per_task: usize,
}

/// Batches run as Ray tasks ([`RaySettings`]).
pub struct RayExecutor {
    settings: RaySettings,
    driver: Mutex<Option<Driver>>,
}

/// The running `tactrace.ray_executor` process.
struct Driver {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    stderr: Arc<Mutex<Vec<String>>>,
}

/// What the process says of the cluster it joined.
#[derive(Debug, Clone, Deserialize)]
pub struct ClusterInfo {
    /// Nodes alive.
    pub nodes: usize,
    /// CPUs in all.
    pub cpus: f64,
    /// Worker processes started for the evaluations (one per
    /// `cpus_per_task` CPUs), each keeping its evaluation built.
    #[serde(default)]
    pub workers: usize,
}

/// A line from the process.
#[derive(Deserialize)]
#[serde(rename_all = "snake_case")]
enum Answer {
    Ready(ClusterInfo),
    Scores(Vec<String>),
    Error(Failure),
}

#[derive(Deserialize)]
struct Failure {
    kind: String,
    message: String,
    #[serde(default)]
    bad_input: bool,
}

impl RayExecutor {
    /// The executor (nothing is started before the first batch).
    pub fn new(settings: RaySettings) -> Self {
        RayExecutor {
            settings,
            driver: Mutex::new(None),
        }
    }

    /// Start the process and join the cluster now (the first batch does
    /// it otherwise); what the cluster said of itself.
    pub fn connect(&self) -> Result<ClusterInfo, RemoteError> {
        let mut guard = self.driver.lock().unwrap_or_else(|p| p.into_inner());
        let (driver, ready) = self.start()?;
        *guard = Some(driver);
        Ok(ready)
    }

    fn start(&self) -> Result<(Driver, ClusterInfo), RemoteError> {
        let s = &self.settings;
        let mut child = Command::new(&s.python)
            .args(["-m", "tactrace.ray_executor", "--address", &s.address])
            .args(["--cpus-per-task", &s.cpus_per_task.to_string()])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|source| RemoteError::PythonNotFound {
                python: s.python.clone(),
                source,
            })?;
        let stderr = Arc::new(Mutex::new(Vec::new()));
        let tail = stderr.clone();
        let mut pipe = child.stderr.take().expect("stderr is piped");
        std::thread::spawn(move || keep_tail(&mut pipe, &tail));
        let mut driver = Driver {
            stdin: child.stdin.take().expect("stdin is piped"),
            stdout: BufReader::new(child.stdout.take().expect("stdout is piped")),
            child,
            stderr,
        };
        match driver.read(s)? {
            Answer::Ready(info) => Ok((driver, info)),
            Answer::Scores(_) => Err(RemoteError::Protocol {
                what: "answered before it was asked".into(),
            }),
            Answer::Error(f) => Err(failure(s, "", f)),
        }
    }
}

impl Driver {
    /// The next line, parsed; the end of the output is the process's
    /// failure, told by the last line of its standard error.
    fn read(&mut self, s: &RaySettings) -> Result<Answer, RemoteError> {
        let mut line = String::new();
        let n = self
            .stdout
            .read_line(&mut line)
            .map_err(RemoteError::Pipe)?;
        if n == 0 {
            let _ = self.child.wait();
            // The stderr thread ends with the process; give it a moment.
            std::thread::sleep(std::time::Duration::from_millis(100));
            let tail = self.stderr.lock().unwrap_or_else(|p| p.into_inner());
            let reason = tail
                .last()
                .cloned()
                .unwrap_or_else(|| "it ended without a word".into());
            return Err(RemoteError::Setup {
                python: s.python.clone(),
                reason,
            });
        }
        serde_json::from_str(&line).map_err(|e| RemoteError::Protocol {
            what: format!("wrote a line that is not an answer ({e})"),
        })
    }
}

impl Drop for RayExecutor {
    fn drop(&mut self) {
        if let Some(mut d) = self.driver.lock().unwrap_or_else(|p| p.into_inner()).take() {
            drop(d.stdin); // the process ends at the end of its input
            let _ = d.child.wait();
        }
    }
}

/// Keep the last lines the process writes on its standard error.
fn keep_tail(pipe: &mut impl Read, tail: &Mutex<Vec<String>>) {
    for line in BufReader::new(pipe).lines().map_while(|l| l.ok()) {
        let mut t = tail.lock().unwrap_or_else(|p| p.into_inner());
        if !line.trim().is_empty() {
            t.push(line);
        }
        if t.len() > 50 {
            t.remove(0);
        }
    }
}

/// The typed error of a failure the process reported.
fn failure(s: &RaySettings, evaluation: &str, f: Failure) -> RemoteError {
    match f.kind.as_str() {
        "setup" => RemoteError::Setup {
            python: s.python.clone(),
            reason: f.message,
        },
        "unreachable" => RemoteError::Unreachable {
            address: s.address.clone(),
            reason: f.message,
        },
        "evaluation" => RemoteError::Evaluation {
            evaluation: evaluation.into(),
            message: f.message,
            bad_input: f.bad_input,
        },
        _ => RemoteError::Protocol { what: f.message },
    }
}

impl Executor for RayExecutor {
    fn run<E: Evaluation>(
        &self,
        evaluation: &E,
        configs: &[E::Config],
    ) -> Result<Vec<E::Score>, RunError<E::Error>> {
        self.batch(evaluation, configs)
            .map_err(|e| RunError::Executor(Box::new(e)))
    }
}

impl RayExecutor {
    fn batch<E: Evaluation>(
        &self,
        evaluation: &E,
        configs: &[E::Config],
    ) -> Result<Vec<E::Score>, RemoteError> {
        let json = |what, source| RemoteError::Json {
            evaluation: E::NAME.into(),
            what,
            source,
        };
        let context = evaluation.context().ok_or_else(|| RemoteError::NotRemote {
            evaluation: E::NAME.into(),
        })?;
        let configs = configs
            .iter()
            .map(|c| serde_json::to_string(c).map_err(|e| json("configuration", e)))
            .collect::<Result<Vec<_>, _>>()?;
        let cwd = std::env::current_dir().map_err(RemoteError::Pipe)?;
        let request = serde_json::json!({
            "name": E::NAME,
            "context": context,
            "cwd": cwd,
            "configs": configs,
        });
        let mut guard = self.driver.lock().unwrap_or_else(|p| p.into_inner());
        if guard.is_none() {
            *guard = Some(self.start()?.0);
        }
        let driver = guard.as_mut().expect("started above");
        writeln!(driver.stdin, "{request}").map_err(RemoteError::Pipe)?;
        driver.stdin.flush().map_err(RemoteError::Pipe)?;
        let scores = match driver.read(&self.settings) {
            Ok(Answer::Scores(scores)) => scores,
            Ok(Answer::Error(f)) => return Err(failure(&self.settings, E::NAME, f)),
            Ok(Answer::Ready(_)) => {
                return Err(RemoteError::Protocol {
                    what: "said it was ready again".into(),
                })
            }
            Err(RemoteError::Setup { reason, .. }) => {
                *guard = None;
                return Err(RemoteError::Protocol {
                    what: format!("ended during a batch: {reason}"),
                });
            }
            Err(e) => return Err(e),
        };
        if scores.len() != configs.len() {
            return Err(RemoteError::Protocol {
                what: format!(
                    "gave {} scores for {} configurations",
                    scores.len(),
                    configs.len()
                ),
            });
        }
        scores
            .iter()
            .map(|s| serde_json::from_str(s).map_err(|e| json("score", e)))
            .collect()
    }
}
