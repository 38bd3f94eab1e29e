//! The C types of the FMI 3.0 ABI (`fmi3PlatformTypes.h`, `fmi3FunctionTypes.h`), written once:
//! the runtime exports its functions with them (`rustfmu`'s `fmi3::abi` re-exports this module)
//! and the conformance suite calls an FMU's functions with them.
//!
//! Declared here rather than taken from `fmi-sys`, so that building an FMU needs only the Rust
//! toolchain; the workspace's `tests/abi3_matches_fmi_sys.rs` proves every exported signature
//! equal to fmi-sys's bindgen output of the official headers.
#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

use core::ffi::{c_char, c_uint, c_void};

pub type fmi3Instance = *mut c_void;
pub type fmi3InstanceEnvironment = *mut c_void;
pub type fmi3FMUState = *mut c_void;
pub type fmi3ValueReference = u32;
pub type fmi3Float32 = f32;
pub type fmi3Float64 = f64;
pub type fmi3Int8 = i8;
pub type fmi3UInt8 = u8;
pub type fmi3Int16 = i16;
pub type fmi3UInt16 = u16;
pub type fmi3Int32 = i32;
pub type fmi3UInt32 = u32;
pub type fmi3Int64 = i64;
pub type fmi3UInt64 = u64;
/// C `bool`. Arrays of it are read as bytes (any non-zero byte is true): a Rust `bool` that is
/// neither 0 nor 1 would be undefined behaviour, and an importer's array is not checked by C.
pub type fmi3Boolean = bool;
pub type fmi3Char = c_char;
pub type fmi3String = *const fmi3Char;
pub type fmi3Byte = u8;
pub type fmi3Binary = *const fmi3Byte;
pub type fmi3Clock = bool;

// The headers' enums, as plain integers (see `c_enum!`).
c_enum!(fmi3Status {
    fmi3OK,
    fmi3Warning,
    fmi3Discard,
    fmi3Error,
    fmi3Fatal
});
c_enum!(fmi3DependencyKind {
    fmi3Independent,
    fmi3Constant,
    fmi3Fixed,
    fmi3Tunable,
    fmi3Discrete,
    fmi3Dependent
});
pub type fmi3IntervalQualifier = c_uint;

pub type fmi3LogMessageCallback = Option<
    unsafe extern "C" fn(
        instanceEnvironment: fmi3InstanceEnvironment,
        status: fmi3Status,
        category: fmi3String,
        message: fmi3String,
    ),
>;
pub type fmi3ClockUpdateCallback = Option<unsafe extern "C" fn(instanceEnvironment: fmi3InstanceEnvironment)>;
pub type fmi3IntermediateUpdateCallback = Option<
    unsafe extern "C" fn(
        instanceEnvironment: fmi3InstanceEnvironment,
        intermediateUpdateTime: fmi3Float64,
        intermediateVariableSetRequested: fmi3Boolean,
        intermediateVariableGetAllowed: fmi3Boolean,
        intermediateStepFinished: fmi3Boolean,
        canReturnEarly: fmi3Boolean,
        earlyReturnRequested: *mut fmi3Boolean,
        earlyReturnTime: *mut fmi3Float64,
    ),
>;
pub type fmi3LockPreemptionCallback = Option<unsafe extern "C" fn()>;
pub type fmi3UnlockPreemptionCallback = Option<unsafe extern "C" fn()>;
