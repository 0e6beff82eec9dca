//! The integration tests of `lab`, built as one test binary (one
//! compile of the shared code and one link, not one a file): each
//! file of this folder is a module. `cargo test --test it NAME` runs
//! those whose path contains NAME, e.g. the module's name.

mod common;

mod calibrate;
mod calibrate_estimated;
mod calibrate_jitter;
mod calibrated_world;
mod config3d;
mod configs;
mod corners;
mod curved_collection;
mod edge3d;
mod faults;
mod hardware_loop;
mod hardware_safety;
mod image_base_recipes;
mod remote;
mod rig_sensor_file;
mod search_space;
mod servo_loop;
mod shear_collection;
mod surface_heading;
mod task3d;
mod twin;
mod twin_pin_jitter;
mod twin_position_map;
mod worlds;
