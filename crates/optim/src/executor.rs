//! Where many evaluations run: an [`Executor`] takes a batch of
//! configurations and returns their scores, in order. Today's
//! implementation is [`Local`] (rayon threads on this machine); a
//! distributed one (Ray, through the Python package) can submit the same
//! evaluations, because an [`Evaluation`] is a pure function of its
//! configuration (seed included), its configurations serialise, and it is
//! named ([`Evaluation::NAME`]) so a remote worker can find the same
//! function.
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

    /// Evaluate one configuration.
    fn evaluate(&self, config: &Self::Config) -> Self::Score;
}

/// Runs a batch of evaluations; the scores come back in the order of
/// `configs`, and do not depend on the executor.
pub trait Executor {
    /// Evaluate every configuration of `configs`.
    fn run<E: Evaluation>(&self, evaluation: &E, configs: &[E::Config]) -> Vec<E::Score>;
}

/// This machine: the batch spread over rayon's global thread pool.
#[derive(Debug, Clone, Copy, Default)]
pub struct Local;

impl Executor for Local {
    fn run<E: Evaluation>(&self, evaluation: &E, configs: &[E::Config]) -> Vec<E::Score> {
        configs.par_iter().map(|c| evaluation.evaluate(c)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Square;
    impl Evaluation for Square {
        const NAME: &'static str = "square";
        type Config = (f64, u64);
        type Score = f64;
        fn evaluate(&self, &(x, seed): &(f64, u64)) -> f64 {
            x * x + seed as f64
        }
    }

    #[test]
    fn issue24_local_executor_keeps_the_order_of_the_batch() {
        let configs: Vec<(f64, u64)> = (0..50).map(|k| (k as f64, k % 3)).collect();
        let got = Local.run(&Square, &configs);
        let want: Vec<f64> = configs.iter().map(|c| Square.evaluate(c)).collect();
        assert_eq!(got, want);
    }
}
