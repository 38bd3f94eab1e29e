//! The C types of the FMI 3.0 ABI (`fmi3PlatformTypes.h`, `fmi3FunctionTypes.h`), as an
//! importer declares them: `fmi-standard`'s (`fmi_standard::fmi3`, which the workspace's tests
//! compare with fmi-sys's bindgen output). Statuses are plain integers there, since an FMU may
//! answer any value. Output flags are read as bytes (`u8`), not Rust `bool`: an FMU may write
//! any byte there, and the suite must be able to report it (a C `bool` is one byte).

#![allow(non_upper_case_globals)] // the standard's names of the statuses, matched on

pub use fmi_standard::fmi3::*;
use std::os::raw::c_void;

/// A status as the standard names it (or the number, if it is none of them).
pub fn status_name(s: fmi3Status) -> String {
    match s {
        fmi3OK => "fmi3OK".into(),
        fmi3Warning => "fmi3Warning".into(),
        fmi3Discard => "fmi3Discard".into(),
        fmi3Error => "fmi3Error".into(),
        fmi3Fatal => "fmi3Fatal".into(),
        n => format!("status {n} (no fmi3Status)"),
    }
}

/// A type-erased value array, for the getters and setters whose element type the checks only
/// pass through (Float32, Int8, ..., UInt64: same calling convention as the typed pointer).
pub type Values = *mut c_void;
