//! The FMI 2.0 C layer, generic over the model: not part of the documented API.
//!
//! [`abi`] declares the C types, [`api`] converts the importer's arguments and calls the
//! version-neutral core ([`crate::core`]), [`export`](crate::export_fmi2) puts the symbols in
//! an FMU crate, and [`TERMS`] is how this version names its functions and states in every
//! message the core writes.

pub mod abi;
pub mod api;
pub mod export;
mod terms;

pub use terms::TERMS;
