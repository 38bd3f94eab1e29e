//! Every function of the FMI 3.0 C API (`fmi3Functions.h`), looked up in a loaded `.so` the way
//! an importer does (`dlopen` + `dlsym`), with the standard's C signatures.

use super::Type;
use super::types::*;
use std::os::raw::{c_char, c_uint, c_void};
use std::path::Path;

pub type Unary = unsafe extern "C" fn(fmi3Instance) -> fmi3Status;
type Vr = *const fmi3ValueReference;
pub type GetAny = unsafe extern "C" fn(fmi3Instance, Vr, usize, Values, usize) -> fmi3Status;
pub type SetAny = unsafe extern "C" fn(fmi3Instance, Vr, usize, *const c_void, usize) -> fmi3Status;
pub type Vector = unsafe extern "C" fn(fmi3Instance, *mut f64, usize) -> fmi3Status;
pub type Count = unsafe extern "C" fn(fmi3Instance, *mut usize) -> fmi3Status;
pub type Derivative =
    unsafe extern "C" fn(fmi3Instance, Vr, usize, Vr, usize, *const f64, usize, *mut f64, usize) -> fmi3Status;

macro_rules! api {
    ($($field:ident: $ty:ty = $symbol:literal,)*) => {
        /// Function pointers into one loaded FMU binary, valid as long as the library is loaded
        /// (it is kept here, unloaded when this is dropped).
        pub struct Api {
            $(pub $field: $ty,)*
            library: libloading::Library,
        }

        /// The names of every function of `fmi3Functions.h`.
        pub const FUNCTIONS: &[&str] = &[$($symbol,)*];

        impl Api {
            /// `dlopen`s the binary and looks up every function; an error names the missing ones.
            pub fn load(so: &Path) -> Result<Api, String> {
                // SAFETY: loading runs the binary's initializers; the runner keeps each check in a
                // child process, so a crash there fails only that check.
                let lib: libloading::Library = unsafe { crate::api::open_library(so) }?;
                let missing: Vec<&str> = FUNCTIONS
                    .iter()
                    .copied()
                    // SAFETY: only looked up, not called.
                    .filter(|name| unsafe { lib.get::<*const ()>(name.as_bytes()) }.is_err())
                    .collect();
                if !missing.is_empty() {
                    return Err(format!("{}: not exported: {}", so.display(), missing.join(", ")));
                }
                Ok(Api {
                    // SAFETY: each field's type is the standard's signature of that function.
                    $($field: *unsafe { lib.get::<$ty>($symbol.as_bytes()) }.map_err(|e| e.to_string())?,)*
                    library: lib,
                })
            }
        }
    };
}

api! {
    get_version: unsafe extern "C" fn() -> *const c_char = "fmi3GetVersion",
    set_debug_logging: unsafe extern "C" fn(fmi3Instance, bool, usize, *const fmi3String) -> fmi3Status = "fmi3SetDebugLogging",
    instantiate_model_exchange: unsafe extern "C" fn(fmi3String, fmi3String, fmi3String, bool, bool, fmi3InstanceEnvironment, fmi3LogMessageCallback) -> fmi3Instance = "fmi3InstantiateModelExchange",
    instantiate_co_simulation: unsafe extern "C" fn(fmi3String, fmi3String, fmi3String, bool, bool, bool, bool, Vr, usize, fmi3InstanceEnvironment, fmi3LogMessageCallback, fmi3IntermediateUpdateCallback) -> fmi3Instance = "fmi3InstantiateCoSimulation",
    instantiate_scheduled_execution: unsafe extern "C" fn(fmi3String, fmi3String, fmi3String, bool, bool, fmi3InstanceEnvironment, fmi3LogMessageCallback, fmi3ClockUpdateCallback, fmi3LockPreemptionCallback, fmi3LockPreemptionCallback) -> fmi3Instance = "fmi3InstantiateScheduledExecution",
    free_instance: unsafe extern "C" fn(fmi3Instance) = "fmi3FreeInstance",
    enter_initialization_mode: unsafe extern "C" fn(fmi3Instance, bool, f64, f64, bool, f64) -> fmi3Status = "fmi3EnterInitializationMode",
    exit_initialization_mode: Unary = "fmi3ExitInitializationMode",
    enter_event_mode: Unary = "fmi3EnterEventMode",
    terminate: Unary = "fmi3Terminate",
    reset: Unary = "fmi3Reset",
    get_float32: GetAny = "fmi3GetFloat32",
    get_float64: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut f64, usize) -> fmi3Status = "fmi3GetFloat64",
    get_int8: GetAny = "fmi3GetInt8",
    get_uint8: GetAny = "fmi3GetUInt8",
    get_int16: GetAny = "fmi3GetInt16",
    get_uint16: GetAny = "fmi3GetUInt16",
    get_int32: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut i32, usize) -> fmi3Status = "fmi3GetInt32",
    get_uint32: GetAny = "fmi3GetUInt32",
    get_int64: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut i64, usize) -> fmi3Status = "fmi3GetInt64",
    get_uint64: GetAny = "fmi3GetUInt64",
    get_boolean: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut u8, usize) -> fmi3Status = "fmi3GetBoolean",
    get_string: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut fmi3String, usize) -> fmi3Status = "fmi3GetString",
    get_binary: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut usize, *mut *const u8, usize) -> fmi3Status = "fmi3GetBinary",
    get_clock: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut u8) -> fmi3Status = "fmi3GetClock",
    set_float32: SetAny = "fmi3SetFloat32",
    set_float64: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const f64, usize) -> fmi3Status = "fmi3SetFloat64",
    set_int8: SetAny = "fmi3SetInt8",
    set_uint8: SetAny = "fmi3SetUInt8",
    set_int16: SetAny = "fmi3SetInt16",
    set_uint16: SetAny = "fmi3SetUInt16",
    set_int32: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const i32, usize) -> fmi3Status = "fmi3SetInt32",
    set_uint32: SetAny = "fmi3SetUInt32",
    set_int64: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const i64, usize) -> fmi3Status = "fmi3SetInt64",
    set_uint64: SetAny = "fmi3SetUInt64",
    set_boolean: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const bool, usize) -> fmi3Status = "fmi3SetBoolean",
    set_string: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const fmi3String, usize) -> fmi3Status = "fmi3SetString",
    set_binary: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const usize, *const *const u8, usize) -> fmi3Status = "fmi3SetBinary",
    set_clock: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const bool) -> fmi3Status = "fmi3SetClock",
    get_number_of_variable_dependencies: unsafe extern "C" fn(fmi3Instance, u32, *mut usize) -> fmi3Status = "fmi3GetNumberOfVariableDependencies",
    get_variable_dependencies: unsafe extern "C" fn(fmi3Instance, u32, *mut usize, *mut u32, *mut usize, *mut c_uint, usize) -> fmi3Status = "fmi3GetVariableDependencies",
    get_fmu_state: unsafe extern "C" fn(fmi3Instance, *mut fmi3FMUState) -> fmi3Status = "fmi3GetFMUState",
    set_fmu_state: unsafe extern "C" fn(fmi3Instance, fmi3FMUState) -> fmi3Status = "fmi3SetFMUState",
    free_fmu_state: unsafe extern "C" fn(fmi3Instance, *mut fmi3FMUState) -> fmi3Status = "fmi3FreeFMUState",
    serialized_fmu_state_size: unsafe extern "C" fn(fmi3Instance, fmi3FMUState, *mut usize) -> fmi3Status = "fmi3SerializedFMUStateSize",
    serialize_fmu_state: unsafe extern "C" fn(fmi3Instance, fmi3FMUState, *mut u8, usize) -> fmi3Status = "fmi3SerializeFMUState",
    deserialize_fmu_state: unsafe extern "C" fn(fmi3Instance, *const u8, usize, *mut fmi3FMUState) -> fmi3Status = "fmi3DeserializeFMUState",
    get_directional_derivative: Derivative = "fmi3GetDirectionalDerivative",
    get_adjoint_derivative: Derivative = "fmi3GetAdjointDerivative",
    enter_configuration_mode: Unary = "fmi3EnterConfigurationMode",
    exit_configuration_mode: Unary = "fmi3ExitConfigurationMode",
    get_interval_decimal: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut f64, *mut c_uint) -> fmi3Status = "fmi3GetIntervalDecimal",
    get_interval_fraction: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut u64, *mut u64, *mut c_uint) -> fmi3Status = "fmi3GetIntervalFraction",
    get_shift_decimal: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut f64) -> fmi3Status = "fmi3GetShiftDecimal",
    get_shift_fraction: unsafe extern "C" fn(fmi3Instance, Vr, usize, *mut u64, *mut u64) -> fmi3Status = "fmi3GetShiftFraction",
    set_interval_decimal: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const f64) -> fmi3Status = "fmi3SetIntervalDecimal",
    set_interval_fraction: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const u64, *const u64) -> fmi3Status = "fmi3SetIntervalFraction",
    set_shift_decimal: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const f64) -> fmi3Status = "fmi3SetShiftDecimal",
    set_shift_fraction: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const u64, *const u64) -> fmi3Status = "fmi3SetShiftFraction",
    evaluate_discrete_states: Unary = "fmi3EvaluateDiscreteStates",
    update_discrete_states: unsafe extern "C" fn(fmi3Instance, *mut u8, *mut u8, *mut u8, *mut u8, *mut u8, *mut f64) -> fmi3Status = "fmi3UpdateDiscreteStates",
    enter_continuous_time_mode: Unary = "fmi3EnterContinuousTimeMode",
    completed_integrator_step: unsafe extern "C" fn(fmi3Instance, bool, *mut u8, *mut u8) -> fmi3Status = "fmi3CompletedIntegratorStep",
    set_time: unsafe extern "C" fn(fmi3Instance, f64) -> fmi3Status = "fmi3SetTime",
    set_continuous_states: unsafe extern "C" fn(fmi3Instance, *const f64, usize) -> fmi3Status = "fmi3SetContinuousStates",
    get_continuous_state_derivatives: Vector = "fmi3GetContinuousStateDerivatives",
    get_event_indicators: Vector = "fmi3GetEventIndicators",
    get_continuous_states: Vector = "fmi3GetContinuousStates",
    get_nominals_of_continuous_states: Vector = "fmi3GetNominalsOfContinuousStates",
    get_number_of_event_indicators: Count = "fmi3GetNumberOfEventIndicators",
    get_number_of_continuous_states: Count = "fmi3GetNumberOfContinuousStates",
    enter_step_mode: Unary = "fmi3EnterStepMode",
    get_output_derivatives: unsafe extern "C" fn(fmi3Instance, Vr, usize, *const i32, *mut f64, usize) -> fmi3Status = "fmi3GetOutputDerivatives",
    do_step: unsafe extern "C" fn(fmi3Instance, f64, f64, bool, *mut u8, *mut u8, *mut u8, *mut f64) -> fmi3Status = "fmi3DoStep",
    activate_model_partition: unsafe extern "C" fn(fmi3Instance, u32, f64) -> fmi3Status = "fmi3ActivateModelPartition",
}

impl Api {
    /// The getter of `ty` (an Enumeration through fmi3GetInt64) for one value reference, into
    /// `n` values at `p`; fmi3Error, with no call, for String, Binary and Clock, whose getters
    /// take other arguments.
    ///
    /// # Safety
    /// `c` is a live instance of this library (or NULL), and `p` holds `n` values of `ty`,
    /// aligned for it (8-byte aligned words hold any of them).
    pub unsafe fn get_values(&self, c: fmi3Instance, ty: Type, vr: &u32, p: *mut u64, n: usize) -> fmi3Status {
        // SAFETY: the caller's contract; each getter is the standard's signature of that type.
        unsafe {
            match ty {
                Type::Float32 => (self.get_float32)(c, vr, 1, p as Values, n),
                Type::Float64 => (self.get_float64)(c, vr, 1, p as *mut f64, n),
                Type::Int8 => (self.get_int8)(c, vr, 1, p as Values, n),
                Type::UInt8 => (self.get_uint8)(c, vr, 1, p as Values, n),
                Type::Int16 => (self.get_int16)(c, vr, 1, p as Values, n),
                Type::UInt16 => (self.get_uint16)(c, vr, 1, p as Values, n),
                Type::Int32 => (self.get_int32)(c, vr, 1, p as *mut i32, n),
                Type::UInt32 => (self.get_uint32)(c, vr, 1, p as Values, n),
                Type::Int64 | Type::Enumeration => (self.get_int64)(c, vr, 1, p as *mut i64, n),
                Type::UInt64 => (self.get_uint64)(c, vr, 1, p as Values, n),
                Type::Boolean => (self.get_boolean)(c, vr, 1, p as *mut u8, n),
                Type::String | Type::Binary | Type::Clock => fmi3Error,
            }
        }
    }

    /// Unloads the library (`dlclose`).
    pub fn unload(self) -> Result<(), String> {
        self.library.close().map_err(|e| e.to_string())
    }
}
