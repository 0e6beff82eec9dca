//! The integration tests of `convnet`, built as one test binary (one
//! compile of the shared code and one link, not one a file): each
//! file of this folder is a module. `cargo test --test it NAME` runs
//! those whose path contains NAME, e.g. the module's name.

mod common;

mod coord_channels;
mod dropout;
mod ensemble;
mod fine_tune;
mod input_noise;
mod model_api;
mod pin_model_residual;
mod pins_and_pixels;
mod pixel_dropout;
mod theory;
mod turned_frames;
mod weight_average;
