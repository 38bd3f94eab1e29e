//! No code. This crate only carries dependency features: see its Cargo.toml.
