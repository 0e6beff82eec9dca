//! Where many evaluations run: an [`Executor`] takes a batch of
//! configurations and returns their scores, in order. [`Local`] runs them
//! on rayon threads on this machine; a distributed executor (Ray, through
//! the Python package: `tactrace_lab::remote`) submits the same
//! evaluations elsewhere, because an [`Evaluation`] is a pure function of
//! its configuration (seed included), its configurations and scores
//! serialise, it is named ([`Evaluation::NAME`]) so a remote worker finds
//! the same function, and it says what a worker needs to rebuild it
//! ([`Evaluation::context`]: dataset paths and fixed settings).
use rayon::prelude::*;
use serde::de::DeserializeOwned;
use serde::Serialize;

/// One kind of evaluation: a pure function from a configuration (which
/// carries its own seed) to a score. Equal configurations give equal
/// scores, wherever and in whatever order they run.
pub trait Evaluation: Sync {
    /// A stable name a remote executor dispatches on.
    const NAME: &'static str;
    /// What is evaluated; serialisable so it can be sent elsewhere.
    type Config: Serialize + DeserializeOwned + Sync;
    /// What comes back; serialisable for the same reason.
    type Score: Serialize + DeserializeOwned + Send;
    /// Why an evaluation could not be made at all (a bad score is a
    /// score, not an error).
    type Error: std::error::Error + Send + Sync + 'static;

    /// Evaluate one configuration.
    fn evaluate(&self, config: &Self::Config) -> Result<Self::Score, Self::Error>;

    /// What a remote worker rebuilds this evaluation from (JSON: data
    /// paths and fixed settings, never the data); `None` when it can only
    /// run here.
    fn context(&self) -> Option<String> {
        None
    }
}

/// Why a batch did not give its scores.
#[derive(Debug, thiserror::Error)]
pub enum RunError<E: std::error::Error + 'static> {
    /// An evaluation failed (on this machine, with its own typed error).
    #[error(transparent)]
    Evaluation(E),
    /// The executor failed: its workers could not be reached, or a remote
    /// evaluation failed (the source says why).
    #[error(transparent)]
    Executor(Box<dyn std::error::Error + Send + Sync>),
}

/// Runs a batch of evaluations; the scores come back in the order of
/// `configs`, and do not depend on the executor.
pub trait Executor {
    /// Evaluate every configuration of `configs`.
    fn run<E: Evaluation>(
        &self,
        evaluation: &E,
        configs: &[E::Config],
    ) -> Result<Vec<E::Score>, RunError<E::Error>>;
}

/// This machine: the batch spread over rayon's global thread pool.
#[derive(Debug, Clone, Copy, Default)]
pub struct Local;

impl Executor for Local {
    fn run<E: Evaluation>(
        &self,
        evaluation: &E,
        configs: &[E::Config],
    ) -> Result<Vec<E::Score>, RunError<E::Error>> {
        configs
            .par_iter()
            .map(|c| evaluation.evaluate(c))
            .collect::<Result<Vec<_>, _>>()
            .map_err(RunError::Evaluation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("negative input {0}")]
    struct Negative(f64);

    struct Square;
    impl Evaluation for Square {
        const NAME: &'static str = "square";
        type Config = (f64, u64);
        type Score = f64;
        type Error = Negative;
        fn evaluate(&self, &(x, seed): &(f64, u64)) -> Result<f64, Negative> {
            if x < 0.0 {
                return Err(Negative(x));
            }
            Ok(x * x + seed as f64)
        }
    }

    #[test]
    fn local_executor_keeps_the_order_of_the_batch() {
        let configs: Vec<(f64, u64)> = (0..50).map(|k| (k as f64, k % 3)).collect();
        let got = Local.run(&Square, &configs).unwrap();
        let want: Vec<f64> = configs
            .iter()
            .map(|c| Square.evaluate(c).unwrap())
            .collect();
        assert_eq!(got, want);
    }

    #[test]
    fn local_executor_returns_an_evaluations_own_error() {
        let configs = [(1.0, 0), (-2.0, 0), (3.0, 0)];
        match Local.run(&Square, &configs) {
            Err(RunError::Evaluation(Negative(x))) => assert_eq!(x, -2.0),
            other => panic!("expected the evaluation's error, got {other:?}"),
        }
        assert_eq!(Square.context(), None);
    }
}
