//! The C types of the FMI 2.0 ABI (`fmi2TypesPlatform.h`, `fmi2FunctionTypes.h`): the ones of
//! `fmi-standard` (`fmi_standard::fmi2`), written there once for the exporter and the importers.
//!
//! Declared there rather than taken from `fmi-sys`, so that building an FMU needs only the Rust
//! toolchain (fmi-sys runs bindgen, which needs libclang). `tests/abi_matches_fmi_sys.rs` proves
//! every exported signature and every struct layout equal to fmi-sys's bindgen output of the
//! official headers.

pub use fmi_standard::fmi2::*;

/// `fmi2TypesPlatform` and `fmi2Version` as NUL-terminated C strings.
pub const TYPES_PLATFORM: &std::ffi::CStr = c"default";
pub const VERSION: &std::ffi::CStr = c"2.0";
