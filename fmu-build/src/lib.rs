//! fmu-build as a library: composed systems read from a TOML systems file and checked against
//! packaged FMUs ([`systems`]), written as SSP 1.0 files ([`ssp`]). Neither knows the Rust
//! types of the models: they read the FMUs' modelDescription.xml, as any importer does.

pub mod ssp;
pub mod systems;
