//! The runner's FMI 2.0 co-simulation importer: an FMU unpacked (or found unpacked), its binary
//! loaded once, instances, values, steps and FMU states.
//!
//! Written here rather than taken from the `fmi` crate (0.8), which the runner used before the
//! container FMU (`cargo fmu container`) linked the runner into an FMU binary of its own. What
//! was measured against the crate there (`cargo fmu check` of the PendulumLQR container):
//! - its fmi-sys exports a `callback_log` symbol from every library it is linked into (the
//!   check "the binary exports the fmi2 functions and no others" failed); this importer's C
//!   logger (`c/logger.c`) is a static C function, not exported;
//! - its import unpacks every FMU into a fresh temporary folder at every load (30 ms per
//!   instantiation of the container), and the `tempfile` names come from a thread-local random
//!   generator whose thread handle stays allocated after the container is unloaded (valgrind:
//!   48 bytes possibly lost per run); here an FMU is unpacked once (or read unpacked from a
//!   container's resources) and its binary loaded once for all its instances;
//! - it never calls fmi2FreeFMUstate before the instance is freed, so every deserialized state
//!   stayed allocated: [`InstanceCS::free_fmu_state`](crate::instance::InstanceCS::free_fmu_state) frees one;
//! - its logger shim panics on an `fmi2Pending` status inside a C callback (an abort of the
//!   importer); here every status is a message;
//! - fmi-sys runs bindgen (libclang) at build time: a cross build of the container for Windows
//!   or macOS needed libclang with the target's headers; this importer's C types are
//!   `rustfmu::fmi2::abi`'s, proven equal to the official headers by `tests/abi_matches_fmi_sys.rs`.

#![allow(non_upper_case_globals)]

use crate::common::{Directional, Scratch, Slots, lengths, load_binary, optional, scratch, symbol};
use rustfmu::fmi2::abi::*;
use std::ffi::{CStr, CString, c_char, c_void};
use std::path::{Path, PathBuf};
use std::sync::Arc;

// The error and the FMU states are the runner's common types ([`crate::common`]); named here too,
// where an importer of FMI 2.0 FMUs looks for them.
pub use crate::common::{Deferred, Fmi2Error, FmuState};

fn check(status: fmi2Status) -> Result<(), Fmi2Error> {
    match status {
        fmi2OK | fmi2Warning => Ok(()),
        fmi2Discard => Err(Fmi2Error::Discard),
        fmi2Error => Err(Fmi2Error::Error),
        fmi2Fatal => Err(Fmi2Error::Fatal),
        fmi2Pending => Err(Fmi2Error::Pending),
        s => Err(Fmi2Error::Unknown(s)),
    }
}

/// The functions of an FMI 2.0 co-simulation binary the runner calls.
struct Api {
    instantiate: fmi2InstantiateTYPE,
    free_instance: fmi2FreeInstanceTYPE,
    set_debug_logging: fmi2SetDebugLoggingTYPE,
    setup_experiment: fmi2SetupExperimentTYPE,
    enter_initialization_mode: fmi2ComponentFunctionTYPE,
    exit_initialization_mode: fmi2ComponentFunctionTYPE,
    terminate: fmi2ComponentFunctionTYPE,
    reset: fmi2ComponentFunctionTYPE,
    get_real: fmi2GetTYPE<f64>,
    get_integer: fmi2GetTYPE<fmi2Integer>,
    get_boolean: fmi2GetTYPE<fmi2Boolean>,
    get_string: fmi2GetTYPE<fmi2String>,
    set_real: fmi2SetTYPE<f64>,
    set_integer: fmi2SetTYPE<fmi2Integer>,
    set_boolean: fmi2SetTYPE<fmi2Boolean>,
    set_string: fmi2SetTYPE<fmi2String>,
    /// Absent from a model-exchange-only FMU.
    do_step: Option<fmi2DoStepTYPE>,
    /// fmi2GetBooleanStatus, fmi2GetRealStatus (co-simulation): asked after fmi2DoStep answers
    /// fmi2Discard (fmi2Terminated, fmi2LastSuccessfulTime).
    get_boolean_status: Option<StatusOf<fmi2Boolean>>,
    get_real_status: Option<StatusOf<fmi2Real>>,
    /// fmi2GetRealOutputDerivatives, fmi2SetRealInputDerivatives (co-simulation, optional).
    get_output_derivatives: Option<Derivatives<*mut fmi2Real>>,
    set_input_derivatives: Option<Derivatives<*const fmi2Real>>,
    get_directional_derivative: Option<DirectionalDerivative>,
    /// The model-exchange functions (fmi2FunctionTypes.h): absent from a co-simulation-only FMU.
    me: Option<MeApi>,
    /// The FMU-state functions: absent from an FMU that declares no FMU state.
    get_fmu_state: Option<fmi2GetFMUstateTYPE>,
    set_fmu_state: Option<fmi2SetFMUstateTYPE>,
    free_fmu_state: Option<fmi2GetFMUstateTYPE>,
    serialized_size: Option<fmi2SerializedFMUstateSizeTYPE>,
    serialize: Option<fmi2SerializeFMUstateTYPE>,
    deserialize: Option<fmi2DeSerializeFMUstateTYPE>,
}

/// `fmi2GetDerivativesTYPE`, `fmi2GetEventIndicatorsTYPE`, `fmi2GetContinuousStatesTYPE`,
/// `fmi2GetNominalsOfContinuousStatesTYPE`, `fmi2SetContinuousStatesTYPE` (const).
type VectorGet = unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status;
type VectorSet = unsafe extern "C" fn(fmi2Component, *const fmi2Real, usize) -> fmi2Status;

/// `fmi2GetRealOutputDerivativesTYPE` (`P`: `*mut fmi2Real`), `fmi2SetRealInputDerivativesTYPE`
/// (`*const fmi2Real`), `fmi2GetDirectionalDerivativeTYPE`.
type Derivatives<P> =
    unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2Integer, P) -> fmi2Status;
type DirectionalDerivative = unsafe extern "C" fn(
    fmi2Component,
    *const fmi2ValueReference,
    usize,
    *const fmi2ValueReference,
    usize,
    *const fmi2Real,
    *mut fmi2Real,
) -> fmi2Status;

/// `fmi2GetBooleanStatusTYPE` (`T`: `fmi2Boolean`), `fmi2GetRealStatusTYPE` (`fmi2Real`).
type StatusOf<T> = unsafe extern "C" fn(fmi2Component, fmi2StatusKind, *mut T) -> fmi2Status;

/// The model-exchange functions of an FMI 2.0 binary (fmi2FunctionTypes.h, section 3.2).
struct MeApi {
    set_time: unsafe extern "C" fn(fmi2Component, fmi2Real) -> fmi2Status,
    set_continuous_states: VectorSet,
    get_derivatives: VectorGet,
    get_event_indicators: VectorGet,
    get_continuous_states: VectorGet,
    get_nominals: VectorGet,
    completed_integrator_step:
        unsafe extern "C" fn(fmi2Component, fmi2Boolean, *mut fmi2Boolean, *mut fmi2Boolean) -> fmi2Status,
    enter_event_mode: fmi2ComponentFunctionTYPE,
    new_discrete_states: unsafe extern "C" fn(fmi2Component, *mut fmi2EventInfo) -> fmi2Status,
    enter_continuous_time_mode: fmi2ComponentFunctionTYPE,
}

/// A loaded FMU binary.
pub struct Library {
    api: Api,
    // Last: unloaded after the function pointers above are gone.
    _lib: libloading::Library,
}

impl Library {
    fn load(path: &Path) -> Result<Library, String> {
        let lib = load_binary(path)?;
        // SAFETY: each symbol is an FMI 2.0 function of the type the standard's header gives.
        let api = unsafe {
            Api {
                instantiate: symbol(&lib, path, "fmi2Instantiate")?,
                free_instance: symbol(&lib, path, "fmi2FreeInstance")?,
                set_debug_logging: symbol(&lib, path, "fmi2SetDebugLogging")?,
                setup_experiment: symbol(&lib, path, "fmi2SetupExperiment")?,
                enter_initialization_mode: symbol(&lib, path, "fmi2EnterInitializationMode")?,
                exit_initialization_mode: symbol(&lib, path, "fmi2ExitInitializationMode")?,
                terminate: symbol(&lib, path, "fmi2Terminate")?,
                reset: symbol(&lib, path, "fmi2Reset")?,
                get_real: symbol(&lib, path, "fmi2GetReal")?,
                get_integer: symbol(&lib, path, "fmi2GetInteger")?,
                get_boolean: symbol(&lib, path, "fmi2GetBoolean")?,
                get_string: symbol(&lib, path, "fmi2GetString")?,
                set_real: symbol(&lib, path, "fmi2SetReal")?,
                set_integer: symbol(&lib, path, "fmi2SetInteger")?,
                set_boolean: symbol(&lib, path, "fmi2SetBoolean")?,
                set_string: symbol(&lib, path, "fmi2SetString")?,
                do_step: optional(&lib, "fmi2DoStep"),
                get_boolean_status: optional(&lib, "fmi2GetBooleanStatus"),
                get_real_status: optional(&lib, "fmi2GetRealStatus"),
                get_output_derivatives: optional(&lib, "fmi2GetRealOutputDerivatives"),
                set_input_derivatives: optional(&lib, "fmi2SetRealInputDerivatives"),
                get_directional_derivative: optional(&lib, "fmi2GetDirectionalDerivative"),
                me: (|| {
                    Some(MeApi {
                        set_time: optional(&lib, "fmi2SetTime")?,
                        set_continuous_states: optional(&lib, "fmi2SetContinuousStates")?,
                        get_derivatives: optional(&lib, "fmi2GetDerivatives")?,
                        get_event_indicators: optional(&lib, "fmi2GetEventIndicators")?,
                        get_continuous_states: optional(&lib, "fmi2GetContinuousStates")?,
                        get_nominals: optional(&lib, "fmi2GetNominalsOfContinuousStates")?,
                        completed_integrator_step: optional(&lib, "fmi2CompletedIntegratorStep")?,
                        enter_event_mode: optional(&lib, "fmi2EnterEventMode")?,
                        new_discrete_states: optional(&lib, "fmi2NewDiscreteStates")?,
                        enter_continuous_time_mode: optional(&lib, "fmi2EnterContinuousTimeMode")?,
                    })
                })(),
                get_fmu_state: optional(&lib, "fmi2GetFMUstate"),
                set_fmu_state: optional(&lib, "fmi2SetFMUstate"),
                free_fmu_state: optional(&lib, "fmi2FreeFMUstate"),
                serialized_size: optional(&lib, "fmi2SerializedFMUstateSize"),
                serialize: optional(&lib, "fmi2SerializeFMUstate"),
                deserialize: optional(&lib, "fmi2DeSerializeFMUstate"),
            }
        };
        Ok(Library { api, _lib: lib })
    }
}

/// The FMI 2.0 platform folder of the machine this runs on.
pub fn platform_folder() -> Option<&'static str> {
    match (std::env::consts::OS, std::env::consts::ARCH) {
        ("linux", "x86_64") => Some("linux64"),
        ("linux", "x86") => Some("linux32"),
        ("linux", "aarch64") => Some("aarch64-linux"),
        ("windows", "x86_64") => Some("win64"),
        ("windows", "x86") => Some("win32"),
        ("macos", _) => Some("darwin64"),
        _ => None,
    }
}

/// `file:` URI of a folder, percent-encoded (RFC 3986; on Windows `file:///C:/...`).
pub fn file_uri(dir: &Path) -> String {
    let abs = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    let mut text = abs.to_string_lossy().replace('\\', "/");
    if !text.starts_with('/') {
        text.insert(0, '/');
    }
    let mut out = String::from("file://");
    for b in text.bytes() {
        if b.is_ascii_alphanumeric() || b"/-._~:".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// An FMU ready to instantiate: its folder (unpacked by this process, or as found) and binary.
pub struct Fmi2Import {
    dir: PathBuf,
    library: Arc<Library>,
    guid: CString,
    resource_uri: CString,
    /// Last: the unpacked folder goes after the library is unloaded.
    _scratch: Option<Scratch>,
}

impl Fmi2Import {
    /// Unpacks the FMU archive `bytes` into a fresh temporary folder (removed when this is dropped).
    pub fn from_bytes(bytes: &[u8], model_identifier: &str, guid: &str) -> Result<Fmi2Import, String> {
        let tmp = scratch()?;
        let mut zip =
            zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| format!("not a zip archive: {e}"))?;
        zip.extract(&tmp.0)
            .map_err(|e| format!("cannot unpack into {}: {e}", tmp.0.display()))?;
        let mut import = Fmi2Import::from_dir(&tmp.0, model_identifier, guid)?;
        import._scratch = Some(tmp);
        Ok(import)
    }

    /// The FMU unpacked in `dir` (left as it is).
    pub fn from_dir(dir: &Path, model_identifier: &str, guid: &str) -> Result<Fmi2Import, String> {
        let folder = platform_folder().ok_or_else(|| {
            format!(
                "FMI 2.0 names no binaries folder for {} on {}",
                std::env::consts::OS,
                std::env::consts::ARCH
            )
        })?;
        let binary = dir
            .join("binaries")
            .join(folder)
            .join(format!("{model_identifier}{}", std::env::consts::DLL_SUFFIX));
        if !binary.is_file() {
            return Err(format!("no binary for this platform: {} is missing", binary.display()));
        }
        let library = Arc::new(Library::load(&binary)?);
        let uri = file_uri(&dir.join("resources"));
        Ok(Fmi2Import {
            dir: dir.to_path_buf(),
            library,
            guid: CString::new(guid).map_err(|_| "a GUID with a NUL".to_string())?,
            resource_uri: CString::new(uri).map_err(|_| "a path with a NUL".to_string())?,
            _scratch: None,
        })
    }

    /// Where the FMU is unpacked.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// fmi2Instantiate(name, fmi2CoSimulation, ...) with the runner's logger.
    pub fn instantiate_cs(&self, name: &str, visible: bool, logging_on: bool) -> Result<Instance2, String> {
        self.instantiate(name, fmi2CoSimulation, visible, logging_on)
    }

    /// fmi2Instantiate(name, fmi2ModelExchange, ...) with the runner's logger.
    pub fn instantiate_me(&self, name: &str, visible: bool, logging_on: bool) -> Result<Instance2, String> {
        if self.library.api.me.is_none() {
            return Err("the binary lacks the model-exchange functions (fmi2SetTime, fmi2GetDerivatives, ...)".into());
        }
        self.instantiate(name, fmi2ModelExchange, visible, logging_on)
    }

    fn instantiate(&self, name: &str, kind: fmi2Type, visible: bool, logging_on: bool) -> Result<Instance2, String> {
        let name_c = CString::new(name).map_err(|_| format!("instance name '{name}' has a NUL"))?;
        let env = Box::new(LogEnv {
            sink: forward,
            instance: name_c.clone(),
        });
        let callbacks = Box::new(fmi2CallbackFunctions {
            logger: Some(logger()),
            allocateMemory: Some(calloc_),
            freeMemory: Some(free_),
            stepFinished: None,
            componentEnvironment: &*env as *const LogEnv as *mut c_void,
        });
        // SAFETY: the arguments are valid C strings and callbacks that outlive the instance
        // (boxed, dropped after fmi2FreeInstance).
        let c = unsafe {
            (self.library.api.instantiate)(
                name_c.as_ptr(),
                kind,
                self.guid.as_ptr(),
                self.resource_uri.as_ptr(),
                &*callbacks,
                fmi2Boolean::from(visible),
                fmi2Boolean::from(logging_on),
            )
        };
        if c.is_null() {
            return Err("fmi2Instantiate returned NULL".into());
        }
        Ok(Instance2 {
            library: self.library.clone(),
            c,
            states: Slots::default(),
            _callbacks: callbacks,
            _env: env,
        })
    }
}

unsafe extern "C" fn calloc_(n: usize, size: usize) -> *mut c_void {
    // The FMU asks for n objects of size bytes each, zeroed (fmi2CallbackAllocateMemory).
    let Some(bytes) = n.checked_mul(size) else {
        return std::ptr::null_mut();
    };
    let bytes = bytes.max(1);
    let Ok(layout) = std::alloc::Layout::from_size_align(bytes + 16, 16) else {
        return std::ptr::null_mut();
    };
    // SAFETY: a non-zero size; the length is kept in front of the block for free_.
    unsafe {
        let p = std::alloc::alloc_zeroed(layout);
        if p.is_null() {
            return p as *mut c_void;
        }
        (p as *mut usize).write(bytes + 16);
        p.add(16) as *mut c_void
    }
}

unsafe extern "C" fn free_(p: *mut c_void) {
    if p.is_null() {
        return;
    }
    // SAFETY: `p` came from calloc_, 16 bytes after the start of a block whose size is there.
    unsafe {
        let start = (p as *mut u8).sub(16);
        let size = (start as *const usize).read();
        std::alloc::dealloc(start, std::alloc::Layout::from_size_align_unchecked(size, 16));
    }
}

/// The componentEnvironment of an instance: the C logger calls `sink` (its first field) with
/// the formatted text.
#[repr(C)]
struct LogEnv {
    sink: unsafe extern "C" fn(*const LogEnv, *const c_char, u32, *const c_char, *const c_char),
    instance: CString,
}

unsafe extern "C" {
    fn rustfmu_runner_logger(
        env: fmi2ComponentEnvironment,
        instance: fmi2String,
        status: fmi2Status,
        category: fmi2String,
        message: fmi2String,
        ...
    );
}

fn logger() -> unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...) {
    rustfmu_runner_logger
}

/// Every FMU message goes to the `log` crate: module path "logger", target the instance name,
/// the level from the status (fmi2OK: Info, fmi2Warning: Warn, fmi2Discard: Trace, fmi2Error
/// and fmi2Fatal: Error; what [`crate::fmu_log`] and the container read back).
unsafe extern "C" fn forward(
    env: *const LogEnv,
    instance: *const c_char,
    status: u32,
    category: *const c_char,
    text: *const c_char,
) {
    let _ = std::panic::catch_unwind(|| {
        let s = |p: *const c_char| {
            if p.is_null() {
                String::new()
            } else {
                // SAFETY: the C logger passes NUL-terminated strings.
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        let name = if instance.is_null() && !env.is_null() {
            // SAFETY: `env` is the LogEnv this instance was given.
            unsafe { &*env }.instance.to_string_lossy().into_owned()
        } else {
            s(instance)
        };
        let _ = s(category);
        let level = match status {
            fmi2OK | fmi2Pending => log::Level::Info,
            fmi2Warning => log::Level::Warn,
            fmi2Discard => log::Level::Trace,
            _ => log::Level::Error,
        };
        log::logger().log(
            &log::Record::builder()
                .args(format_args!("{}", s(text)))
                .level(level)
                .module_path(Some("logger"))
                .target(&name)
                .build(),
        );
    });
}

/// An FMI 2.0 co-simulation instance; fmi2FreeInstance when dropped (its FMU states freed first).
pub struct Instance2 {
    library: Arc<Library>,
    c: fmi2Component,
    /// FMU states taken.
    states: Slots,
    _callbacks: Box<fmi2CallbackFunctions>,
    _env: Box<LogEnv>,
}

// SAFETY: an FMI instance may be used from any one thread at a time (FMI 2.0, 2.1.1); the
// runner never uses one from two threads at once (it is owned by one Simulation).
unsafe impl Send for Instance2 {}

impl Drop for Instance2 {
    fn drop(&mut self) {
        if let Some(free) = self.library.api.free_fmu_state {
            for s in self.states.live() {
                // SAFETY: a state this instance took and did not free.
                unsafe { free(self.c, s) };
            }
        }
        // SAFETY: the instance this library made, freed once.
        unsafe { (self.library.api.free_instance)(self.c) };
    }
}

fn missing(what: &str) -> Fmi2Error {
    Fmi2Error::Importer(format!("the FMU has no {what}"))
}

impl Instance2 {
    fn api(&self) -> &Api {
        &self.library.api
    }

    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<(), Fmi2Error> {
        let owned: Vec<CString> = categories
            .iter()
            .map(|c| CString::new(*c).unwrap_or_default())
            .collect();
        let ptrs: Vec<fmi2String> = owned.iter().map(|c| c.as_ptr()).collect();
        // SAFETY: a live instance; `ptrs` holds `len` valid strings.
        check(unsafe { (self.api().set_debug_logging)(self.c, fmi2Boolean::from(on), ptrs.len(), ptrs.as_ptr()) })
    }

    pub fn setup_experiment(&mut self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> Result<(), Fmi2Error> {
        // SAFETY: a live instance.
        check(unsafe {
            (self.api().setup_experiment)(
                self.c,
                fmi2Boolean::from(tolerance.is_some()),
                tolerance.unwrap_or(0.0),
                start,
                fmi2Boolean::from(stop.is_some()),
                stop.unwrap_or(0.0),
            )
        })
    }

    crate::common::calls!(instance: enter_initialization_mode, exit_initialization_mode, terminate, reset);

    #[inline]
    pub fn do_step(&mut self, t: f64, h: f64, no_set_prior: bool) -> Result<(), Fmi2Error> {
        let step = self.api().do_step.ok_or_else(|| missing("fmi2DoStep"))?;
        // SAFETY: a live instance.
        match check(unsafe { step(self.c, t, h, fmi2Boolean::from(no_set_prior)) }) {
            Err(Fmi2Error::Discard) => Err(self.why_discarded(t, h)),
            r => r,
        }
    }

    /// After fmi2DoStep(t, h) answered fmi2Discard: [`Fmi2Error::Terminate`] at its
    /// fmi2LastSuccessfulTime where fmi2GetBooleanStatus(fmi2Terminated) says the slave wants to
    /// end the simulation (FMI 2.0.5 4.2.3), fmi2Discard otherwise.
    #[cold]
    #[inline(never)]
    fn why_discarded(&mut self, t: f64, h: f64) -> Fmi2Error {
        let Some(terminated) = self.api().get_boolean_status else {
            return Fmi2Error::Discard;
        };
        let mut yes: fmi2Boolean = fmi2False;
        // SAFETY: a live instance; the output points to a local.
        if check(unsafe { terminated(self.c, fmi2Terminated, &mut yes) }).is_err() || yes == fmi2False {
            return Fmi2Error::Discard;
        }
        let mut last = f64::NAN;
        if let Some(f) = self.api().get_real_status {
            // SAFETY: as above.
            if check(unsafe { f(self.c, fmi2LastSuccessfulTime, &mut last) }).is_err() {
                last = f64::NAN;
            }
        }
        // A time outside the step (or none given): the step's start, the last time known reached.
        Fmi2Error::Terminate(if last >= t && last <= t + h { last } else { t })
    }

    /// First time derivatives (order 1) of the outputs `vrs` (fmi2GetRealOutputDerivatives).
    pub fn get_output_derivatives(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
        let f = self.api().get_output_derivatives;
        self.derivatives(f, "fmi2GetRealOutputDerivatives", vrs, out.len(), out.as_mut_ptr())
    }

    /// First time derivatives of the inputs `vrs` (fmi2SetRealInputDerivatives, order 1).
    pub fn set_input_derivatives(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
        let f = self.api().set_input_derivatives;
        self.derivatives(f, "fmi2SetRealInputDerivatives", vrs, values.len(), values.as_ptr())
    }

    /// The first derivatives (`values`, `n` of them, got or set) of the variables `vrs` by the
    /// function `f` (`name`, optional).
    fn derivatives<P>(
        &self,
        f: Option<
            unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2Integer, P) -> fmi2Status,
        >,
        name: &str,
        vrs: &[u32],
        n: usize,
        values: P,
    ) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), n)?;
        let f = f.ok_or_else(|| missing(name))?;
        let orders = vec![1 as fmi2Integer; vrs.len()];
        // SAFETY: a live instance; the arrays hold vrs.len() elements (`values` too: `n`, checked).
        check(unsafe { f(self.c, vrs.as_ptr(), vrs.len(), orders.as_ptr(), values) })
    }

    /// d(unknowns) = J d(knowns) (fmi2GetDirectionalDerivative).
    pub fn get_directional_derivative(&mut self, mut d: Directional) -> Result<(), Fmi2Error> {
        d.check_lengths(lengths)?;
        let f = self
            .api()
            .get_directional_derivative
            .ok_or_else(|| missing("fmi2GetDirectionalDerivative"))?;
        let (unknowns, n_unknowns, knowns, n_knowns, seed, out) = d.c_args();
        // SAFETY: a live instance; the arrays hold the lengths passed (checked).
        check(unsafe { f(self.c, unknowns, n_unknowns, knowns, n_knowns, seed, out) })
    }

    fn me(&self) -> Result<&MeApi, Fmi2Error> {
        self.api()
            .me
            .as_ref()
            .ok_or_else(|| missing("model-exchange functions"))
    }

    crate::common::calls!(me time, states and indicators);
    crate::common::calls!(me vectors: get_derivatives, get_continuous_states, get_nominals);
    crate::common::calls!(me: enter_event_mode, enter_continuous_time_mode);

    /// fmi2CompletedIntegratorStep: (enterEventMode, terminateSimulation).
    pub fn completed_integrator_step(&mut self, no_set_prior: bool) -> Result<(bool, bool), Fmi2Error> {
        let f = self.me()?.completed_integrator_step;
        let (mut event, mut terminate) = (fmi2False, fmi2False);
        // SAFETY: a live model-exchange instance; the outputs point to locals.
        check(unsafe { f(self.c, fmi2Boolean::from(no_set_prior), &mut event, &mut terminate) })?;
        Ok((event != fmi2False, terminate != fmi2False))
    }

    pub fn new_discrete_states(&mut self) -> Result<fmi2EventInfo, Fmi2Error> {
        let f = self.me()?.new_discrete_states;
        let mut info = fmi2EventInfo {
            newDiscreteStatesNeeded: fmi2False,
            terminateSimulation: fmi2False,
            nominalsOfContinuousStatesChanged: fmi2False,
            valuesOfContinuousStatesChanged: fmi2False,
            nextEventTimeDefined: fmi2False,
            nextEventTime: 0.0,
        };
        // SAFETY: a live model-exchange instance; `info` is a local.
        check(unsafe { f(self.c, &mut info) })?;
        Ok(info)
    }

    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        // SAFETY: a live instance; both arrays hold vrs.len() elements.
        check(unsafe { (self.api().get_real)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) })
    }

    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        // SAFETY: as get_real.
        check(unsafe { (self.api().get_integer)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) })
    }

    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        // SAFETY: as get_real.
        check(unsafe { (self.api().get_boolean)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) })
    }

    pub fn get_string(&mut self, vrs: &[u32], out: &mut [CString]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), out.len())?;
        let mut ptrs: Vec<fmi2String> = vec![std::ptr::null(); vrs.len()];
        // SAFETY: as get_real; the FMU's strings are copied before the next call.
        check(unsafe { (self.api().get_string)(self.c, vrs.as_ptr(), vrs.len(), ptrs.as_mut_ptr()) })?;
        for (o, p) in out.iter_mut().zip(&ptrs) {
            if p.is_null() {
                return Err(Fmi2Error::Importer("fmi2GetString gave a NULL string".into()));
            }
            // SAFETY: a NUL-terminated string of the FMU, valid until its next call.
            *o = unsafe { CStr::from_ptr(*p) }.to_owned();
        }
        Ok(())
    }

    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), values.len())?;
        // SAFETY: a live instance; both arrays hold vrs.len() elements.
        check(unsafe { (self.api().set_real)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) })
    }

    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), values.len())?;
        // SAFETY: as set_real.
        check(unsafe { (self.api().set_integer)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) })
    }

    pub fn set_boolean(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), values.len())?;
        // SAFETY: as set_real.
        check(unsafe { (self.api().set_boolean)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) })
    }

    pub fn set_string(&mut self, vrs: &[u32], values: &[CString]) -> Result<(), Fmi2Error> {
        lengths(vrs.len(), values.len())?;
        let ptrs: Vec<fmi2String> = values.iter().map(|s| s.as_ptr()).collect();
        // SAFETY: as set_real.
        check(unsafe { (self.api().set_string)(self.c, vrs.as_ptr(), vrs.len(), ptrs.as_ptr()) })
    }

    /// FMI 2.0 has only its four types ([`Instance2::get_real`] ...): never called for it.
    pub fn get_typed(&mut self, _vrs: &[u32], out: &mut crate::values::Values) -> Result<(), Fmi2Error> {
        Err(Fmi2Error::Importer(format!(
            "an FMI 2.0 FMU has no {} variables",
            out.type_name()
        )))
    }

    /// FMI 2.0 has no Configuration Mode (nor structural parameters).
    pub fn configuration_mode(&mut self, _enter: bool) -> Result<(), Fmi2Error> {
        Err(Fmi2Error::Importer(
            "an FMI 2.0 FMU has no Configuration Mode (no structural parameters)".into(),
        ))
    }

    /// As [`Instance2::get_typed`].
    pub fn set_typed(&mut self, _vrs: &[u32], values: &crate::values::Values) -> Result<(), Fmi2Error> {
        Err(Fmi2Error::Importer(format!(
            "an FMI 2.0 FMU has no {} variables",
            values.type_name()
        )))
    }

    /// fmi2GetFMUstate into a new state of this instance.
    pub fn get_fmu_state(&mut self) -> Result<FmuState, Fmi2Error> {
        let get = self.api().get_fmu_state.ok_or_else(|| missing("fmi2GetFMUstate"))?;
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: a live instance; `s` is NULL, so the FMU makes a new state.
        check(unsafe { get(self.c, &mut s) })?;
        self.states.keep(s)
    }

    /// fmi2GetFMUstate into the existing state `s` (overwritten).
    pub fn update_fmu_state(&mut self, s: &FmuState) -> Result<(), Fmi2Error> {
        let get = self.api().get_fmu_state.ok_or_else(|| missing("fmi2GetFMUstate"))?;
        let mut raw = self.states.raw(s)?;
        // SAFETY: a live instance and one of its states.
        check(unsafe { get(self.c, &mut raw) })?;
        self.states.replace(s, raw);
        Ok(())
    }

    pub fn set_fmu_state(&mut self, s: &FmuState) -> Result<(), Fmi2Error> {
        let set = self.api().set_fmu_state.ok_or_else(|| missing("fmi2SetFMUstate"))?;
        let raw = self.states.raw(s)?;
        // SAFETY: a live instance and one of its states.
        check(unsafe { set(self.c, raw) })
    }

    /// fmi2FreeFMUstate of `s` (which is then no state of this instance).
    pub fn free_fmu_state(&mut self, s: FmuState) -> Result<(), Fmi2Error> {
        let free = self.api().free_fmu_state.ok_or_else(|| missing("fmi2FreeFMUstate"))?;
        let mut raw = self.states.raw(&s)?;
        self.states.forget(&s);
        // SAFETY: a live instance and one of its states, freed once.
        check(unsafe { free(self.c, &mut raw) })
    }

    pub fn serialize_fmu_state(&mut self, s: &FmuState) -> Result<Vec<u8>, Fmi2Error> {
        let size_of = self
            .api()
            .serialized_size
            .ok_or_else(|| missing("fmi2SerializedFMUstateSize"))?;
        let serialize = self.api().serialize.ok_or_else(|| missing("fmi2SerializeFMUstate"))?;
        let raw = self.states.raw(s)?;
        let mut size = 0usize;
        // SAFETY: a live instance and one of its states; the buffer holds `size` bytes.
        check(unsafe { size_of(self.c, raw, &mut size) })?;
        let mut out = vec![0u8; size];
        // SAFETY: as above; `out` holds the `size` bytes the FMU asked for.
        check(unsafe { serialize(self.c, raw, out.as_mut_ptr() as *mut fmi2Byte, size) })?;
        Ok(out)
    }

    pub fn deserialize_fmu_state(&mut self, bytes: &[u8]) -> Result<FmuState, Fmi2Error> {
        let deserialize = self
            .api()
            .deserialize
            .ok_or_else(|| missing("fmi2DeSerializeFMUstate"))?;
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: a live instance; `bytes` is readable for its length.
        check(unsafe { deserialize(self.c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut s) })?;
        self.states.keep(s)
    }
}
