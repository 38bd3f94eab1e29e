//! The C types of the FMI 2.0 ABI (co-simulation and model exchange) (`fmi2TypesPlatform.h`,
//! `fmi2FunctionTypes.h`), as an importer declares them. The suite is an importer: it takes
//! nothing from an exporter's crate, only the standard's definitions, `fmi-standard`'s
//! (`fmi_standard::fmi2`, which the workspace's tests compare with fmi-sys's bindgen output).
//! Statuses and enums are plain integers there, not Rust enums: an FMU may answer any value, and
//! the suite must be able to report it.

pub use fmi_standard::fmi2::*;
