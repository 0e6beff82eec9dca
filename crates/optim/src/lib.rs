//! Derivative-free optimisation for tuning the controller in simulation
//! (issue 12): the (mu/mu_w, lambda)-CMA-ES with an ask/tell interface, so
//! the caller evaluates each generation however it likes (in parallel,
//! with a progress bar, saving the best so far).
//!
//! Pure: no files, no printing; every random draw from the seed given.

mod cmaes;
mod error;

pub use cmaes::{Cmaes, CmaesConfig};
pub use error::OptimError;
