//! The integration tests of `hw`, built as one test binary (one
//! compile of the shared code and one link, not one a file): each
//! file of this folder is a module. `cargo test --test it NAME` runs
//! those whose path contains NAME, e.g. the module's name.

mod dashboard_fake;
mod docs_config;
mod rtde_conformance;
mod rtde_fake;
mod safety;
mod se3_poses;
mod signals;
mod ur5_fake;
mod v4l2_fake;
