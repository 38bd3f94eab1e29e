//! The functions each FMI standard declares: what a binary must export, and may export of the
//! other version. The lists are `fmi-standard`'s (`fmi_standard::functions`), written there once
//! for `cargo fmu` and the conformance suite.

pub use fmi_standard::functions::{FMI2_CS_FUNCTIONS, FMI2_FUNCTIONS, FMI3_FUNCTIONS};
