//! The C types of the FMI 3.0 ABI (`fmi3PlatformTypes.h`, `fmi3FunctionTypes.h`), as an
//! importer declares them. Output flags are read as bytes (`u8`), not Rust `bool`: an FMU may
//! write any byte there, and the suite must be able to report it (a C `bool` is one byte).
#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

use std::os::raw::{c_char, c_uint, c_void};

pub type fmi3Instance = *mut c_void;
pub type fmi3InstanceEnvironment = *mut c_void;
pub type fmi3FMUState = *mut c_void;
pub type fmi3ValueReference = u32;
pub type fmi3Float64 = f64;
pub type fmi3Int32 = i32;
pub type fmi3Int64 = i64;
/// C `bool` (one byte) as an input argument.
pub type fmi3Boolean = bool;
pub type fmi3String = *const c_char;
pub type fmi3Byte = u8;

/// A C enum: `unsigned int` on the supported platforms; a plain integer, since an FMU may
/// answer any value.
pub type fmi3Status = c_uint;
pub const fmi3OK: fmi3Status = 0;
pub const fmi3Warning: fmi3Status = 1;
pub const fmi3Discard: fmi3Status = 2;
pub const fmi3Error: fmi3Status = 3;
pub const fmi3Fatal: fmi3Status = 4;

pub type fmi3LogMessageCallback = Option<
    unsafe extern "C" fn(env: fmi3InstanceEnvironment, status: fmi3Status, category: fmi3String, message: fmi3String),
>;
pub type fmi3IntermediateUpdateCallback = Option<
    unsafe extern "C" fn(
        env: fmi3InstanceEnvironment,
        intermediateUpdateTime: f64,
        intermediateVariableSetRequested: bool,
        intermediateVariableGetAllowed: bool,
        intermediateStepFinished: bool,
        canReturnEarly: bool,
        earlyReturnRequested: *mut bool,
        earlyReturnTime: *mut f64,
    ),
>;
pub type fmi3ClockUpdateCallback = Option<unsafe extern "C" fn(env: fmi3InstanceEnvironment)>;
pub type fmi3LockPreemptionCallback = Option<unsafe extern "C" fn()>;

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
