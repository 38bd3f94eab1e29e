//! The C types of the FMI 2.0 ABI (`fmi2TypesPlatform.h`, `fmi2FunctionTypes.h`), written once:
//! the runtime exports its functions with them (`rustfmu`'s `fmi2::abi` re-exports this module)
//! and the importers (the conformance suite, the runner) call an FMU's functions with them.
//!
//! Declared here rather than taken from `fmi-sys`, so that building an FMU needs only the Rust
//! toolchain (fmi-sys runs bindgen, which needs libclang). The workspace's
//! `tests/abi_matches_fmi_sys.rs` proves every exported signature and every struct layout equal
//! to fmi-sys's bindgen output of the official headers.
#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

use core::ffi::{c_char, c_int, c_uint, c_void};

pub type fmi2Component = *mut c_void;
pub type fmi2ComponentEnvironment = *mut c_void;
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = c_uint;
pub type fmi2Real = f64;
pub type fmi2Integer = c_int;
pub type fmi2Boolean = c_int;
pub type fmi2Char = c_char;
pub type fmi2String = *const fmi2Char;
pub type fmi2Byte = c_char;

pub const fmi2True: fmi2Boolean = 1;
pub const fmi2False: fmi2Boolean = 0;

// The headers' enums, as plain integers (see `c_enum!`).
c_enum!(fmi2Status {
    fmi2OK,
    fmi2Warning,
    fmi2Discard,
    fmi2Error,
    fmi2Fatal,
    fmi2Pending
});
c_enum!(fmi2Type {
    fmi2ModelExchange,
    fmi2CoSimulation
});
c_enum!(fmi2StatusKind {
    fmi2DoStepStatus,
    fmi2PendingStatus,
    fmi2LastSuccessfulTime,
    fmi2Terminated
});

pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        componentEnvironment: fmi2ComponentEnvironment,
        instanceName: fmi2String,
        status: fmi2Status,
        category: fmi2String,
        message: fmi2String,
        ...
    ),
>;
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(nobj: usize, size: usize) -> *mut c_void>;
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(obj: *mut c_void)>;
pub type fmi2StepFinished =
    Option<unsafe extern "C" fn(componentEnvironment: fmi2ComponentEnvironment, status: fmi2Status)>;

#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct fmi2CallbackFunctions {
    pub logger: fmi2CallbackLogger,
    pub allocateMemory: fmi2CallbackAllocateMemory,
    pub freeMemory: fmi2CallbackFreeMemory,
    pub stepFinished: fmi2StepFinished,
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// What fmi2NewDiscreteStates reports (model exchange).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct fmi2EventInfo {
    pub newDiscreteStatesNeeded: fmi2Boolean,
    pub terminateSimulation: fmi2Boolean,
    pub nominalsOfContinuousStatesChanged: fmi2Boolean,
    pub valuesOfContinuousStatesChanged: fmi2Boolean,
    pub nextEventTimeDefined: fmi2Boolean,
    pub nextEventTime: fmi2Real,
}

// The function types of `fmi2FunctionTypes.h` an importer loads (pointers to them: what
// `dlsym` gives), named as the header names them; the importers (the runner, the conformance
// suite) use these.
pub type fmi2GetTypesPlatformTYPE = unsafe extern "C" fn() -> fmi2String;
/// fmi2GetTypesPlatform, fmi2GetVersion.
pub type fmi2GetVersionTYPE = fmi2GetTypesPlatformTYPE;
pub type fmi2InstantiateTYPE = unsafe extern "C" fn(
    fmi2String,
    fmi2Type,
    fmi2String,
    fmi2String,
    *const fmi2CallbackFunctions,
    fmi2Boolean,
    fmi2Boolean,
) -> fmi2Component;
pub type fmi2FreeInstanceTYPE = unsafe extern "C" fn(fmi2Component);
pub type fmi2SetDebugLoggingTYPE =
    unsafe extern "C" fn(fmi2Component, fmi2Boolean, usize, *const fmi2String) -> fmi2Status;
pub type fmi2SetupExperimentTYPE =
    unsafe extern "C" fn(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real) -> fmi2Status;
/// fmi2EnterInitializationMode, fmi2ExitInitializationMode, fmi2Terminate, fmi2Reset.
pub type fmi2ComponentFunctionTYPE = unsafe extern "C" fn(fmi2Component) -> fmi2Status;
/// fmi2GetReal (T = fmi2Real), fmi2GetInteger, fmi2GetBoolean, fmi2GetString.
pub type fmi2GetTYPE<T> = unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *mut T) -> fmi2Status;
/// fmi2SetReal (T = fmi2Real), fmi2SetInteger, fmi2SetBoolean, fmi2SetString.
pub type fmi2SetTYPE<T> = unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const T) -> fmi2Status;
pub type fmi2DoStepTYPE = unsafe extern "C" fn(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean) -> fmi2Status;
/// fmi2GetFMUstate, fmi2FreeFMUstate.
pub type fmi2GetFMUstateTYPE = unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status;
pub type fmi2SetFMUstateTYPE = unsafe extern "C" fn(fmi2Component, fmi2FMUstate) -> fmi2Status;
pub type fmi2SerializedFMUstateSizeTYPE = unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut usize) -> fmi2Status;
pub type fmi2SerializeFMUstateTYPE =
    unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut fmi2Byte, usize) -> fmi2Status;
pub type fmi2DeSerializeFMUstateTYPE =
    unsafe extern "C" fn(fmi2Component, *const fmi2Byte, usize, *mut fmi2FMUstate) -> fmi2Status;
pub type fmi2GetDirectionalDerivativeTYPE = unsafe extern "C" fn(
    fmi2Component,
    *const fmi2ValueReference,
    usize,
    *const fmi2ValueReference,
    usize,
    *const fmi2Real,
    *mut fmi2Real,
) -> fmi2Status;

// Co-simulation only.
pub type fmi2SetRealInputDerivativesTYPE = unsafe extern "C" fn(
    fmi2Component,
    *const fmi2ValueReference,
    usize,
    *const fmi2Integer,
    *const fmi2Real,
) -> fmi2Status;
pub type fmi2GetRealOutputDerivativesTYPE = unsafe extern "C" fn(
    fmi2Component,
    *const fmi2ValueReference,
    usize,
    *const fmi2Integer,
    *mut fmi2Real,
) -> fmi2Status;
/// fmi2GetStatus (T = fmi2Status), fmi2GetRealStatus, fmi2GetIntegerStatus, fmi2GetBooleanStatus,
/// fmi2GetStringStatus.
pub type fmi2GetStatusTYPE<T> = unsafe extern "C" fn(fmi2Component, fmi2StatusKind, *mut T) -> fmi2Status;

// Model exchange only.
pub type fmi2NewDiscreteStatesTYPE = unsafe extern "C" fn(fmi2Component, *mut fmi2EventInfo) -> fmi2Status;
pub type fmi2CompletedIntegratorStepTYPE =
    unsafe extern "C" fn(fmi2Component, fmi2Boolean, *mut fmi2Boolean, *mut fmi2Boolean) -> fmi2Status;
pub type fmi2SetTimeTYPE = unsafe extern "C" fn(fmi2Component, fmi2Real) -> fmi2Status;
pub type fmi2SetContinuousStatesTYPE = unsafe extern "C" fn(fmi2Component, *const fmi2Real, usize) -> fmi2Status;
/// fmi2GetDerivatives, fmi2GetEventIndicators, fmi2GetContinuousStates,
/// fmi2GetNominalsOfContinuousStates.
pub type fmi2GetRealVectorTYPE = unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status;
