//! The 34 functions of the FMI 2.0 co-simulation interface (and the 10 of model exchange, when exported), looked up in a loaded `.so` the way an
//! importer does (`dlopen` + `dlsym`), with the standard's C signatures.

use crate::fmi2::*;
use std::ffi::CStr;
use std::path::Path;

pub type Unary = fmi2ComponentFunctionTYPE;

/// The functions only the model-exchange interface has (FMI 2.0 section 3.2.1), with the
/// standard's C signatures.
pub struct MeApi {
    pub enter_event_mode: Unary,
    pub new_discrete_states: fmi2NewDiscreteStatesTYPE,
    pub enter_continuous_time_mode: Unary,
    pub completed_integrator_step: fmi2CompletedIntegratorStepTYPE,
    pub set_time: fmi2SetTimeTYPE,
    pub set_continuous_states: fmi2SetContinuousStatesTYPE,
    pub get_derivatives: fmi2GetRealVectorTYPE,
    pub get_event_indicators: fmi2GetRealVectorTYPE,
    pub get_continuous_states: fmi2GetRealVectorTYPE,
    pub get_nominals_of_continuous_states: fmi2GetRealVectorTYPE,
}

/// The names of the model-exchange functions, as exported (`fmi-standard`'s list).
pub use fmi_standard::functions::FMI2_ME_ONLY_FUNCTIONS as ME_FUNCTIONS;

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

/// `struct Api` of the functions `$field: $ty = $symbol` and `Api::load`, which looks each up
/// (the fields and the list of symbols, written once).
macro_rules! api {
    ($($field:ident: $ty:ty = $symbol:literal,)*) => {
        /// Function pointers into one loaded FMU binary. They stay valid as long as the library
        /// does: the [`libloading::Library`] is kept here and unloaded (`dlclose`) when this is
        /// dropped.
        pub struct Api {
            $(pub $field: $ty,)*
            /// The 10 functions of the model-exchange interface, or which are not exported (a
            /// co-simulation-only FMU need not export them).
            pub me: Result<MeApi, String>,
            /// Last, so that the pointers above are never used after the library is gone.
            library: libloading::Library,
        }

        impl Api {
            /// `dlopen`s the binary and looks up every function; an error names the first one missing.
            pub fn load(so: &Path) -> Result<Api, String> {
                // SAFETY: loading runs the binary's initializers: an FMU is trusted to run here (the
                // runner keeps each check in a child process, so a crash there fails only that check).
                // RTLD_NOW: a symbol the binary needs but no library provides fails here, by name.
                let lib: libloading::Library = unsafe { open_library(so) }?;
                Ok(Api {
                    me: MeApi::load(&lib),
                    $(
                        // SAFETY: the field's type is the standard's signature of this function.
                        $field: *unsafe { lib.get($symbol) }
                            .map_err(|e| format!("{} is not exported: {e}", String::from_utf8_lossy($symbol)))?,
                    )*
                    library: lib,
                })
            }

            /// Unloads the library (`dlclose`).
            pub fn unload(self) -> Result<(), String> {
                self.library.close().map_err(|e| e.to_string())
            }
        }
    };
}

api! {
    get_types_platform: fmi2GetTypesPlatformTYPE = b"fmi2GetTypesPlatform",
    get_version: fmi2GetVersionTYPE = b"fmi2GetVersion",
    set_debug_logging: fmi2SetDebugLoggingTYPE = b"fmi2SetDebugLogging",
    instantiate: fmi2InstantiateTYPE = b"fmi2Instantiate",
    free_instance: fmi2FreeInstanceTYPE = b"fmi2FreeInstance",
    setup_experiment: fmi2SetupExperimentTYPE = b"fmi2SetupExperiment",
    enter_initialization_mode: Unary = b"fmi2EnterInitializationMode",
    exit_initialization_mode: Unary = b"fmi2ExitInitializationMode",
    terminate: Unary = b"fmi2Terminate",
    reset: Unary = b"fmi2Reset",
    get_real: fmi2GetTYPE<fmi2Real> = b"fmi2GetReal",
    get_integer: fmi2GetTYPE<fmi2Integer> = b"fmi2GetInteger",
    get_boolean: fmi2GetTYPE<fmi2Boolean> = b"fmi2GetBoolean",
    get_string: fmi2GetTYPE<fmi2String> = b"fmi2GetString",
    set_real: fmi2SetTYPE<fmi2Real> = b"fmi2SetReal",
    set_integer: fmi2SetTYPE<fmi2Integer> = b"fmi2SetInteger",
    set_boolean: fmi2SetTYPE<fmi2Boolean> = b"fmi2SetBoolean",
    set_string: fmi2SetTYPE<fmi2String> = b"fmi2SetString",
    get_fmu_state: fmi2GetFMUstateTYPE = b"fmi2GetFMUstate",
    set_fmu_state: fmi2SetFMUstateTYPE = b"fmi2SetFMUstate",
    free_fmu_state: fmi2GetFMUstateTYPE = b"fmi2FreeFMUstate",
    serialized_fmu_state_size: fmi2SerializedFMUstateSizeTYPE = b"fmi2SerializedFMUstateSize",
    serialize_fmu_state: fmi2SerializeFMUstateTYPE = b"fmi2SerializeFMUstate",
    deserialize_fmu_state: fmi2DeSerializeFMUstateTYPE = b"fmi2DeSerializeFMUstate",
    get_directional_derivative: fmi2GetDirectionalDerivativeTYPE = b"fmi2GetDirectionalDerivative",
    set_real_input_derivatives: fmi2SetRealInputDerivativesTYPE = b"fmi2SetRealInputDerivatives",
    get_real_output_derivatives: fmi2GetRealOutputDerivativesTYPE = b"fmi2GetRealOutputDerivatives",
    do_step: fmi2DoStepTYPE = b"fmi2DoStep",
    cancel_step: Unary = b"fmi2CancelStep",
    get_status: fmi2GetStatusTYPE<fmi2Status> = b"fmi2GetStatus",
    get_real_status: fmi2GetStatusTYPE<fmi2Real> = b"fmi2GetRealStatus",
    get_integer_status: fmi2GetStatusTYPE<fmi2Integer> = b"fmi2GetIntegerStatus",
    get_boolean_status: fmi2GetStatusTYPE<fmi2Boolean> = b"fmi2GetBooleanStatus",
    get_string_status: fmi2GetStatusTYPE<fmi2String> = b"fmi2GetStringStatus",
}

impl Api {
    /// fmi2Instantiate of a co-simulation instance, not visible and without debug logging, by a
    /// raw call (the probes and runs that do without an [`crate::instance::Instance`]).
    ///
    /// # Safety
    /// `callbacks` (and the environment it names) must outlive the instance.
    pub unsafe fn instantiate_cs(
        &self,
        name: &CStr,
        guid: &CStr,
        resources: &CStr,
        callbacks: &fmi2CallbackFunctions,
    ) -> fmi2Component {
        // SAFETY: NUL-terminated strings and callbacks the caller keeps alive.
        unsafe {
            (self.instantiate)(
                name.as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                resources.as_ptr(),
                callbacks,
                fmi2False,
                fmi2False,
            )
        }
    }
}

/// Loads an FMU's binary: `dlopen` with RTLD_NOW | RTLD_LOCAL on Unix (a symbol the binary needs
/// but no library provides fails here, by name), `LoadLibraryExW` on Windows; before it, the
/// libpython a PythonFMU binary expects its importer to have loaded and names none of, as the
/// runner loads it ([`rustfmu_libpython`]; the report's head says which, from
/// [`rustfmu_libpython::loaded`]).
///
/// # Safety
/// Loading runs the binary's initializers (and those of the libpython loaded for it).
pub unsafe fn open_library(so: &Path) -> Result<libloading::Library, String> {
    rustfmu_libpython::before(so, Some("--preload-lib")).map_err(|e| format!("{}: {e}", so.display()))?;
    // SAFETY: the caller of this `unsafe fn` accepts that loading runs the binary's initializers.
    let lib = unsafe { dlopen(so) };
    match lib {
        Err(e) => match rustfmu_libpython::after_failure(so, &e.to_string(), Some("--preload-lib")) {
            // SAFETY: as above (libpython is loaded now).
            Ok(Some(_)) => unsafe { dlopen(so) },
            Ok(None) => Err(e),
            Err(why) => return Err(format!("{}: {why}", so.display())),
        },
        ok => ok,
    }
    .map_err(|e| format!("{}: {e}", so.display()))
}

/// `dlopen` of `so` with RTLD_NOW | RTLD_LOCAL.
///
/// # Safety
/// Loading runs the binary's initializers.
#[cfg(unix)]
unsafe fn dlopen(so: &Path) -> Result<libloading::Library, libloading::Error> {
    use libloading::os::unix::{Library, RTLD_LOCAL, RTLD_NOW};
    // SAFETY: the caller of this `unsafe fn` accepts that loading runs the binary's initializers.
    unsafe { Library::open(Some(so), RTLD_NOW | RTLD_LOCAL) }.map(libloading::Library::from)
}

/// `LoadLibraryExW` of `so`.
///
/// # Safety
/// Loading runs the binary's initializers.
#[cfg(not(unix))]
unsafe fn dlopen(so: &Path) -> Result<libloading::Library, libloading::Error> {
    // SAFETY: the caller of this `unsafe fn` accepts that loading runs the binary's initializers.
    unsafe { libloading::Library::new(so) }
}
