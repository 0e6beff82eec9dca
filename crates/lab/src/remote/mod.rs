//! Evaluations run elsewhere: the executor the commands choose
//! ([`Exec`]: this machine or a Ray cluster) and the worker's side
//! ([`prepare`] and [`evaluate`]: an evaluation rebuilt from its name and
//! context, then run on one configuration).
//!
//! A remote batch crosses two processes as JSON text: the command writes
//! the evaluation's name, its context (data paths and fixed settings,
//! [`Evaluation::context`]) and each configuration; the Python package's
//! `tactrace.ray_executor` submits one Ray task per configuration; each
//! task calls `tactrace._tactrace.evaluate`, which is [`evaluate`]. Floats
//! are written shortest-round-trip and parsed exactly (serde_json's
//! `float_roundtrip`), so a worker sees the very bits the command had and
//! the scores equal the local executor's.
mod error;
mod ray;

pub use error::RemoteError;
pub use ray::{ClusterInfo, RayExecutor, RaySettings};

use crate::error::{LabError, Result};
use std::any::Any;
use std::sync::{Arc, Mutex};
use tactrace_optim::{Evaluation, Executor, Local, RunError};

/// The executor a command was given.
pub enum Exec {
    /// rayon threads on this machine (the default).
    Local,
    /// Ray tasks on the cluster at an address (`tactrace.ray_executor`).
    Ray(RayExecutor),
}

impl Executor for Exec {
    fn run<E: Evaluation>(
        &self,
        evaluation: &E,
        configs: &[E::Config],
    ) -> std::result::Result<Vec<E::Score>, RunError<E::Error>> {
        match self {
            Exec::Local => Local.run(evaluation, configs),
            Exec::Ray(ray) => ray.run(evaluation, configs),
        }
    }
}

impl From<RunError<LabError>> for LabError {
    fn from(e: RunError<LabError>) -> Self {
        match e {
            RunError::Evaluation(e) => e,
            RunError::Executor(source) => match source.downcast::<RemoteError>() {
                Ok(remote) => LabError::Remote(*remote),
                Err(other) => LabError::Remote(RemoteError::Protocol {
                    what: format!("failed: {other}"),
                }),
            },
        }
    }
}

/// Run the evaluation named `name`, rebuilt from `context`, on one
/// configuration; the score as JSON. What a remote worker calls (through
/// the Python package); an evaluation is rebuilt once per process and
/// context, then reused.
pub fn evaluate(name: &str, context: &str, config: &str) -> Result<String> {
    use crate::search::PoseTrial;
    use crate::transfer_fit::TransferTrial;
    use crate::tune::{HeldOutTrial, TuneTrial};
    match name {
        PoseTrial::NAME => run_one(context, config, PoseTrial::from_context),
        TransferTrial::NAME => run_one(context, config, TransferTrial::from_context),
        TuneTrial::NAME => run_one(context, config, TuneTrial::from_context),
        HeldOutTrial::NAME => run_one(context, config, HeldOutTrial::from_context),
        _ => Err(RemoteError::UnknownEvaluation { name: name.into() }.into()),
    }
}

/// Build the evaluation named `name` from `context` and keep it for the
/// calls of [`evaluate`] that follow (reading its data now, not inside the
/// first evaluation); whether it was built now (false: it was kept from
/// before). What a remote worker calls before its first configuration, so
/// that the start-up is timed apart from the evaluations.
pub fn prepare(name: &str, context: &str) -> Result<bool> {
    use crate::search::PoseTrial;
    use crate::transfer_fit::TransferTrial;
    use crate::tune::{HeldOutTrial, TuneTrial};
    match name {
        PoseTrial::NAME => keep(context, PoseTrial::from_context),
        TransferTrial::NAME => keep(context, TransferTrial::from_context),
        TuneTrial::NAME => keep(context, TuneTrial::from_context),
        HeldOutTrial::NAME => keep(context, HeldOutTrial::from_context),
        _ => Err(RemoteError::UnknownEvaluation { name: name.into() }.into()),
    }
}

/// The evaluation of `context` built and kept; whether it was built now.
fn keep<E: Evaluation + Send + Sync + 'static>(
    context: &str,
    make: fn(&str) -> Result<E>,
) -> Result<bool> {
    built(E::NAME, context, || make(context)).map(|(_, fresh)| fresh)
}

/// The evaluation of `context` (built, or the one built last), run on
/// `config`.
fn run_one<E>(context: &str, config: &str, make: fn(&str) -> Result<E>) -> Result<String>
where
    E: Evaluation<Error = LabError> + Send + 'static,
{
    let (evaluation, _) = built(E::NAME, context, || make(context))?;
    let json = |what, source| RemoteError::Json {
        evaluation: E::NAME.into(),
        what,
        source,
    };
    let config: E::Config = serde_json::from_str(config).map_err(|e| json("configuration", e))?;
    let score = evaluation.evaluate(&config)?;
    Ok(serde_json::to_string(&score).map_err(|e| json("score", e))?)
}

/// The last evaluation built in this process: its name, context, itself.
type Built = (String, String, Arc<dyn Any + Send + Sync>);

static LAST_BUILT: Mutex<Option<Built>> = Mutex::new(None);

/// The evaluation `name` of `context`: the one kept from the last call
/// when it was the same, else made (and kept); and whether it was made now.
fn built<E: Send + Sync + 'static>(
    name: &str,
    context: &str,
    make: impl FnOnce() -> Result<E>,
) -> Result<(Arc<E>, bool)> {
    let last = LAST_BUILT.lock().unwrap_or_else(|p| p.into_inner()).clone();
    if let Some((n, c, e)) = last {
        if n == name && c == context {
            if let Ok(e) = e.downcast::<E>() {
                return Ok((e, false));
            }
        }
    }
    let made = Arc::new(make()?);
    let kept: Arc<dyn Any + Send + Sync> = made.clone();
    *LAST_BUILT.lock().unwrap_or_else(|p| p.into_inner()) =
        Some((name.to_string(), context.to_string(), kept));
    Ok((made, true))
}

/// `value` as the JSON of a context; a failure names the evaluation.
pub(crate) fn context_json(evaluation: &str, value: &impl serde::Serialize) -> Option<String> {
    serde_json::to_string(value)
        .map_err(|e| {
            debug_assert!(false, "the context of {evaluation} does not serialise: {e}");
        })
        .ok()
}

/// A context read back, or a typed error naming the evaluation.
pub(crate) fn parse_context<T: serde::de::DeserializeOwned>(
    evaluation: &str,
    context: &str,
) -> Result<T> {
    serde_json::from_str(context).map_err(|source| {
        RemoteError::Json {
            evaluation: evaluation.into(),
            what: "context",
            source,
        }
        .into()
    })
}
