//! The system of Lipták et al., *The control of holonomic system*, as plain Rust: no FMI here.
//!
//! - [`models`]: the physics and control, with the paper's symbols and equation numbers.
//! - [`numerics`]: the integrators, the LQR design and LTI tools the models use.
//!
//! The FMU crates in `holonomic/fmus/` declare these models' variables with `rustfmu` and export
//! them; the composed systems are described in `holonomic/systems.toml`.

pub mod models;
pub mod numerics;
