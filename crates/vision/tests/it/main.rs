//! The integration tests of `vision`, built as one test binary (one
//! compile of the shared code and one link, not one a file): each
//! file of this folder is a module. `cargo test --test it NAME` runs
//! those whose path contains NAME, e.g. the module's name.

mod common;

mod any_tactip;
mod configs;
mod cut_field;
mod fuzz_regressions;
mod nn_start;
mod real_frames;
mod runs;
mod shared_sets;
mod speed;
mod speed_cuts;
mod synthetic;
