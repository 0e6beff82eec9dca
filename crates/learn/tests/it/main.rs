//! The integration tests of `learn`, built as one test binary (one
//! compile of the shared code and one link, not one a file): each
//! file of this folder is a module. `cargo test --test it NAME` runs
//! those whose path contains NAME, e.g. the module's name.

mod support;

mod band_weight;
mod continued_fit;
mod cost;
mod ensemble;
mod ensemble_restart;
mod ep_beta;
mod ep_gradient;
mod fuzz_regressions;
mod honest_training;
mod image_model_turns;
mod pca;
mod pin_features;
mod pose_model;
mod reflections;
mod rest_shift;
mod rotations;
mod shared_support;
mod targets;
mod two_hidden_layers;
