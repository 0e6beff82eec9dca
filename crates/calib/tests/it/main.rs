//! The integration tests of `calib`, built as one test binary (one
//! compile of the shared code and one link, not one a file): each
//! file of this folder is a module. `cargo test --test it NAME` runs
//! those whose path contains NAME, e.g. the module's name.

mod common;

mod calibrate;
mod jitter;
mod position_map;
mod record;
mod ridge;
mod rings;
mod select;
