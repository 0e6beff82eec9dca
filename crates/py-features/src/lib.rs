//! No code: this crate exists for its `Cargo.toml`, which turns on in the
//! main workspace the dependency features that only the Python package's
//! dependencies ask for (see there).
