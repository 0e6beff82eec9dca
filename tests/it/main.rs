//! The integration tests of `wt-ci`, built as one test binary (one
//! compile of the shared code and one link, not one a file): each
//! file of this folder is a module. `cargo test --test it NAME` runs
//! those whose path contains NAME, e.g. the module's name.

mod util;

mod any_sensor;
mod calibrate_any;
mod cli;
mod ensemble_cli;
mod ensemble_command;
mod executors;
mod faults;
mod fuzz_inputs;
mod hardware_runs;
mod held_out;
mod honest;
mod image_base_reuse;
mod image_ensemble;
mod image_init;
mod image_input;
mod image_models;
mod image_residual;
mod kill;
mod new_user;
mod outputs;
mod pin_init;
mod plain_taps;
mod regression;
mod replay_world;
mod rig_check;
mod search;
mod seed_range;
mod shear_cli;
mod sim_fit;
mod sim_frames;
mod small_pins;
mod steer_cli;
mod targets;
mod task3d;
mod test_layout;
mod train_sets;
mod tune;
mod turned_views;
