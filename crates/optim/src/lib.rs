//! Derivative-free optimisation for tuning the controller in simulation
//! (issue 12): the (mu/mu_w, lambda)-CMA-ES with an ask/tell interface, so
//! the caller evaluates each generation however it likes (in parallel,
//! with a progress bar, saving the best so far); the tree-structured
//! Parzen estimator (TPE) for Bayesian hyper-parameter search; and the
//! executor interface that runs a batch of evaluations.
//!
//! Pure: no files, no printing; every random draw from the seed given.

mod cmaes;
mod error;
mod executor;
mod tpe;

pub use cmaes::{Cmaes, CmaesConfig};
pub use error::OptimError;
pub use executor::{Evaluation, Executor, Local, RunError};
pub use tpe::{Domain, Observation, Tpe, TpeConfig};
