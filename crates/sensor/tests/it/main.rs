//! The integration tests of `sensor`, built as one test binary (one
//! compile of the shared code and one link, not one a file): each
//! file of this folder is a module. `cargo test --test it NAME` runs
//! those whose path contains NAME, e.g. the module's name.

mod common;

mod brush_law;
mod config;
mod contact3d;
mod depth_law;
mod frames;
mod fuzz_regressions;
mod label_convention;
mod labelled_depth;
mod layout_fit;
mod layouts;
mod mechanics;
mod pivot_fit;
mod slip_fit;
