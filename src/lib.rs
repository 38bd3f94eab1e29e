//! FMI 2.0 co-simulation FMUs from plain Rust models.
//!
//! - [`models`]: the physics and control of "The control of holonomic system" (Lipták et al.),
//!   plain Rust with the paper's symbols and equation numbers; no FMI.
//! - [`numerics`]: the integrators the models step with.
//! - [`fmi2`]: the generic FMI 2.0 co-simulation runtime (C ABI, state machine, logging, FMU
//!   state, model description).
//! - [`fmus`]: each FMU's variable declarations, joining a model to the runtime.
//! - [`systems`]: the composed systems (FMU instances, parameters, connections), described once
//!   for the SSP files and the benchmarks.

extern crate self as rustfmu;

pub mod fmi2;
pub mod fmus;
pub mod models;
pub mod numerics;
pub mod systems;

#[doc(hidden)]
pub use serde;
