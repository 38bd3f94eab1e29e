//! The runner's FMI 3.0 co-simulation importer: an FMU unpacked (or found unpacked), its binary
//! loaded once, instances (in Event Mode where the runner ticks their input clocks: `fmi3/clocks.rs`;
//! without it otherwise), values, steps and FMU states, behind the same
//! [`crate::instance::InstanceCS`] as FMI 2.0 instances, so a system mixes both.
//!
//! The runner reads an FMI 3.0 FMU as the FMI 2.0 one it would be ([`as_fmi2`]): Float64 as
//! Real, Int32 as Integer, Enumeration (read and set here with fmi3GetInt64 / fmi3SetInt64),
//! Boolean (C `bool`), String. Every variable of every type but Clock, scalar or array, is also
//! kept as a [`Var3`] and got and set with its type's own function (`typed.rs`:
//! fmi3GetFloat32 ... fmi3GetBinary, `nValues` the array's elements): what connections,
//! parameters and records of the types FMI 2.0 lacks go through. The clocked Float64 scalars of
//! the input clocks the runner ticks are read as Real ones; the clocks and every other clocked
//! variable are left out, named in [`Fmi3Parts::skipped`] (a connection or parameter naming one
//! is refused with what it is).
//! Written here for the reasons of [`crate::fmi2`]'s header, and because the `fmi` crate's FMI 3.0
//! description parser refuses FMI 3.0 units; the description is `md-reader`'s.

#![allow(non_upper_case_globals, non_camel_case_types)]

use crate::common::{
    Directional, Fmi2Error, FmuState, Scratch, Slots, lengths, load_binary, optional, scratch, symbol,
};
use rustfmu::fmi3::abi::*;
use std::collections::HashSet;
use std::ffi::{CStr, CString, c_char, c_void};
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod clocks;
mod intermediate;
mod scheduled;
mod typed;
mod view;
pub use clocks::ClockState;
pub use clocks::{ClockDecl, ClockPlan, Interval};
pub use view::{Fmi3Parts, Var3, as_fmi2};

fn check(status: fmi3Status) -> Result<(), Fmi2Error> {
    match status {
        fmi3OK | fmi3Warning => Ok(()),
        fmi3Discard => Err(Fmi2Error::Discard),
        fmi3Error => Err(Fmi2Error::Error),
        fmi3Fatal => Err(Fmi2Error::Fatal),
        s => Err(Fmi2Error::Unknown(s)),
    }
}

type Get<T> = unsafe extern "C" fn(fmi3Instance, *const fmi3ValueReference, usize, *mut T, usize) -> fmi3Status;
type Set<T> = unsafe extern "C" fn(fmi3Instance, *const fmi3ValueReference, usize, *const T, usize) -> fmi3Status;
type GetBinary = unsafe extern "C" fn(
    fmi3Instance,
    *const fmi3ValueReference,
    usize,
    *mut usize,
    *mut fmi3Binary,
    usize,
) -> fmi3Status;
type SetBinary = unsafe extern "C" fn(
    fmi3Instance,
    *const fmi3ValueReference,
    usize,
    *const usize,
    *const fmi3Binary,
    usize,
) -> fmi3Status;
type InstantiateCS = unsafe extern "C" fn(
    fmi3String,
    fmi3String,
    fmi3String,
    fmi3Boolean,
    fmi3Boolean,
    fmi3Boolean,
    fmi3Boolean,
    *const fmi3ValueReference,
    usize,
    fmi3InstanceEnvironment,
    fmi3LogMessageCallback,
    fmi3IntermediateUpdateCallback,
) -> fmi3Instance;
type InstanceFunction = unsafe extern "C" fn(fmi3Instance) -> fmi3Status;
type InstantiateSE = unsafe extern "C" fn(
    fmi3String,
    fmi3String,
    fmi3String,
    fmi3Boolean,
    fmi3Boolean,
    fmi3InstanceEnvironment,
    fmi3LogMessageCallback,
    fmi3ClockUpdateCallback,
    fmi3LockPreemptionCallback,
    fmi3UnlockPreemptionCallback,
) -> fmi3Instance;
type ActivateModelPartition = unsafe extern "C" fn(fmi3Instance, fmi3ValueReference, fmi3Float64) -> fmi3Status;
type InstantiateME = unsafe extern "C" fn(
    fmi3String,
    fmi3String,
    fmi3String,
    fmi3Boolean,
    fmi3Boolean,
    fmi3InstanceEnvironment,
    fmi3LogMessageCallback,
) -> fmi3Instance;
type SetTime = unsafe extern "C" fn(fmi3Instance, fmi3Float64) -> fmi3Status;
type SetStates = unsafe extern "C" fn(fmi3Instance, *const fmi3Float64, usize) -> fmi3Status;
type GetVector = unsafe extern "C" fn(fmi3Instance, *mut fmi3Float64, usize) -> fmi3Status;
type Completed = unsafe extern "C" fn(fmi3Instance, fmi3Boolean, *mut fmi3Boolean, *mut fmi3Boolean) -> fmi3Status;
type UpdateDiscreteStates = unsafe extern "C" fn(
    fmi3Instance,
    *mut fmi3Boolean,
    *mut fmi3Boolean,
    *mut fmi3Boolean,
    *mut fmi3Boolean,
    *mut fmi3Boolean,
    *mut fmi3Float64,
) -> fmi3Status;

/// The model-exchange functions (a binary without them runs as co-simulation only).
struct MeApi {
    instantiate: InstantiateME,
    set_time: SetTime,
    set_continuous_states: SetStates,
    get_derivatives: GetVector,
    get_event_indicators: GetVector,
    get_continuous_states: GetVector,
    get_nominals: GetVector,
    completed_integrator_step: Completed,
    enter_event_mode: InstanceFunction,
    update_discrete_states: UpdateDiscreteStates,
    enter_continuous_time_mode: InstanceFunction,
    /// fmi3GetNumberOfContinuousStates, fmi3GetNumberOfEventIndicators: what the structural
    /// parameters in force give.
    number_of: Option<(GetCount, GetCount)>,
}
type GetCount = unsafe extern "C" fn(fmi3Instance, *mut usize) -> fmi3Status;
/// The Event Mode and clock functions of co-simulation with eventModeUsed ([`clocks`]).
struct EventApi {
    enter_event_mode: InstanceFunction,
    enter_step_mode: InstanceFunction,
    update_discrete_states: UpdateDiscreteStates,
    set_clock: unsafe extern "C" fn(fmi3Instance, *const fmi3ValueReference, usize, *const fmi3Clock) -> fmi3Status,
    get_clock: unsafe extern "C" fn(fmi3Instance, *const fmi3ValueReference, usize, *mut fmi3Clock) -> fmi3Status,
    get_interval: unsafe extern "C" fn(
        fmi3Instance,
        *const fmi3ValueReference,
        usize,
        *mut fmi3Float64,
        *mut fmi3IntervalQualifier,
    ) -> fmi3Status,
    get_shift: unsafe extern "C" fn(fmi3Instance, *const fmi3ValueReference, usize, *mut fmi3Float64) -> fmi3Status,
}
type EnterInit =
    unsafe extern "C" fn(fmi3Instance, fmi3Boolean, fmi3Float64, fmi3Float64, fmi3Boolean, fmi3Float64) -> fmi3Status;
type DoStep = unsafe extern "C" fn(
    fmi3Instance,
    fmi3Float64,
    fmi3Float64,
    fmi3Boolean,
    *mut fmi3Boolean,
    *mut fmi3Boolean,
    *mut fmi3Boolean,
    *mut fmi3Float64,
) -> fmi3Status;
type OutputDerivatives = unsafe extern "C" fn(
    fmi3Instance,
    *const fmi3ValueReference,
    usize,
    *const fmi3Int32,
    *mut fmi3Float64,
    usize,
) -> fmi3Status;
type DirectionalDerivative = unsafe extern "C" fn(
    fmi3Instance,
    *const fmi3ValueReference,
    usize,
    *const fmi3ValueReference,
    usize,
    *const fmi3Float64,
    usize,
    *mut fmi3Float64,
    usize,
) -> fmi3Status;
type SetDebugLogging = unsafe extern "C" fn(fmi3Instance, fmi3Boolean, usize, *const fmi3String) -> fmi3Status;
type GetState = unsafe extern "C" fn(fmi3Instance, *mut fmi3FMUState) -> fmi3Status;
type SetState = unsafe extern "C" fn(fmi3Instance, fmi3FMUState) -> fmi3Status;
type StateSize = unsafe extern "C" fn(fmi3Instance, fmi3FMUState, *mut usize) -> fmi3Status;
type Serialize = unsafe extern "C" fn(fmi3Instance, fmi3FMUState, *mut fmi3Byte, usize) -> fmi3Status;
type Deserialize = unsafe extern "C" fn(fmi3Instance, *const fmi3Byte, usize, *mut fmi3FMUState) -> fmi3Status;

/// The functions of an FMI 3.0 co-simulation binary the runner calls.
struct Api {
    instantiate: Option<InstantiateCS>,
    free_instance: unsafe extern "C" fn(fmi3Instance),
    set_debug_logging: SetDebugLogging,
    enter_initialization_mode: EnterInit,
    exit_initialization_mode: InstanceFunction,
    terminate: InstanceFunction,
    reset: InstanceFunction,
    /// fmi3EnterConfigurationMode, fmi3ExitConfigurationMode (structural parameters).
    enter_configuration_mode: Option<InstanceFunction>,
    exit_configuration_mode: Option<InstanceFunction>,
    get_float64: Get<f64>,
    get_int32: Get<i32>,
    get_int64: Get<i64>,
    get_boolean: Get<bool>,
    get_string: Get<fmi3String>,
    get_binary: GetBinary,
    get_float32: Get<f32>,
    get_int8: Get<i8>,
    get_uint8: Get<u8>,
    get_int16: Get<i16>,
    get_uint16: Get<u16>,
    get_uint32: Get<u32>,
    get_uint64: Get<u64>,
    set_float32: Set<f32>,
    set_int8: Set<i8>,
    set_uint8: Set<u8>,
    set_int16: Set<i16>,
    set_uint16: Set<u16>,
    set_uint32: Set<u32>,
    set_uint64: Set<u64>,
    set_binary: SetBinary,
    set_float64: Set<f64>,
    set_int32: Set<i32>,
    set_int64: Set<i64>,
    set_boolean: Set<bool>,
    set_string: Set<fmi3String>,
    do_step: Option<DoStep>,
    get_output_derivatives: Option<OutputDerivatives>,
    get_directional_derivative: DirectionalDerivative,
    get_fmu_state: GetState,
    set_fmu_state: SetState,
    free_fmu_state: GetState,
    serialized_size: StateSize,
    serialize: Serialize,
    deserialize: Deserialize,
    me: Option<MeApi>,
    events: Option<EventApi>,
    /// Scheduled Execution (FMI 3.0, chapter 5): fmi3InstantiateScheduledExecution,
    /// fmi3ActivateModelPartition.
    scheduled: Option<(InstantiateSE, ActivateModelPartition)>,
}

/// A loaded FMI 3.0 binary.
struct Library {
    api: Api,
    _lib: libloading::Library,
}

impl Library {
    fn load(path: &Path) -> Result<Library, String> {
        let lib = load_binary(path)?;
        // SAFETY: each symbol is an FMI 3.0 function of the type fmi3FunctionTypes.h gives
        // (every one is exported by an FMI 3.0 binary: FMI 3.0, 2.3.1).
        let api = unsafe {
            // Optional: the functions of the interface an FMU may not offer (FMI 3.0 asks every
            // binary to export every function; some exporters leave out what they do not offer).
            let me = (|| {
                Some(MeApi {
                    instantiate: optional(&lib, "fmi3InstantiateModelExchange")?,
                    set_time: optional(&lib, "fmi3SetTime")?,
                    set_continuous_states: optional(&lib, "fmi3SetContinuousStates")?,
                    get_derivatives: optional(&lib, "fmi3GetContinuousStateDerivatives")?,
                    get_event_indicators: optional(&lib, "fmi3GetEventIndicators")?,
                    get_continuous_states: optional(&lib, "fmi3GetContinuousStates")?,
                    get_nominals: optional(&lib, "fmi3GetNominalsOfContinuousStates")?,
                    completed_integrator_step: optional(&lib, "fmi3CompletedIntegratorStep")?,
                    enter_event_mode: optional(&lib, "fmi3EnterEventMode")?,
                    update_discrete_states: optional(&lib, "fmi3UpdateDiscreteStates")?,
                    enter_continuous_time_mode: optional(&lib, "fmi3EnterContinuousTimeMode")?,
                    number_of: optional(&lib, "fmi3GetNumberOfContinuousStates")
                        .zip(optional(&lib, "fmi3GetNumberOfEventIndicators")),
                })
            })();
            let events = (|| {
                Some(EventApi {
                    enter_event_mode: optional(&lib, "fmi3EnterEventMode")?,
                    enter_step_mode: optional(&lib, "fmi3EnterStepMode")?,
                    update_discrete_states: optional(&lib, "fmi3UpdateDiscreteStates")?,
                    set_clock: optional(&lib, "fmi3SetClock")?,
                    get_clock: optional(&lib, "fmi3GetClock")?,
                    get_interval: optional(&lib, "fmi3GetIntervalDecimal")?,
                    get_shift: optional(&lib, "fmi3GetShiftDecimal")?,
                })
            })();
            let scheduled =
                optional(&lib, "fmi3InstantiateScheduledExecution").zip(optional(&lib, "fmi3ActivateModelPartition"));
            Api {
                me,
                events,
                scheduled,
                instantiate: optional(&lib, "fmi3InstantiateCoSimulation"),
                free_instance: symbol(&lib, path, "fmi3FreeInstance")?,
                set_debug_logging: symbol(&lib, path, "fmi3SetDebugLogging")?,
                enter_initialization_mode: symbol(&lib, path, "fmi3EnterInitializationMode")?,
                exit_initialization_mode: symbol(&lib, path, "fmi3ExitInitializationMode")?,
                terminate: symbol(&lib, path, "fmi3Terminate")?,
                reset: symbol(&lib, path, "fmi3Reset")?,
                enter_configuration_mode: optional(&lib, "fmi3EnterConfigurationMode"),
                exit_configuration_mode: optional(&lib, "fmi3ExitConfigurationMode"),
                get_float64: symbol(&lib, path, "fmi3GetFloat64")?,
                get_int32: symbol(&lib, path, "fmi3GetInt32")?,
                get_int64: symbol(&lib, path, "fmi3GetInt64")?,
                get_boolean: symbol(&lib, path, "fmi3GetBoolean")?,
                get_string: symbol(&lib, path, "fmi3GetString")?,
                get_binary: symbol(&lib, path, "fmi3GetBinary")?,
                get_float32: symbol(&lib, path, "fmi3GetFloat32")?,
                get_int8: symbol(&lib, path, "fmi3GetInt8")?,
                get_uint8: symbol(&lib, path, "fmi3GetUInt8")?,
                get_int16: symbol(&lib, path, "fmi3GetInt16")?,
                get_uint16: symbol(&lib, path, "fmi3GetUInt16")?,
                get_uint32: symbol(&lib, path, "fmi3GetUInt32")?,
                get_uint64: symbol(&lib, path, "fmi3GetUInt64")?,
                set_float32: symbol(&lib, path, "fmi3SetFloat32")?,
                set_int8: symbol(&lib, path, "fmi3SetInt8")?,
                set_uint8: symbol(&lib, path, "fmi3SetUInt8")?,
                set_int16: symbol(&lib, path, "fmi3SetInt16")?,
                set_uint16: symbol(&lib, path, "fmi3SetUInt16")?,
                set_uint32: symbol(&lib, path, "fmi3SetUInt32")?,
                set_uint64: symbol(&lib, path, "fmi3SetUInt64")?,
                set_binary: symbol(&lib, path, "fmi3SetBinary")?,
                set_float64: symbol(&lib, path, "fmi3SetFloat64")?,
                set_int32: symbol(&lib, path, "fmi3SetInt32")?,
                set_int64: symbol(&lib, path, "fmi3SetInt64")?,
                set_boolean: symbol(&lib, path, "fmi3SetBoolean")?,
                set_string: symbol(&lib, path, "fmi3SetString")?,
                do_step: optional(&lib, "fmi3DoStep"),
                get_output_derivatives: optional(&lib, "fmi3GetOutputDerivatives"),
                get_directional_derivative: symbol(&lib, path, "fmi3GetDirectionalDerivative")?,
                get_fmu_state: symbol(&lib, path, "fmi3GetFMUState")?,
                set_fmu_state: symbol(&lib, path, "fmi3SetFMUState")?,
                free_fmu_state: symbol(&lib, path, "fmi3FreeFMUState")?,
                serialized_size: symbol(&lib, path, "fmi3SerializedFMUStateSize")?,
                serialize: symbol(&lib, path, "fmi3SerializeFMUState")?,
                deserialize: symbol(&lib, path, "fmi3DeserializeFMUState")?,
            }
        };
        Ok(Library { api, _lib: lib })
    }
}

/// The FMI 3.0 platform folder (`<arch>-<os>`) of the machine this runs on.
pub fn platform_folder() -> Option<String> {
    let arch = match std::env::consts::ARCH {
        "x86_64" => "x86_64",
        "x86" => "x86",
        "aarch64" => "aarch64",
        _ => return None,
    };
    let os = match std::env::consts::OS {
        "linux" => "linux",
        "windows" => "windows",
        "macos" => "darwin",
        _ => return None,
    };
    Some(format!("{arch}-{os}"))
}

/// An FMI 3.0 FMU ready to instantiate: its folder and binary.
pub struct Fmi3Import {
    dir: PathBuf,
    library: Arc<Library>,
    token: CString,
    resource_path: CString,
    int64: Arc<HashSet<u32>>,
    /// The input clocks the runner ticks (None: it runs without event mode).
    clocks: Option<Arc<ClockPlan>>,
    /// Last: the unpacked folder goes after the library is unloaded.
    _scratch: Option<Scratch>,
}

impl Fmi3Import {
    /// Unpacks the FMU archive `bytes` into a fresh temporary folder (removed when this is dropped).
    pub fn from_bytes(
        bytes: &[u8],
        model_identifier: &str,
        token: &str,
        int64: HashSet<u32>,
    ) -> Result<Fmi3Import, String> {
        let tmp = scratch()?;
        let mut zip =
            zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| format!("not a zip archive: {e}"))?;
        zip.extract(&tmp.0)
            .map_err(|e| format!("cannot unpack into {}: {e}", tmp.0.display()))?;
        let mut import = Fmi3Import::from_dir(&tmp.0, model_identifier, token, int64)?;
        import._scratch = Some(tmp);
        Ok(import)
    }

    /// The FMU unpacked in `dir` (left as it is).
    pub fn from_dir(
        dir: &Path,
        model_identifier: &str,
        token: &str,
        int64: HashSet<u32>,
    ) -> Result<Fmi3Import, String> {
        let folder = platform_folder().ok_or_else(|| {
            format!(
                "FMI 3.0 names no binaries folder for {} on {}",
                std::env::consts::OS,
                std::env::consts::ARCH
            )
        })?;
        let binary = dir
            .join("binaries")
            .join(&folder)
            .join(format!("{model_identifier}{}", std::env::consts::DLL_SUFFIX));
        if !binary.is_file() {
            return Err(format!("no binary for this platform: {} is missing", binary.display()));
        }
        let library = Arc::new(Library::load(&binary)?);
        // resourcePath: a native absolute path with a trailing separator (FMI 3.0, 2.3.1).
        let abs = std::path::absolute(dir.join("resources")).unwrap_or_else(|_| dir.join("resources"));
        let mut path = abs.to_string_lossy().into_owned();
        if !path.ends_with(std::path::MAIN_SEPARATOR) {
            path.push(std::path::MAIN_SEPARATOR);
        }
        Ok(Fmi3Import {
            dir: dir.to_path_buf(),
            library,
            token: CString::new(token).map_err(|_| "an instantiation token with a NUL".to_string())?,
            resource_path: CString::new(path).map_err(|_| "a path with a NUL".to_string())?,
            int64: Arc::new(int64),
            clocks: None,
            _scratch: None,
        })
    }

    /// Its input clocks, ticked by the runner: co-simulation instances run with eventModeUsed.
    pub fn with_clocks(mut self, plan: Option<ClockPlan>) -> Result<Fmi3Import, String> {
        if plan.is_some() && self.library.api.events.is_none() {
            return Err(
                "the FMU has clocks but its binary lacks fmi3EnterEventMode, fmi3EnterStepMode, \
                 fmi3UpdateDiscreteStates, fmi3SetClock, fmi3GetClock, fmi3GetIntervalDecimal or fmi3GetShiftDecimal"
                    .into(),
            );
        }
        self.clocks = plan.map(Arc::new);
        Ok(self)
    }

    /// Whether the runner ticks input clocks of this FMU.
    pub fn has_clocks(&self) -> bool {
        self.clocks.is_some()
    }

    /// Its clocks (None: it runs without event mode).
    pub fn clock_plan(&self) -> Option<&ClockPlan> {
        self.clocks.as_deref()
    }

    /// Where the FMU is unpacked.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The instance `c` this import's library made, with its environment.
    fn instance(&self, c: fmi3Instance, env: Box<Env>, clocks: Option<Arc<ClockPlan>>) -> Instance3 {
        Instance3 {
            clocks: clocks.map(|p| Box::new(ClockState::new(p))),
            library: self.library.clone(),
            c,
            states: Slots::default(),
            experiment: (None, 0.0, None),
            int64: self.int64.clone(),
            ptrs: Vec::new(),
            sizes: Vec::new(),
            env,
        }
    }

    /// fmi3InstantiateCoSimulation(name, ...) with the runner's logger; eventModeUsed when the
    /// runner ticks the FMU's input clocks (`fmi3/clocks.rs`), earlyReturnAllowed false.
    pub fn instantiate_cs(&self, name: &str, visible: bool, logging_on: bool) -> Result<Instance3, String> {
        self.instantiate_with(name, visible, logging_on, self.clocks.is_some(), false, None)
    }

    /// fmi3InstantiateCoSimulation(name, ...) with eventModeUsed and earlyReturnAllowed: the
    /// events it reports are handled in Event Mode, its early returns end the system's step.
    pub fn instantiate_cs_events(&self, name: &str) -> Result<Instance3, String> {
        if self.library.api.events.is_none() {
            return Err(
                "its binary lacks fmi3EnterEventMode, fmi3EnterStepMode, fmi3UpdateDiscreteStates, \
                 fmi3SetClock, fmi3GetClock, fmi3GetIntervalDecimal or fmi3GetShiftDecimal"
                    .into(),
            );
        }
        self.instantiate_with(name, false, false, true, true, None)
    }

    /// fmi3InstantiateCoSimulation; `intermediate`: the requiredIntermediateVariables, the
    /// intermediateUpdate callback and what it reads into ([`intermediate`]).
    fn instantiate_with(
        &self,
        name: &str,
        visible: bool,
        logging_on: bool,
        event_mode: bool,
        early_return: bool,
        intermediate: Option<(&[u32], fmi3IntermediateUpdateCallback, intermediate::Samples)>,
    ) -> Result<Instance3, String> {
        let name_c = CString::new(name).map_err(|_| format!("instance name '{name}' has a NUL"))?;
        let (required, callback, samples) = match intermediate {
            Some((vrs, callback, samples)) => (vrs, callback, Some(samples)),
            None => (&[][..], None, None),
        };
        let env = Box::new(Env {
            instance: name_c.clone(),
            updates: Default::default(),
            samples: std::cell::RefCell::new(samples),
        });
        let instantiate = self
            .library
            .api
            .instantiate
            .ok_or("the binary has no fmi3InstantiateCoSimulation")?;
        // SAFETY: valid C strings; the environment outlives the instance (dropped after
        // fmi3FreeInstance).
        let c = unsafe {
            instantiate(
                name_c.as_ptr(),
                self.token.as_ptr(),
                self.resource_path.as_ptr(),
                visible,
                logging_on,
                event_mode,
                early_return,
                if required.is_empty() {
                    std::ptr::null()
                } else {
                    required.as_ptr()
                },
                required.len(),
                &*env as *const Env as *mut c_void,
                Some(log_message),
                callback,
            )
        };
        if c.is_null() {
            return Err("fmi3InstantiateCoSimulation returned NULL".into());
        }
        let clocks = match (&self.clocks, event_mode) {
            (Some(p), _) => Some(p.clone()),
            (None, true) => Some(Arc::new(ClockPlan::default())),
            (None, false) => None,
        };
        let mut inst = self.instance(c, env, clocks);
        if let Some(state) = inst.clocks.as_mut() {
            state.early_allowed = early_return;
        }
        inst.arm_intermediate();
        Ok(inst)
    }
}

impl Fmi3Import {
    /// fmi3InstantiateModelExchange(name, ...) with the runner's logger (for [`crate::me`]).
    pub fn instantiate_me(&self, name: &str, visible: bool, logging_on: bool) -> Result<Instance3, String> {
        let me =
            self.library.api.me.as_ref().ok_or(
                "the binary lacks the model-exchange functions (fmi3InstantiateModelExchange, fmi3SetTime, ...)",
            )?;
        let name_c = CString::new(name).map_err(|_| format!("instance name '{name}' has a NUL"))?;
        let env = Box::new(Env {
            instance: name_c.clone(),
            updates: Default::default(),
            samples: Default::default(),
        });
        // SAFETY: valid C strings; the environment outlives the instance (dropped after
        // fmi3FreeInstance).
        let c = unsafe {
            (me.instantiate)(
                name_c.as_ptr(),
                self.token.as_ptr(),
                self.resource_path.as_ptr(),
                visible,
                logging_on,
                &*env as *const Env as *mut c_void,
                Some(log_message),
            )
        };
        if c.is_null() {
            return Err("fmi3InstantiateModelExchange returned NULL".into());
        }
        Ok(self.instance(c, env, None))
    }
}

/// The model-exchange calls of an FMI 3.0 instance, as [`crate::fmi2::Instance2`]'s.
impl Instance3 {
    fn me(&self) -> Result<&MeApi, Fmi2Error> {
        self.library
            .api
            .me
            .as_ref()
            .ok_or_else(|| Fmi2Error::Importer("the FMU has no model-exchange functions".into()))
    }

    crate::common::calls!(me time, states and indicators);
    crate::common::calls!(me vectors: get_derivatives, get_continuous_states, get_nominals);
    crate::common::calls!(me: enter_event_mode, enter_continuous_time_mode);

    /// (continuous states, event indicators) as the FMU counts them now (after Configuration
    /// Mode: as its structural parameters give them); None where its binary lacks the functions.
    pub fn me_sizes(&mut self) -> Result<Option<(usize, usize)>, Fmi2Error> {
        let Some((states, indicators)) = self.me()?.number_of else {
            return Ok(None);
        };
        let (mut nx, mut nz) = (0usize, 0usize);
        // SAFETY: a live model-exchange instance; the outputs point to locals.
        check(unsafe { states(self.c, &mut nx) })?;
        // SAFETY: as above.
        check(unsafe { indicators(self.c, &mut nz) })?;
        Ok(Some((nx, nz)))
    }

    /// (enterEventMode, terminateSimulation).
    pub fn completed_integrator_step(&mut self, no_set_prior: bool) -> Result<(bool, bool), Fmi2Error> {
        let f = self.me()?.completed_integrator_step;
        let (mut event, mut terminate) = (false, false);
        // SAFETY: a live model-exchange instance; the outputs point to locals.
        check(unsafe { f(self.c, no_set_prior, &mut event, &mut terminate) })?;
        Ok((event, terminate))
    }

    /// fmi3UpdateDiscreteStates, its answers as FMI 2.0's event info.
    pub fn new_discrete_states(&mut self) -> Result<rustfmu::fmi2::abi::fmi2EventInfo, Fmi2Error> {
        let f = self.me()?.update_discrete_states;
        let (status, d) = self.update_discrete_states(f);
        check(status)?;
        let b = |x: bool| rustfmu::fmi2::abi::fmi2Boolean::from(x);
        Ok(rustfmu::fmi2::abi::fmi2EventInfo {
            newDiscreteStatesNeeded: b(d.update),
            terminateSimulation: b(d.terminate),
            nominalsOfContinuousStatesChanged: b(d.nominals),
            valuesOfContinuousStatesChanged: b(d.values),
            nextEventTimeDefined: b(d.defined),
            nextEventTime: d.next,
        })
    }
}

/// What fmi3UpdateDiscreteStates answered besides its status: discreteStatesNeedUpdate,
/// terminateSimulation, nominalsOfContinuousStatesChanged, valuesOfContinuousStatesChanged,
/// nextEventTimeDefined, nextEventTime.
#[derive(Default)]
struct Discrete {
    update: bool,
    terminate: bool,
    nominals: bool,
    values: bool,
    defined: bool,
    next: f64,
}

impl Instance3 {
    /// fmi3UpdateDiscreteStates through `f` (the model-exchange functions' or the event
    /// functions' of co-simulation): its status and answers.
    fn update_discrete_states(&self, f: UpdateDiscreteStates) -> (fmi3Status, Discrete) {
        let mut d = Discrete::default();
        // SAFETY: a live instance in Event Mode (the callers'); the outputs point to the fields of
        // a local.
        let status = unsafe {
            f(
                self.c,
                &mut d.update,
                &mut d.terminate,
                &mut d.nominals,
                &mut d.values,
                &mut d.defined,
                &mut d.next,
            )
        };
        (status, d)
    }
}

/// The instanceEnvironment of an instance: its name, for the messages.
struct Env {
    instance: CString,
    /// What the clockUpdate callback of a Scheduled Execution instance read ([`scheduled`]).
    updates: std::cell::RefCell<Option<scheduled::Updates>>,
    /// What the intermediateUpdate callback read ([`intermediate`]; None: no callback).
    samples: std::cell::RefCell<Option<intermediate::Samples>>,
}

/// Every FMU message goes to the `log` crate as FMI 2.0 ones do (module path "logger", target
/// the instance name, the level from the status).
unsafe extern "C" fn log_message(
    env: fmi3InstanceEnvironment,
    status: fmi3Status,
    category: fmi3String,
    message: fmi3String,
) {
    let _ = std::panic::catch_unwind(|| {
        let s = |p: *const c_char| {
            if p.is_null() {
                String::new()
            } else {
                // SAFETY: the FMU passes NUL-terminated strings.
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        let name = if env.is_null() {
            String::new()
        } else {
            // SAFETY: `env` is the Env this instance was given.
            unsafe { &*(env as *const Env) }.instance.to_string_lossy().into_owned()
        };
        let _ = s(category);
        let level = match status {
            fmi3OK => log::Level::Info,
            fmi3Warning => log::Level::Warn,
            fmi3Discard => log::Level::Trace,
            _ => log::Level::Error,
        };
        log::logger().log(
            &log::Record::builder()
                .args(format_args!("{}", s(message)))
                .level(level)
                .module_path(Some("logger"))
                .target(&name)
                .build(),
        );
    });
}

/// An FMI 3.0 co-simulation instance; fmi3FreeInstance when dropped (its FMU states freed first).
pub struct Instance3 {
    library: Arc<Library>,
    c: fmi3Instance,
    states: Slots,
    /// tolerance, start and stop time of `setup_experiment`, for fmi3EnterInitializationMode.
    experiment: (Option<f64>, f64, Option<f64>),
    int64: Arc<HashSet<u32>>,
    /// The pointers and sizes of the String and Binary values of a typed call, kept from call
    /// to call ([`Instance3::get_typed`]).
    ptrs: Vec<*const u8>,
    sizes: Vec<usize>,
    /// The input clocks the runner ticks and where they stand (None: no event mode).
    clocks: Option<Box<ClockState>>,
    env: Box<Env>,
}

// SAFETY: as an FMI 2.0 instance (FMI 3.0, 2.2.1: one thread at a time).
unsafe impl Send for Instance3 {}

impl Drop for Instance3 {
    fn drop(&mut self) {
        for s in self.states.live() {
            // SAFETY: a state this instance took and did not free.
            unsafe { (self.library.api.free_fmu_state)(self.c, s) };
        }
        // SAFETY: the instance this library made, freed once.
        unsafe { (self.library.api.free_instance)(self.c) };
    }
}

impl Instance3 {
    fn api(&self) -> &Api {
        &self.library.api
    }

    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<(), Fmi2Error> {
        let owned: Vec<CString> = categories
            .iter()
            .map(|c| CString::new(*c).unwrap_or_default())
            .collect();
        let ptrs: Vec<fmi3String> = owned.iter().map(|c| c.as_ptr()).collect();
        // SAFETY: a live instance; `ptrs` holds `len` valid strings.
        check(unsafe { (self.api().set_debug_logging)(self.c, on, ptrs.len(), ptrs.as_ptr()) })
    }

    /// Kept for fmi3EnterInitializationMode, which takes them (FMI 3.0 has no setup function).
    pub fn setup_experiment(&mut self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> Result<(), Fmi2Error> {
        self.experiment = (tolerance, start, stop);
        Ok(())
    }

    pub fn enter_initialization_mode(&mut self) -> Result<(), Fmi2Error> {
        if let Some(c) = &mut self.clocks {
            c.initializing = true;
        }
        let (tol, start, stop) = self.experiment;
        // SAFETY: a live instance.
        check(unsafe {
            (self.api().enter_initialization_mode)(
                self.c,
                tol.is_some(),
                tol.unwrap_or(0.0),
                start,
                stop.is_some(),
                stop.unwrap_or(0.0),
            )
        })
    }

    crate::common::calls!(instance: terminate);

    pub fn exit_initialization_mode(&mut self) -> Result<(), Fmi2Error> {
        if self.clocks.is_some() {
            return self.exit_initialization_clocked();
        }
        // SAFETY: a live instance.
        check(unsafe { (self.api().exit_initialization_mode)(self.c) })
    }

    /// fmi3EnterConfigurationMode (`enter`) or fmi3ExitConfigurationMode: the structural
    /// parameters are set between the two (FMI 3.0.2, Configuration Mode).
    pub fn configuration_mode(&mut self, enter: bool) -> Result<(), Fmi2Error> {
        let (f, name) = if enter {
            (self.api().enter_configuration_mode, "fmi3EnterConfigurationMode")
        } else {
            (self.api().exit_configuration_mode, "fmi3ExitConfigurationMode")
        };
        let f = f.ok_or_else(|| Fmi2Error::Importer(format!("the binary has no {name}")))?;
        // SAFETY: a live instance.
        check(unsafe { f(self.c) })
    }

    pub fn reset(&mut self) -> Result<(), Fmi2Error> {
        if let Some(c) = &mut self.clocks {
            c.reset();
        }
        // SAFETY: a live instance.
        check(unsafe { (self.api().reset)(self.c) })
    }

    pub fn do_step(&mut self, t: f64, h: f64, no_set_prior: bool) -> Result<(), Fmi2Error> {
        if self.clocks.as_ref().is_some_and(|c| c.scheduled) {
            return self.step_scheduled(t, h);
        }
        if self.clocks.is_some() {
            self.end_event_mode(t, h)?;
        }
        let (mut event, mut terminate, mut early, mut last) = (false, false, false, t);
        // SAFETY: a live instance; the four outputs point to locals.
        check(unsafe {
            (self
                .api()
                .do_step
                .ok_or_else(|| Fmi2Error::Importer("the binary has no fmi3DoStep".into()))?)(
                self.c,
                t,
                h,
                no_set_prior,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last,
            )
        })?;
        if terminate {
            // FMI 3.0.2 4.2.1: "the FMU requests to stop the simulation"; lastSuccessfulTime is
            // where it stopped (the step's end if it gives a time outside the step).
            return Err(Fmi2Error::Terminate(if last >= t && last <= t + h {
                last
            } else {
                t + h
            }));
        }
        if early {
            if !self.clocks.as_ref().is_some_and(|c| c.early_allowed) {
                return Err(Fmi2Error::Importer(format!(
                    "fmi3DoStep({t}, {h}) returned early at {last} (not allowed: earlyReturnAllowed = false)"
                )));
            }
            if !(last >= t && last <= t + h) {
                return Err(Fmi2Error::Importer(format!(
                    "fmi3DoStep({t}, {h}) returned early at lastSuccessfulTime = {last}, outside the step"
                )));
            }
            self.state_mut().early_at = Some(last);
            return self.begin_event_mode(last, event);
        }
        if self.clocks.is_some() {
            self.begin_event_mode(t + h, event)?;
        }
        Ok(())
    }

    pub fn get_output_derivatives(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        let orders = vec![1i32; vrs.len()];
        // SAFETY: a live instance; the arrays hold vrs.len() elements.
        check(unsafe {
            (self
                .api()
                .get_output_derivatives
                .ok_or_else(|| Fmi2Error::Importer("the binary has no fmi3GetOutputDerivatives".into()))?)(
                self.c,
                vrs.as_ptr(),
                vrs.len(),
                orders.as_ptr(),
                out.as_mut_ptr(),
                out.len(),
            )
        })
    }

    /// FMI 3.0 has no input derivatives.
    pub fn set_input_derivatives(&mut self, _vrs: &[u32], _values: &[f64]) -> Result<(), Fmi2Error> {
        Err(Fmi2Error::Importer("FMI 3.0 has no input derivatives".into()))
    }

    pub fn get_directional_derivative(&mut self, mut d: Directional) -> Result<(), Fmi2Error> {
        d.check_lengths(lengths)?;
        let (unknowns, n_unknowns, knowns, n_knowns, seed, out) = d.c_args();
        let f = self.api().get_directional_derivative;
        // SAFETY: a live instance; the arrays hold the lengths passed (checked: the seed as many
        // as the knowns, the output as the unknowns; every variable a scalar).
        check(unsafe {
            f(
                self.c, unknowns, n_unknowns, knowns, n_knowns, seed, n_knowns, out, n_unknowns,
            )
        })
    }

    /// fmi3GetFloat64, whatever the clocks (for [`clocks`]).
    fn get_float64(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
        // SAFETY: a live instance; both arrays hold vrs.len() elements (every variable a scalar).
        check(unsafe { (self.api().get_float64)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr(), out.len()) })
    }

    /// fmi3SetFloat64, whatever the clocks (for [`clocks`]).
    fn set_float64(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
        // SAFETY: a live instance; both arrays hold vrs.len() elements.
        check(unsafe { (self.api().set_float64)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr(), values.len()) })
    }

    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        if self.clocks.is_some() {
            return self.get_clocked(vrs, out);
        }
        // SAFETY: a live instance; both arrays hold vrs.len() elements (every variable a scalar).
        check(unsafe { (self.api().get_float64)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr(), out.len()) })
    }

    /// Int32 variables, and Enumerations (fmi3GetInt64, narrowed).
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        for (k, vr) in vrs.iter().enumerate() {
            if self.int64.contains(vr) {
                let mut x = [0i64];
                // SAFETY: a live instance; one value.
                check(unsafe { (self.api().get_int64)(self.c, vr, 1, x.as_mut_ptr(), 1) })?;
                out[k] = i32::try_from(x[0])
                    .map_err(|_| Fmi2Error::Importer(format!("value reference {vr}: {} does not fit 32 bits", x[0])))?;
            } else {
                // SAFETY: as above.
                check(unsafe { (self.api().get_int32)(self.c, vr, 1, &mut out[k], 1) })?;
            }
        }
        Ok(())
    }

    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        let mut b = vec![false; vrs.len()];
        // SAFETY: a live instance; both arrays hold vrs.len() elements.
        check(unsafe { (self.api().get_boolean)(self.c, vrs.as_ptr(), vrs.len(), b.as_mut_ptr(), b.len()) })?;
        for (o, x) in out.iter_mut().zip(b) {
            *o = i32::from(x);
        }
        Ok(())
    }

    pub fn get_string(&mut self, vrs: &[u32], out: &mut [CString]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        let mut ptrs: Vec<fmi3String> = vec![std::ptr::null(); vrs.len()];
        // SAFETY: as get_real; the FMU's strings are copied before the next call.
        check(unsafe { (self.api().get_string)(self.c, vrs.as_ptr(), vrs.len(), ptrs.as_mut_ptr(), ptrs.len()) })?;
        for (o, p) in out.iter_mut().zip(&ptrs) {
            if p.is_null() {
                return Err(Fmi2Error::Importer("fmi3GetString gave a NULL string".into()));
            }
            // SAFETY: a NUL-terminated string of the FMU, valid until its next call.
            *o = unsafe { CStr::from_ptr(*p) }.to_owned();
        }
        Ok(())
    }

    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), values.len())?;
        if self.clocks.is_some() {
            return self.set_clocked(vrs, values);
        }
        // SAFETY: a live instance; both arrays hold vrs.len() elements.
        check(unsafe { (self.api().set_float64)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr(), values.len()) })
    }

    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), values.len())?;
        for (vr, &x) in vrs.iter().zip(values) {
            if self.int64.contains(vr) {
                let wide = [i64::from(x)];
                // SAFETY: a live instance; one value.
                check(unsafe { (self.api().set_int64)(self.c, vr, 1, wide.as_ptr(), 1) })?;
            } else {
                // SAFETY: as above.
                check(unsafe { (self.api().set_int32)(self.c, vr, 1, &x, 1) })?;
            }
        }
        Ok(())
    }

    pub fn set_boolean(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), values.len())?;
        let b: Vec<bool> = values.iter().map(|&x| x != 0).collect();
        // SAFETY: a live instance; both arrays hold vrs.len() elements.
        check(unsafe { (self.api().set_boolean)(self.c, vrs.as_ptr(), vrs.len(), b.as_ptr(), b.len()) })
    }

    pub fn set_string(&mut self, vrs: &[u32], values: &[CString]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), values.len())?;
        let ptrs: Vec<fmi3String> = values.iter().map(|s| s.as_ptr()).collect();
        // SAFETY: as set_real.
        check(unsafe { (self.api().set_string)(self.c, vrs.as_ptr(), vrs.len(), ptrs.as_ptr(), ptrs.len()) })
    }

    pub fn get_fmu_state(&mut self) -> Result<FmuState, Fmi2Error> {
        let mut s: fmi3FMUState = std::ptr::null_mut();
        // SAFETY: a live instance; `s` is NULL, so the FMU makes a new state.
        check(unsafe { (self.api().get_fmu_state)(self.c, &mut s) })?;
        self.states.keep(s)
    }

    pub fn update_fmu_state(&mut self, s: &FmuState) -> Result<(), Fmi2Error> {
        let mut raw = self.states.raw(s)?;
        // SAFETY: a live instance and one of its states.
        check(unsafe { (self.api().get_fmu_state)(self.c, &mut raw) })?;
        self.states.replace(s, raw);
        Ok(())
    }

    pub fn set_fmu_state(&mut self, s: &FmuState) -> Result<(), Fmi2Error> {
        let raw = self.states.raw(s)?;
        // SAFETY: a live instance and one of its states.
        check(unsafe { (self.api().set_fmu_state)(self.c, raw) })
    }

    pub fn free_fmu_state(&mut self, s: FmuState) -> Result<(), Fmi2Error> {
        let mut raw = self.states.raw(&s)?;
        self.states.forget(&s);
        // SAFETY: a live instance and one of its states, freed once.
        check(unsafe { (self.api().free_fmu_state)(self.c, &mut raw) })
    }

    pub fn serialize_fmu_state(&mut self, s: &FmuState) -> Result<Vec<u8>, Fmi2Error> {
        let raw = self.states.raw(s)?;
        let mut size = 0usize;
        // SAFETY: a live instance and one of its states; the buffer holds `size` bytes.
        check(unsafe { (self.api().serialized_size)(self.c, raw, &mut size) })?;
        let mut out = vec![0u8; size];
        // SAFETY: as above; `out` holds the `size` bytes the FMU asked for.
        check(unsafe { (self.api().serialize)(self.c, raw, out.as_mut_ptr(), size) })?;
        Ok(out)
    }

    pub fn deserialize_fmu_state(&mut self, bytes: &[u8]) -> Result<FmuState, Fmi2Error> {
        let mut s: fmi3FMUState = std::ptr::null_mut();
        // SAFETY: a live instance; `bytes` is readable for its length.
        check(unsafe { (self.api().deserialize)(self.c, bytes.as_ptr(), bytes.len(), &mut s) })?;
        self.states.keep(s)
    }
}
