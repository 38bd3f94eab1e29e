//! The 34 functions of the FMI 2.0 co-simulation interface (and the 10 of model exchange, when exported), looked up in a loaded `.so` the way an
//! importer does (`dlopen` + `dlsym`), with the standard's C signatures.

use crate::fmi2::*;
use std::path::Path;

pub type Unary = unsafe extern "C" fn(fmi2Component) -> fmi2Status;

/// Function pointers into one loaded FMU binary. They stay valid as long as the library does:
/// the [`libloading::Library`] is kept here and unloaded (`dlclose`) when this is dropped.
pub struct Api {
    pub get_types_platform: unsafe extern "C" fn() -> fmi2String,
    pub get_version: unsafe extern "C" fn() -> fmi2String,
    pub set_debug_logging: unsafe extern "C" fn(fmi2Component, fmi2Boolean, usize, *const fmi2String) -> fmi2Status,
    pub instantiate: unsafe extern "C" fn(
        fmi2String,
        fmi2Type,
        fmi2String,
        fmi2String,
        *const fmi2CallbackFunctions,
        fmi2Boolean,
        fmi2Boolean,
    ) -> fmi2Component,
    pub free_instance: unsafe extern "C" fn(fmi2Component),
    pub setup_experiment:
        unsafe extern "C" fn(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real) -> fmi2Status,
    pub enter_initialization_mode: Unary,
    pub exit_initialization_mode: Unary,
    pub terminate: Unary,
    pub reset: Unary,
    pub get_real: unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *mut fmi2Real) -> fmi2Status,
    pub get_integer:
        unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *mut fmi2Integer) -> fmi2Status,
    pub get_boolean:
        unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *mut fmi2Boolean) -> fmi2Status,
    pub get_string:
        unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *mut fmi2String) -> fmi2Status,
    pub set_real: unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2Real) -> fmi2Status,
    pub set_integer:
        unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2Integer) -> fmi2Status,
    pub set_boolean:
        unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2Boolean) -> fmi2Status,
    pub set_string:
        unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2String) -> fmi2Status,
    pub get_fmu_state: unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status,
    pub set_fmu_state: unsafe extern "C" fn(fmi2Component, fmi2FMUstate) -> fmi2Status,
    pub free_fmu_state: unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status,
    pub serialized_fmu_state_size: unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut usize) -> fmi2Status,
    pub serialize_fmu_state: unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut fmi2Byte, usize) -> fmi2Status,
    pub deserialize_fmu_state:
        unsafe extern "C" fn(fmi2Component, *const fmi2Byte, usize, *mut fmi2FMUstate) -> fmi2Status,
    pub get_directional_derivative: unsafe extern "C" fn(
        fmi2Component,
        *const fmi2ValueReference,
        usize,
        *const fmi2ValueReference,
        usize,
        *const fmi2Real,
        *mut fmi2Real,
    ) -> fmi2Status,
    pub set_real_input_derivatives: unsafe extern "C" fn(
        fmi2Component,
        *const fmi2ValueReference,
        usize,
        *const fmi2Integer,
        *const fmi2Real,
    ) -> fmi2Status,
    pub get_real_output_derivatives: unsafe extern "C" fn(
        fmi2Component,
        *const fmi2ValueReference,
        usize,
        *const fmi2Integer,
        *mut fmi2Real,
    ) -> fmi2Status,
    pub do_step: unsafe extern "C" fn(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean) -> fmi2Status,
    pub cancel_step: Unary,
    pub get_status: unsafe extern "C" fn(fmi2Component, fmi2StatusKind, *mut fmi2Status) -> fmi2Status,
    pub get_real_status: unsafe extern "C" fn(fmi2Component, fmi2StatusKind, *mut fmi2Real) -> fmi2Status,
    pub get_integer_status: unsafe extern "C" fn(fmi2Component, fmi2StatusKind, *mut fmi2Integer) -> fmi2Status,
    pub get_boolean_status: unsafe extern "C" fn(fmi2Component, fmi2StatusKind, *mut fmi2Boolean) -> fmi2Status,
    pub get_string_status: unsafe extern "C" fn(fmi2Component, fmi2StatusKind, *mut fmi2String) -> fmi2Status,
    /// The 10 functions of the model-exchange interface, or which are not exported (a
    /// co-simulation-only FMU need not export them).
    pub me: Result<MeApi, String>,
    /// Last, so that the pointers above are never used after the library is gone.
    library: libloading::Library,
}

/// The functions only the model-exchange interface has (FMI 2.0 section 3.2.1), with the
/// standard's C signatures.
pub struct MeApi {
    pub enter_event_mode: Unary,
    pub new_discrete_states: unsafe extern "C" fn(fmi2Component, *mut fmi2EventInfo) -> fmi2Status,
    pub enter_continuous_time_mode: Unary,
    pub completed_integrator_step:
        unsafe extern "C" fn(fmi2Component, fmi2Boolean, *mut fmi2Boolean, *mut fmi2Boolean) -> fmi2Status,
    pub set_time: unsafe extern "C" fn(fmi2Component, fmi2Real) -> fmi2Status,
    pub set_continuous_states: unsafe extern "C" fn(fmi2Component, *const fmi2Real, usize) -> fmi2Status,
    pub get_derivatives: unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status,
    pub get_event_indicators: unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status,
    pub get_continuous_states: unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status,
    pub get_nominals_of_continuous_states: unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status,
}

/// The names of the model-exchange functions, as exported.
pub const ME_FUNCTIONS: [&str; 10] = [
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
];

impl MeApi {
    fn load(lib: &libloading::Library) -> Result<MeApi, String> {
        let missing: Vec<&str> = ME_FUNCTIONS
            .iter()
            .copied()
            // SAFETY: only looked up, not called.
            .filter(|name| unsafe { lib.get::<*const ()>(name.as_bytes()) }.is_err())
            .collect();
        if !missing.is_empty() {
            return Err(format!("not exported: {}", missing.join(", ")));
        }
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the field's type is the standard's signature of this function.
                *unsafe { lib.get($name) }.map_err(|e| format!("{}: {e}", String::from_utf8_lossy($name)))?
            };
        }
        Ok(MeApi {
            enter_event_mode: sym!(b"fmi2EnterEventMode"),
            new_discrete_states: sym!(b"fmi2NewDiscreteStates"),
            enter_continuous_time_mode: sym!(b"fmi2EnterContinuousTimeMode"),
            completed_integrator_step: sym!(b"fmi2CompletedIntegratorStep"),
            set_time: sym!(b"fmi2SetTime"),
            set_continuous_states: sym!(b"fmi2SetContinuousStates"),
            get_derivatives: sym!(b"fmi2GetDerivatives"),
            get_event_indicators: sym!(b"fmi2GetEventIndicators"),
            get_continuous_states: sym!(b"fmi2GetContinuousStates"),
            get_nominals_of_continuous_states: sym!(b"fmi2GetNominalsOfContinuousStates"),
        })
    }
}

macro_rules! load {
    ($lib:ident; $($field:ident = $symbol:literal),* $(,)?) => {
        Api {
            me: MeApi::load(&$lib),
            $(
                // SAFETY: the field's type is the standard's signature of this function.
                $field: *unsafe { $lib.get($symbol) }
                    .map_err(|e| format!("{} is not exported: {e}", String::from_utf8_lossy($symbol)))?,
            )*
            library: $lib,
        }
    };
}

/// Loads an FMU's binary: `dlopen` with RTLD_NOW | RTLD_LOCAL on Unix (a symbol the binary needs
/// but no library provides fails here, by name), `LoadLibraryExW` on Windows.
///
/// # Safety
/// Loading runs the binary's initializers.
pub unsafe fn open_library(so: &Path) -> Result<libloading::Library, String> {
    #[cfg(unix)]
    // SAFETY: the caller of this `unsafe fn` accepts that loading runs the binary's initializers.
    let lib = unsafe {
        libloading::os::unix::Library::open(
            Some(so),
            libloading::os::unix::RTLD_NOW | libloading::os::unix::RTLD_LOCAL,
        )
    }
    .map(libloading::Library::from);
    #[cfg(not(unix))]
    // SAFETY: the caller of this `unsafe fn` accepts that loading runs the binary's initializers.
    let lib = unsafe { libloading::Library::new(so) };
    lib.map_err(|e| format!("{}: {e}", so.display()))
}

impl Api {
    /// `dlopen`s the binary and looks up every function; an error names the first one missing.
    pub fn load(so: &Path) -> Result<Api, String> {
        // SAFETY: loading runs the binary's initializers: an FMU is trusted to run here (the
        // runner keeps each check in a child process, so a crash there fails only that check).
        // RTLD_NOW: a symbol the binary needs but no library provides fails here, by name.
        let lib: libloading::Library = unsafe { open_library(so) }?;
        Ok(load!(lib;
            get_types_platform = b"fmi2GetTypesPlatform",
            get_version = b"fmi2GetVersion",
            set_debug_logging = b"fmi2SetDebugLogging",
            instantiate = b"fmi2Instantiate",
            free_instance = b"fmi2FreeInstance",
            setup_experiment = b"fmi2SetupExperiment",
            enter_initialization_mode = b"fmi2EnterInitializationMode",
            exit_initialization_mode = b"fmi2ExitInitializationMode",
            terminate = b"fmi2Terminate",
            reset = b"fmi2Reset",
            get_real = b"fmi2GetReal",
            get_integer = b"fmi2GetInteger",
            get_boolean = b"fmi2GetBoolean",
            get_string = b"fmi2GetString",
            set_real = b"fmi2SetReal",
            set_integer = b"fmi2SetInteger",
            set_boolean = b"fmi2SetBoolean",
            set_string = b"fmi2SetString",
            get_fmu_state = b"fmi2GetFMUstate",
            set_fmu_state = b"fmi2SetFMUstate",
            free_fmu_state = b"fmi2FreeFMUstate",
            serialized_fmu_state_size = b"fmi2SerializedFMUstateSize",
            serialize_fmu_state = b"fmi2SerializeFMUstate",
            deserialize_fmu_state = b"fmi2DeSerializeFMUstate",
            get_directional_derivative = b"fmi2GetDirectionalDerivative",
            set_real_input_derivatives = b"fmi2SetRealInputDerivatives",
            get_real_output_derivatives = b"fmi2GetRealOutputDerivatives",
            do_step = b"fmi2DoStep",
            cancel_step = b"fmi2CancelStep",
            get_status = b"fmi2GetStatus",
            get_real_status = b"fmi2GetRealStatus",
            get_integer_status = b"fmi2GetIntegerStatus",
            get_boolean_status = b"fmi2GetBooleanStatus",
            get_string_status = b"fmi2GetStringStatus",
        ))
    }

    /// Unloads the library (`dlclose`).
    pub fn unload(self) -> Result<(), String> {
        self.library.close().map_err(|e| e.to_string())
    }
}
