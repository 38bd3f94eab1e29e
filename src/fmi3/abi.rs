//! The C types of the FMI 3.0 ABI (`fmi3PlatformTypes.h`, `fmi3FunctionTypes.h`): the ones of
//! `fmi-standard` (`fmi_standard::fmi3`), written there once for the exporter and the
//! conformance suite.
//!
//! Declared there rather than taken from `fmi-sys`, so that building an FMU needs only the Rust
//! toolchain; `tests/abi3_matches_fmi_sys.rs` proves every exported signature equal to
//! fmi-sys's bindgen output of the official headers.

pub use fmi_standard::fmi3::*;

/// `fmi3Version` as a NUL-terminated C string.
pub const VERSION: &std::ffi::CStr = c"3.0";
