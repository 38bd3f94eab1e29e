//! The binary of every container FMU: `cargo fmu container SYSTEM.ssp` copies this library,
//! renamed to the container's model identifier, into an FMU whose `resources/` hold the system
//! (`resources/system/`: SystemStructure.ssd and the component FMUs) and its
//! `resources/container.toml` ([`rustfmu_runner::container::Spec`]).
//!
//! fmi2Instantiate reads the spec (its GUID must be the importer's), loads the system with
//! rustfmu-runner ([`rustfmu_runner::Simulation::from_dir`]: every component FMU unpacked and
//! instantiated) and sets the system's parameter set. Then every FMI 2.0 co-simulation call is
//! checked against the standard's state table (the FMU runtime's, `rustfmu::core::machine`) and
//! the exposed variables' causality and variability, and forwarded:
//!
//! - fmi2Set*/fmi2Get* of an exposed variable go to its component (all or nothing: every value
//!   reference, type, bound and finite value is checked before the first is set); an output read
//!   after an input changed, or after a step, first propagates the connections (the runner's
//!   Gauss-Seidel order), so a container output equals the runner's at the same point;
//! - fmi2ExitInitializationMode propagates the connections once per component, as the runner;
//! - fmi2DoStep(t, H) makes n = ceil(H / step) internal steps of H / n (the connections
//!   propagated before each), so at the spec's step and H a multiple of it the components see
//!   the runner's calls exactly;
//! - an FMU state is every component's FMU state plus the container's time and mode;
//! - the components' log messages go to the importer's logger, "[component] message", with
//!   their status; the container's own refusals say what was wrong and where.
//!
//! No panic crosses the C boundary: each function runs under `catch_unwind` and returns
//! fmi2Fatal (logged) if anything in it panicked.
#![allow(
    non_snake_case,
    non_upper_case_globals,
    clippy::missing_safety_doc,
    clippy::result_large_err,
    // get_values and set_values take the C arguments as they come, and what to do with them.
    clippy::too_many_arguments
)]

use fmi_description::fmi2::Type;
use fmi_description::{Causality, Variability};
use rustfmu::__private::TERMS2 as TERMS;
use rustfmu::core::machine::{Call, State, contains, state_names};
use rustfmu::fmi2::abi::*;
use rustfmu_runner::container::{SPEC_FILE, SYSTEM_FOLDER, Spec};
use rustfmu_runner::fmi2::{Fmi2Error, FmuState, InstanceCS};
use rustfmu_runner::{Error, Simulation};
use std::cell::Cell;
use std::ffi::{CStr, CString, c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Where the messages of the call in progress go (the importer's logger and environment).
struct Sink {
    logger: fmi2CallbackLogger,
    environment: fmi2ComponentEnvironment,
    name: CString,
    logging_on: Cell<bool>,
}

impl Sink {
    fn log(&self, status: fmi2Status, category: &str, message: &str) {
        if let Some(f) = self.logger {
            let category = CString::new(category).unwrap_or_default();
            let message = CString::new(message.replace('\0', "?")).unwrap_or_default();
            // "%s": a message is never a format.
            unsafe {
                f(
                    self.environment,
                    self.name.as_ptr(),
                    status,
                    category.as_ptr(),
                    c"%s".as_ptr(),
                    message.as_ptr(),
                )
            };
        }
    }
}

thread_local! {
    /// The sink of the container whose call runs on this thread (null between calls).
    static CURRENT: Cell<*const Sink> = const { Cell::new(std::ptr::null()) };
}

/// The `log` crate's logger: the fmi crate hands each component's message to it (module path
/// "logger", target the component's instance name); it goes to the container's importer.
struct Forward;

impl log::Log for Forward {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }
    fn log(&self, record: &log::Record) {
        if record.module_path() != Some("logger") {
            return;
        }
        let status = match record.level() {
            log::Level::Info | log::Level::Debug => fmi2OK,
            log::Level::Warn => fmi2Warning,
            log::Level::Trace => fmi2Discard,
            log::Level::Error => fmi2Error,
        };
        CURRENT.with(|c| {
            let sink = c.get();
            if !sink.is_null() {
                let sink = unsafe { &*sink };
                sink.log(status, "logAll", &format!("[{}] {}", record.target(), record.args()));
            }
        });
    }
    fn flush(&self) {}
}

static FORWARD: Forward = Forward;

/// Sets `sink` as this thread's for the duration of a call.
struct Using;

impl Using {
    fn new(sink: &Sink) -> Using {
        static INSTALLED: std::sync::Once = std::sync::Once::new();
        INSTALLED.call_once(|| {
            if log::set_logger(&FORWARD).is_ok() {
                log::set_max_level(log::LevelFilter::Trace);
            }
        });
        CURRENT.with(|c| c.set(sink));
        Using
    }
}

impl Drop for Using {
    fn drop(&mut self) {
        CURRENT.with(|c| c.set(std::ptr::null()));
    }
}

/// An exposed variable resolved: its component (index), the component's value reference, type.
#[derive(Clone, Copy)]
struct Port {
    component: usize,
    vr: u32,
    ty: Type,
    causality: Causality,
    variability: Variability,
    min: Option<f64>,
    max: Option<f64>,
}

/// An FMU state of a container: its components' FMU states in the instance that took it
/// (`owner`) and, where every component serializes, their serialized bytes (so that another
/// instance can take it up, also after the owner was freed), with the container's time and mode.
struct Saved {
    owner: u64,
    /// Of the container whose GUID is this.
    guid: String,
    components: Vec<FmuState>,
    bytes: Option<Vec<Vec<u8>>>,
    time: f64,
    state: State,
    dirty: bool,
    last_successful: f64,
    stop_time: Option<f64>,
}

struct Container {
    /// This instance among all of the process (FMU states name their owner by it).
    id: u64,
    sink: Box<Sink>,
    spec: Spec,
    ports: Vec<Port>,
    sim: Simulation,
    state: State,
    /// The current communication point, s.
    time: f64,
    /// Something was set (or stepped) since the connections were last propagated.
    dirty: bool,
    /// stopTime of fmi2SetupExperiment, if given.
    stop_time: Option<f64>,
    /// The end of the last step completed (fmi2GetRealStatus(fmi2LastSuccessfulTime)).
    last_successful: f64,
    /// The strings fmi2GetString returned last (valid until the next call).
    strings: Vec<CString>,
    /// Component state slots of freed FMU states, reused by the next fmi2GetFMUstate.
    free: Vec<Vec<FmuState>>,
    /// Every component's state before the call in progress that moves them (a step, the
    /// initialization), restored if one of them fails: a failed call changes nothing.
    rollback: Option<Vec<FmuState>>,
}

/// The most internal steps one fmi2DoStep makes: a longer step is discarded before it begins
/// (fmi2Discard, the last successful time its start), so that a huge step cannot hang the importer.
pub const MAX_INTERNAL_STEPS: f64 = 1.0e6;

/// Every live FMU state of every container of the process (their addresses): a pointer that is
/// not one is refused, and a state may be set into another instance of the same container.
static STATES: std::sync::Mutex<Vec<usize>> = std::sync::Mutex::new(Vec::new());
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn states() -> std::sync::MutexGuard<'static, Vec<usize>> {
    STATES.lock().unwrap_or_else(|e| e.into_inner())
}

type Outcome = Result<fmi2Status, fmi2Status>;

impl Container {
    fn error(&self, message: &str) -> fmi2Status {
        self.sink.log(fmi2Error, "logStatusError", message);
        fmi2Error
    }

    fn debug(&self, message: &str) {
        if self.sink.logging_on.get() {
            self.sink.log(fmi2OK, "logAll", message);
        }
    }

    /// A component's refusal of a call that changed nothing (a setup, an FMU state): logged; the
    /// container stays where it was, unless the component answered fmi2Fatal.
    fn refused(&mut self, function: &str, e: Error) -> fmi2Status {
        let status = match e.status.as_deref() {
            Some("Discard") => fmi2Discard,
            Some("Fatal") => fmi2Fatal,
            _ => fmi2Error,
        };
        self.sink.log(
            status,
            "logStatusError",
            &format!("{function} at t = {}: {}", self.time, e.message),
        );
        if status == fmi2Fatal {
            self.state = State::Fatal;
        }
        status
    }

    /// A component's failure in a call that moves the system (initialization, a step): logged;
    /// the container's state follows the worst status (fmi2Error: Error, as some components
    /// may have moved and others not).
    fn failed(&mut self, function: &str, e: Error) -> fmi2Status {
        let status = match e.status.as_deref() {
            Some("Discard") => fmi2Discard,
            Some("Fatal") => fmi2Fatal,
            _ => fmi2Error,
        };
        self.sink.log(
            status,
            "logStatusError",
            &format!("{function} at t = {}: {}", self.time, e.message),
        );
        match status {
            fmi2Fatal => self.state = State::Fatal,
            fmi2Error => self.state = State::Error,
            _ => {}
        }
        status
    }

    /// Keeps every component's state for [`Container::restore`] (false: a component cannot
    /// get its state, so a failure cannot be undone).
    fn snapshot(&mut self) -> bool {
        if !self.all_components(|cs| cs.can_get_and_set_fmu_state) {
            return false;
        }
        let slots = self.rollback.take();
        match slots {
            Some(slots) => {
                for (i, slot) in slots.iter().enumerate() {
                    if self.sim.instance_mut(i).update_fmu_state(slot).is_err() {
                        return false;
                    }
                }
                self.rollback = Some(slots);
            }
            None => {
                let mut slots = Vec::with_capacity(self.sim.len());
                for i in 0..self.sim.len() {
                    match self.sim.instance_mut(i).get_fmu_state() {
                        Ok(s) => slots.push(s),
                        Err(_) => return false,
                    }
                }
                self.rollback = Some(slots);
            }
        }
        true
    }

    /// Every component back to the [`Container::snapshot`]; false if one refused.
    fn restore(&mut self) -> bool {
        let Some(slots) = self.rollback.take() else {
            return false;
        };
        let ok = slots
            .iter()
            .enumerate()
            .all(|(i, slot)| self.sim.instance_mut(i).set_fmu_state(slot).is_ok());
        self.rollback = Some(slots);
        ok
    }

    /// A component failed in a call that moves the system: every component back to where the
    /// call found it if they can be (the container stays in its state: fmi2Error changes
    /// nothing), else the container follows the failure's status ([`Container::failed`]).
    fn undo(&mut self, function: &str, e: Error, saved: bool) -> fmi2Status {
        if e.status.as_deref() == Some("Fatal") || !saved {
            return self.failed(function, e);
        }
        let status = self.refused(function, e);
        if self.restore() {
            self.sink.log(
                status,
                "logStatusError",
                &format!("{function}: every component was set back to its state before the call"),
            );
            status
        } else {
            self.state = State::Error;
            self.sink.log(
                fmi2Error,
                "logStatusError",
                &format!("{function}: a component could not be set back"),
            );
            fmi2Error
        }
    }

    fn check(&self, call: Call, function: &str) -> Result<(), fmi2Status> {
        if contains(call.allowed_in(), self.state) {
            return Ok(());
        }
        Err(self.error(&format!(
            "{function} is not allowed in state {}; it is allowed in: {}",
            TERMS.state_name(self.state),
            state_names(&TERMS, call.allowed_in())
        )))
    }

    fn port(&self, vr: fmi2ValueReference, ty: Type, function: &str) -> Result<Port, fmi2Status> {
        let Some(p) = self.ports.get(vr as usize) else {
            return Err(self.error(&format!(
                "{function}: value reference {vr} is not a variable of {} (0 .. {})",
                self.spec.model_identifier,
                self.ports.len().saturating_sub(1)
            )));
        };
        let same = p.ty == ty || (ty == Type::Integer && p.ty == Type::Enumeration);
        if !same {
            let e = &self.spec.variables[vr as usize];
            return Err(self.error(&format!(
                "{function}: '{}' (vr {vr}) is {}, not {}",
                e.name,
                e.ty,
                ty.name()
            )));
        }
        Ok(*p)
    }

    /// Whether the variable of `vr` may be set now (FMI 2.0, 4.2.4).
    fn settable(&self, vr: u32, p: &Port, function: &str) -> Result<(), fmi2Status> {
        let name = &self.spec.variables[vr as usize].name;
        let e = &self.spec.variables[vr as usize];
        let ok = match (self.state, p.causality) {
            // An output with a start value (initial = exact) takes one before initialization.
            (State::Instantiated | State::InitializationMode, Causality::Output) => e.start.is_some(),
            (_, Causality::Output) => false,
            (State::Instantiated | State::InitializationMode, _) => true,
            (State::StepComplete, Causality::Input) => true,
            (State::StepComplete, Causality::Parameter) => p.variability == Variability::Tunable,
            _ => false,
        };
        if ok {
            return Ok(());
        }
        Err(self.error(&format!(
            "{function}: '{name}' (vr {vr}, {} {}) cannot be set in state {}",
            p.variability.name(),
            p.causality.name(),
            TERMS.state_name(self.state)
        )))
    }

    /// Propagates the connections if anything changed since they last were (before values are
    /// read). A component that fails it leaves every component as it was (when they can get and
    /// set their state), and the container where it was.
    fn settle(&mut self, function: &str) -> Result<(), fmi2Status> {
        if self.dirty && matches!(self.state, State::InitializationMode | State::StepComplete) {
            let saved = self.snapshot();
            let t = self.time;
            if let Err(e) = self.sim.propagate(t) {
                return Err(self.undo(function, e, saved));
            }
            self.dirty = false;
        }
        Ok(())
    }

    fn component_call<T>(&mut self, function: &str, vr: u32, r: Result<T, Fmi2Error>) -> Result<T, fmi2Status> {
        r.map_err(|e| {
            let v = &self.spec.variables[vr as usize];
            let status = match e {
                Fmi2Error::Discard => fmi2Discard,
                Fmi2Error::Fatal => fmi2Fatal,
                _ => fmi2Error,
            };
            self.sink.log(
                status,
                "logStatusError",
                &format!(
                    "{function} of '{}': component '{}' refused ({e:?})",
                    v.name, v.component
                ),
            );
            if status == fmi2Fatal {
                self.state = State::Fatal;
            }
            status
        })
    }
}

fn slice<'a, T>(p: *const T, n: usize) -> &'a [T] {
    if n == 0 || p.is_null() {
        &[]
    } else {
        unsafe { std::slice::from_raw_parts(p, n) }
    }
}

fn slice_mut<'a, T>(p: *mut T, n: usize) -> &'a mut [T] {
    if n == 0 || p.is_null() {
        &mut []
    } else {
        unsafe { std::slice::from_raw_parts_mut(p, n) }
    }
}

/// Runs `f` on the container `c` with its sink set and panics caught.
fn with(c: fmi2Component, function: &str, f: impl FnOnce(&mut Container) -> Outcome) -> fmi2Status {
    if c.is_null() {
        return fmi2Error;
    }
    let container = unsafe { &mut *(c as *mut Container) };
    let sink: *const Sink = &*container.sink;
    let _using = Using::new(unsafe { &*sink });
    match catch_unwind(AssertUnwindSafe(|| f(container))) {
        Ok(Ok(s)) | Ok(Err(s)) => s,
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            let sink = unsafe { &*sink };
            sink.log(
                fmi2Fatal,
                "logStatusFatal",
                &format!("{function}: internal error (a panic: {what}); the instance can only be freed"),
            );
            container.state = State::Fatal;
            fmi2Fatal
        }
    }
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    TYPES_PLATFORM.as_ptr()
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    VERSION.as_ptr()
}

fn text(p: fmi2String) -> Option<String> {
    if p.is_null() {
        None
    } else {
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let r = catch_unwind(AssertUnwindSafe(|| {
        instantiate(
            instanceName,
            fmuType,
            fmuGUID,
            fmuResourceLocation,
            functions,
            loggingOn,
        )
    }));
    match r {
        Ok(Some(c)) => Box::into_raw(c) as fmi2Component,
        _ => std::ptr::null_mut(),
    }
}

fn instantiate(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resources: fmi2String,
    functions: *const fmi2CallbackFunctions,
    logging_on: fmi2Boolean,
) -> Option<Box<Container>> {
    if functions.is_null() {
        return None;
    }
    let functions = unsafe { *functions };
    let name = text(instance_name).unwrap_or_default();
    let sink = Box::new(Sink {
        logger: functions.logger,
        environment: functions.componentEnvironment,
        name: CString::new(name.clone()).unwrap_or_default(),
        logging_on: Cell::new(logging_on != fmi2False),
    });
    let _using = Using::new(&sink);
    let fail = |m: String| {
        sink.log(fmi2Error, "logStatusError", &format!("fmi2Instantiate: {m}"));
        None
    };
    if name.is_empty() {
        return fail("instanceName is NULL or empty".into());
    }
    if fmu_type != fmi2CoSimulation {
        return fail(format!(
            "fmuType = {fmu_type}: a container is a co-simulation FMU only (fmi2CoSimulation = 1)"
        ));
    }
    let Some(uri) = text(resources) else {
        return fail("fmuResourceLocation is NULL: the container's system is in its resources".into());
    };
    let Some(dir) = rustfmu::core::resources::resource_dir(&uri) else {
        return fail(format!("fmuResourceLocation '{uri}' is not a file: URI of a folder"));
    };
    let spec_path = dir.join(SPEC_FILE);
    let spec = match std::fs::read_to_string(&spec_path)
        .map_err(|e| format!("{}: {e}", spec_path.display()))
        .and_then(|t| Spec::from_toml(&t))
    {
        Ok(s) => s,
        Err(e) => return fail(e),
    };
    let given = text(guid).unwrap_or_default();
    if given != spec.guid {
        return fail(format!(
            "fmuGUID '{given}' is not this container's ({}): the modelDescription.xml and the resources are of different builds",
            spec.guid
        ));
    }
    let mut sim = match Simulation::from_dir(&dir.join(SYSTEM_FOLDER)) {
        Ok(s) => s,
        Err(e) => return fail(e.message),
    };
    let mut ports = Vec::with_capacity(spec.variables.len());
    {
        let descriptions = sim.component_descriptions();
        for e in &spec.variables {
            let Some(ci) = descriptions.iter().position(|(c, _)| *c == e.component) else {
                return fail(format!(
                    "{SPEC_FILE}: '{}': the system has no component '{}'",
                    e.name, e.component
                ));
            };
            let Some(v) = descriptions[ci].1.variable(&e.variable) else {
                return fail(format!(
                    "{SPEC_FILE}: '{}': component '{}' has no variable '{}'",
                    e.name, e.component, e.variable
                ));
            };
            if v.ty != e.ty() || v.causality != e.causality() {
                return fail(format!(
                    "{SPEC_FILE}: '{}' is not the component's variable of that type and causality",
                    e.name
                ));
            }
            ports.push(Port {
                component: ci,
                vr: v.vr,
                ty: v.ty,
                causality: v.causality,
                variability: v.variability,
                min: v.min,
                max: v.max,
            });
        }
    }
    if logging_on != fmi2False {
        for i in 0..sim.len() {
            let _ = sim.instance_mut(i).set_debug_logging(true, &[]);
        }
    }
    if let Err(e) = sim.apply_starts() {
        return fail(format!("the system's parameter set: {}", e.message));
    }
    drop(_using);
    let c = Box::new(Container {
        id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        sink,
        spec,
        ports,
        sim,
        state: State::Instantiated,
        time: 0.0,
        dirty: true,
        stop_time: None,
        last_successful: 0.0,
        strings: Vec::new(),
        free: Vec::new(),
        rollback: None,
    });
    c.debug(&format!(
        "instantiated: {} components, {} variables, internal step {} s",
        c.sim.len(),
        c.ports.len(),
        c.spec.step
    ));
    Some(c)
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        let container = unsafe { Box::from_raw(c as *mut Container) };
        let _using = Using::new(&container.sink);
        // Its FMU states stay valid (their bytes); the importer frees them with fmi2FreeFMUstate.
        drop(container);
    }));
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    with(c, "fmi2SetDebugLogging", |me| {
        me.check(Call::SetDebugLogging, "fmi2SetDebugLogging")?;
        if nCategories > 0 && categories.is_null() {
            return Err(me.error(&format!(
                "fmi2SetDebugLogging: {nCategories} categories in a NULL array"
            )));
        }
        let mut names = Vec::new();
        for &p in slice(categories, nCategories) {
            match text(p) {
                Some(n) if rustfmu_runner::container::LOG_CATEGORIES.iter().any(|(c, _)| *c == n) => names.push(n),
                Some(n) => {
                    let known: Vec<&str> = rustfmu_runner::container::LOG_CATEGORIES
                        .iter()
                        .map(|(c, _)| *c)
                        .collect();
                    return Err(me.error(&format!(
                        "fmi2SetDebugLogging: unknown log category '{n}' (this FMU's: {})",
                        known.join(", ")
                    )));
                }
                None => return Err(me.error("fmi2SetDebugLogging: a category is NULL")),
            }
        }
        me.sink.logging_on.set(loggingOn != fmi2False);
        for i in 0..me.sim.len() {
            let _ = me.sim.instance_mut(i).set_debug_logging(loggingOn != fmi2False, &[]);
        }
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    with(c, "fmi2SetupExperiment", |me| {
        me.check(Call::SetupExperiment, "fmi2SetupExperiment")?;
        if !startTime.is_finite() {
            return Err(me.error(&format!("fmi2SetupExperiment: startTime = {startTime}")));
        }
        let tol = (toleranceDefined != fmi2False).then_some(tolerance);
        let stop = (stopTimeDefined != fmi2False).then_some(stopTime);
        if let Some(tol) = tol
            && !(tol.is_finite() && tol > 0.0)
        {
            return Err(me.error(&format!(
                "fmi2SetupExperiment: tolerance = {tol} must be finite and > 0"
            )));
        }
        if let Some(s) = stop
            && !(s.is_finite() && s >= startTime)
        {
            return Err(me.error(&format!(
                "fmi2SetupExperiment: stopTime = {s} must be finite and not before startTime = {startTime}"
            )));
        }
        for i in 0..me.sim.len() {
            let r = me.sim.instance_mut(i).setup_experiment(tol, startTime, stop);
            if let Err(e) = r {
                let name = me.sim.component_descriptions()[i].0.to_owned();
                let e = Error::fmi(&name, "fmi2SetupExperiment", &e, None, "");
                return Err(me.refused("fmi2SetupExperiment", e));
            }
        }
        me.time = startTime;
        me.last_successful = startTime;
        me.stop_time = stop;
        Ok(fmi2OK)
    })
}

/// Calls `f` on every component, in order; the first failure stops it and is returned.
fn each_raw(
    me: &mut Container,
    function: &str,
    f: impl Fn(&mut InstanceCS) -> Result<(), Fmi2Error>,
) -> Result<(), Error> {
    for i in 0..me.sim.len() {
        if let Err(e) = f(me.sim.instance_mut(i)) {
            let name = me.sim.component_descriptions()[i].0.to_owned();
            let t = me.time;
            return Err(Error::fmi(&name, function, &e, Some(t), ""));
        }
    }
    Ok(())
}

/// Calls `f` on every component, in order; the first failure stops it.
fn each(
    me: &mut Container,
    function: &str,
    f: impl Fn(&mut InstanceCS) -> Result<(), Fmi2Error>,
) -> Result<(), fmi2Status> {
    for i in 0..me.sim.len() {
        if let Err(e) = f(me.sim.instance_mut(i)) {
            let name = me.sim.component_descriptions()[i].0.to_owned();
            let t = me.time;
            let e = Error::fmi(&name, function, &e, Some(t), "");
            return Err(me.failed(function, e));
        }
    }
    Ok(())
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2EnterInitializationMode", |me| {
        me.check(Call::EnterInitializationMode, "fmi2EnterInitializationMode")?;
        let saved = me.snapshot();
        if let Err(e) = each_raw(me, "fmi2EnterInitializationMode", |i| i.enter_initialization_mode()) {
            return Err(me.undo("fmi2EnterInitializationMode", e, saved));
        }
        me.state = State::InitializationMode;
        me.dirty = true;
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2ExitInitializationMode", |me| {
        me.check(Call::ExitInitializationMode, "fmi2ExitInitializationMode")?;
        let saved = me.snapshot();
        // As the runner: the connections once per component, then every component leaves.
        for _ in 0..me.sim.len() {
            let t = me.time;
            if let Err(e) = me.sim.propagate(t) {
                return Err(me.undo("fmi2ExitInitializationMode", e, saved));
            }
        }
        if let Err(e) = each_raw(me, "fmi2ExitInitializationMode", |i| i.exit_initialization_mode()) {
            return Err(me.undo("fmi2ExitInitializationMode", e, saved));
        }
        me.state = State::StepComplete;
        me.dirty = true;
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2Terminate", |me| {
        me.check(Call::Terminate, "fmi2Terminate")?;
        each(me, "fmi2Terminate", |i| i.terminate())?;
        me.state = State::Terminated;
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2Reset", |me| {
        me.check(Call::Reset, "fmi2Reset")?;
        each(me, "fmi2Reset", |i| i.reset())?;
        if let Err(e) = me.sim.apply_starts() {
            return Err(me.failed("fmi2Reset", e));
        }
        me.state = State::Instantiated;
        me.time = 0.0;
        me.last_successful = 0.0;
        me.stop_time = None;
        me.dirty = true;
        Ok(fmi2OK)
    })
}

/// Reads `vrs` of type `ty` into `out` (one value per value reference) with `get`.
fn get_values<T: Copy>(
    c: fmi2Component,
    function: &'static str,
    ty: Type,
    vr: *const fmi2ValueReference,
    nvr: usize,
    out: *mut T,
    get: impl Fn(&mut InstanceCS, &[u32], &mut [T]) -> Result<(), Fmi2Error>,
    check: impl Fn(&T) -> bool,
) -> fmi2Status {
    with(c, function, |me| {
        me.check(Call::GetValues, function)?;
        let vrs = slice(vr, nvr);
        if nvr > 0 && (vr.is_null() || out.is_null()) {
            return Err(me.error(&format!("{function}: {nvr} values asked with a NULL array")));
        }
        let out = slice_mut(out, nvr);
        let mut ports = Vec::with_capacity(nvr);
        for &v in vrs {
            ports.push(me.port(v, ty, function)?);
        }
        if nvr > 0 {
            me.settle(function)?;
        }
        // One call per run of variables of the same component.
        let mut i = 0;
        let mut component_vrs = Vec::with_capacity(nvr);
        while i < nvr {
            let c = ports[i].component;
            let j = i + ports[i..].iter().take_while(|p| p.component == c).count();
            component_vrs.clear();
            component_vrs.extend(ports[i..j].iter().map(|p| p.vr));
            let r = get(me.sim.instance_mut(c), &component_vrs, &mut out[i..j]);
            me.component_call(function, vrs[i], r)?;
            i = j;
        }
        for k in 0..nvr {
            if !check(&out[k]) {
                return Err(me.error(&format!(
                    "{function}: '{}' (vr {}) is not a finite number",
                    me.spec.variables[vrs[k] as usize].name, vrs[k]
                )));
            }
        }
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    get_values(
        c,
        "fmi2GetReal",
        Type::Real,
        vr,
        nvr,
        value,
        |i, v, out| i.get_real(v, out),
        |x| x.is_finite(),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    get_values(
        c,
        "fmi2GetInteger",
        Type::Integer,
        vr,
        nvr,
        value,
        |i, v, out| i.get_integer(v, out),
        |_| true,
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    get_values(
        c,
        "fmi2GetBoolean",
        Type::Boolean,
        vr,
        nvr,
        value,
        |i, v, out| i.get_boolean(v, out),
        |_| true,
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    with(c, "fmi2GetString", |me| {
        me.check(Call::GetValues, "fmi2GetString")?;
        if nvr > 0 && (vr.is_null() || value.is_null()) {
            return Err(me.error(&format!("fmi2GetString: {nvr} values asked with a NULL array")));
        }
        let vrs = slice(vr, nvr);
        let mut ports = Vec::with_capacity(nvr);
        for &v in vrs {
            ports.push(me.port(v, Type::String, "fmi2GetString")?);
        }
        if nvr > 0 {
            me.settle("fmi2GetString")?;
        }
        let mut strings = Vec::with_capacity(nvr);
        for (k, p) in ports.iter().enumerate() {
            let mut s = vec![CString::default()];
            let r = me.sim.instance_mut(p.component).get_string(&[p.vr], &mut s);
            me.component_call("fmi2GetString", vrs[k], r)?;
            strings.push(s.pop().unwrap_or_default());
        }
        me.strings = strings;
        let out = slice_mut(value, nvr);
        for (k, s) in me.strings.iter().enumerate() {
            out[k] = s.as_ptr();
        }
        Ok(fmi2OK)
    })
}

/// Sets `vrs` of type `ty`: every value reference and value checked first (all or nothing).
fn set_values<T: Copy>(
    c: fmi2Component,
    function: &'static str,
    ty: Type,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const T,
    number: impl Fn(&T) -> Option<f64>,
    set: impl Fn(&mut InstanceCS, u32, T) -> Result<(), Fmi2Error>,
) -> fmi2Status {
    with(c, function, |me| {
        let call = if ty == Type::Real {
            Call::SetValues
        } else {
            Call::SetDiscreteValues
        };
        me.check(call, function)?;
        if nvr > 0 && (vr.is_null() || value.is_null()) {
            return Err(me.error(&format!("{function}: {nvr} values given with a NULL array")));
        }
        let vrs = slice(vr, nvr);
        let values = slice(value, nvr);
        let mut ports = Vec::with_capacity(nvr);
        for (k, &v) in vrs.iter().enumerate() {
            let p = me.port(v, ty, function)?;
            me.settable(v, &p, function)?;
            if let Some(x) = number(&values[k]) {
                let name = &me.spec.variables[v as usize].name;
                if !x.is_finite() {
                    return Err(me.error(&format!(
                        "{function}: '{name}' (vr {v}) = {x}: not a finite number; nothing set"
                    )));
                }
                if p.min.is_some_and(|m| x < m) || p.max.is_some_and(|m| x > m) {
                    return Err(me.error(&format!(
                        "{function}: '{name}' (vr {v}) = {x} is outside [{}, {}]; nothing set",
                        p.min.map_or("-inf".into(), |m| m.to_string()),
                        p.max.map_or("inf".into(), |m| m.to_string())
                    )));
                }
            }
            ports.push(p);
        }
        for (k, p) in ports.iter().enumerate() {
            let r = set(me.sim.instance_mut(p.component), p.vr, values[k]);
            me.component_call(function, vrs[k], r)?;
        }
        if nvr > 0 {
            me.dirty = true;
        }
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    set_values(
        c,
        "fmi2SetReal",
        Type::Real,
        vr,
        nvr,
        value,
        |x| Some(*x),
        |i, v, x| i.set_real(&[v], &[x]).map(|_| ()),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    set_values(
        c,
        "fmi2SetInteger",
        Type::Integer,
        vr,
        nvr,
        value,
        |x| Some(f64::from(*x)),
        |i, v, x| i.set_integer(&[v], &[x]).map(|_| ()),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    set_values(
        c,
        "fmi2SetBoolean",
        Type::Boolean,
        vr,
        nvr,
        value,
        |_| None,
        |i, v, x| i.set_boolean(&[v], &[x]).map(|_| ()),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    with(c, "fmi2SetString", |me| {
        me.check(Call::SetDiscreteValues, "fmi2SetString")?;
        if nvr > 0 && (vr.is_null() || value.is_null()) {
            return Err(me.error(&format!("fmi2SetString: {nvr} values given with a NULL array")));
        }
        let vrs = slice(vr, nvr);
        let values = slice(value, nvr);
        let mut sets = Vec::with_capacity(nvr);
        for (k, &v) in vrs.iter().enumerate() {
            let p = me.port(v, Type::String, "fmi2SetString")?;
            me.settable(v, &p, "fmi2SetString")?;
            if values[k].is_null() {
                return Err(me.error(&format!(
                    "fmi2SetString: '{}' (vr {v}): the value is NULL; nothing set",
                    me.spec.variables[v as usize].name
                )));
            }
            sets.push((p, unsafe { CStr::from_ptr(values[k]) }.to_owned()));
        }
        for (k, (p, s)) in sets.iter().enumerate() {
            let r = me
                .sim
                .instance_mut(p.component)
                .set_string(&[p.vr], std::slice::from_ref(s));
            me.component_call("fmi2SetString", vrs[k], r)?;
        }
        if nvr > 0 {
            me.dirty = true;
        }
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    with(c, "fmi2DoStep", |me| {
        me.check(Call::DoStep, "fmi2DoStep")?;
        let (t, big_h) = (currentCommunicationPoint, communicationStepSize);
        if !(big_h > 0.0 && big_h.is_finite()) {
            return Err(me.error(&format!(
                "fmi2DoStep: communicationStepSize = {big_h} must be finite and > 0; time stays {}",
                me.time
            )));
        }
        // As the FMU runtime: a tolerance for importers that sum their steps.
        let tol = 1e-8 * me.time.abs().max(1.0) + 4.0 * f64::EPSILON * big_h;
        if !t.is_finite() || (t - me.time).abs() > tol {
            return Err(me.error(&format!(
                "fmi2DoStep: currentCommunicationPoint = {t} does not match the container's time {}",
                me.time
            )));
        }
        let end = t + big_h;
        if end <= t {
            return Err(me.error(&format!(
                "fmi2DoStep: communicationStepSize = {big_h} is too small to advance time from {t}"
            )));
        }
        if let Some(stop) = me.stop_time
            && end > stop + 1e-8 * stop.abs().max(big_h)
        {
            return Err(me.error(&format!(
                "fmi2DoStep: the step from {t} by {big_h} ends after stopTime = {stop} set in fmi2SetupExperiment"
            )));
        }
        let ratio = big_h / me.spec.step;
        let n = if (ratio - ratio.round()).abs() <= 1e-9 * ratio.max(1.0) {
            ratio.round().max(1.0)
        } else {
            ratio.ceil().max(1.0)
        };
        if n > MAX_INTERNAL_STEPS {
            me.state = State::StepFailed;
            me.last_successful = t;
            me.sink.log(
                fmi2Discard,
                "logStatusDiscard",
                &format!(
                    "fmi2DoStep: a step of {big_h} s from t = {t} is {n} internal steps of {} s, more than {MAX_INTERNAL_STEPS}: discarded, nothing stepped",
                    me.spec.step
                ),
            );
            return Err(fmi2Discard);
        }
        let n = n as usize;
        let h = big_h / n as f64;
        let saved = me.snapshot();
        let (time0, dirty0) = (me.time, me.dirty);
        for k in 0..n {
            let tk = t + k as f64 * h;
            me.time = tk;
            if k > 0 {
                me.dirty = true;
            }
            let r = if me.dirty {
                me.sim.propagate(tk).map(|_| me.dirty = false)
            } else {
                Ok(())
            };
            let last = k + 1 == n;
            let r = r.and_then(|_| me.sim.do_step(tk, h)).and_then(|_| {
                // The connections at the step's end, inside the step (undone with it): what the
                // runner does before it reads the outputs.
                if last {
                    me.sim.propagate(end).map(|_| me.dirty = false)
                } else {
                    Ok(())
                }
            });
            if let Err(e) = r {
                let discard = e.status.as_deref() == Some("Discard");
                let status = me.undo("fmi2DoStep", e, saved);
                if saved && me.state != State::Error && me.state != State::Fatal {
                    // Back at the step's start: nothing of it happened.
                    (me.time, me.dirty) = (time0, dirty0);
                    me.last_successful = time0;
                    if discard {
                        me.state = State::StepFailed;
                    }
                } else {
                    me.last_successful = tk;
                    if discard && me.state != State::Fatal {
                        me.state = State::StepFailed;
                    }
                }
                return Err(status);
            }
        }
        me.last_successful = end;
        me.time = end;
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2CancelStep", |me| {
        me.check(Call::CancelStep, "fmi2CancelStep")?;
        Ok(fmi2OK)
    })
}

/// The standard's answer for a status a container does not have: fmi2Discard, with the reason.
fn status_unavailable(me: &Container, function: &str, kind: fmi2StatusKind) -> Outcome {
    let what = match kind {
        fmi2DoStepStatus | fmi2PendingStatus => "there is no asynchronous step (fmi2DoStep never returns fmi2Pending)",
        fmi2LastSuccessfulTime => "fmi2LastSuccessfulTime is a Real status (fmi2GetRealStatus)",
        fmi2Terminated => "fmi2Terminated is a Boolean status (fmi2GetBooleanStatus)",
        _ => "unknown fmi2StatusKind",
    };
    me.sink.log(
        fmi2Discard,
        "logStatusDiscard",
        &format!("{function}(kind = {kind}): not available: {what}"),
    );
    Err(fmi2Discard)
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status {
    with(c, "fmi2GetStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetStatus: value is NULL"));
        }
        status_unavailable(me, "fmi2GetStatus", s)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status {
    with(c, "fmi2GetRealStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetRealStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetRealStatus: value is NULL"));
        }
        if s != fmi2LastSuccessfulTime {
            return status_unavailable(me, "fmi2GetRealStatus", s);
        }
        unsafe { *value = me.last_successful };
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    with(c, "fmi2GetIntegerStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetIntegerStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetIntegerStatus: value is NULL"));
        }
        status_unavailable(me, "fmi2GetIntegerStatus", s)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    with(c, "fmi2GetBooleanStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetBooleanStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetBooleanStatus: value is NULL"));
        }
        if s != fmi2Terminated {
            return status_unavailable(me, "fmi2GetBooleanStatus", s);
        }
        unsafe { *value = fmi2False };
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    with(c, "fmi2GetStringStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetStringStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetStringStatus: value is NULL"));
        }
        status_unavailable(me, "fmi2GetStringStatus", s)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *const fmi2Real,
) -> fmi2Status {
    with(c, "fmi2SetRealInputDerivatives", |me| {
        Err(me.error(
            "fmi2SetRealInputDerivatives: a container does not interpolate inputs (canInterpolateInputs = false)",
        ))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    with(c, "fmi2GetRealOutputDerivatives", |me| {
        Err(me.error(
            "fmi2GetRealOutputDerivatives: a container gives no output derivatives (maxOutputDerivativeOrder = 0)",
        ))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _u: *const fmi2ValueReference,
    _nu: usize,
    _z: *const fmi2ValueReference,
    _nz: usize,
    _du: *const fmi2Real,
    _dz: *mut fmi2Real,
) -> fmi2Status {
    with(c, "fmi2GetDirectionalDerivative", |me| {
        Err(me.error("fmi2GetDirectionalDerivative: a container gives no directional derivatives (providesDirectionalDerivative = false)"))
    })
}

impl Container {
    fn all_components(&self, f: fn(&fmi_description::fmi2::CoSimulation) -> bool) -> bool {
        self.sim
            .component_descriptions()
            .iter()
            .all(|(_, d)| d.cs.as_ref().is_some_and(f))
    }

    fn can_state(&self, function: &str) -> Result<(), fmi2Status> {
        if self.all_components(|cs| cs.can_get_and_set_fmu_state) {
            Ok(())
        } else {
            Err(self.error(&format!(
                "{function}: a component cannot get and set its FMU state (canGetAndSetFMUstate = false)"
            )))
        }
    }

    fn can_serialize(&self, function: &str) -> Result<(), fmi2Status> {
        self.can_state(function)?;
        if self.all_components(|cs| cs.can_serialize_fmu_state) {
            Ok(())
        } else {
            Err(self.error(&format!(
                "{function}: a component cannot serialize its FMU state (canSerializeFMUstate = false)"
            )))
        }
    }

    /// The state `state` points to, if it is a live state of this container (any instance).
    fn saved(&self, state: fmi2FMUstate, function: &str) -> Result<&'static mut Saved, fmi2Status> {
        let live = !state.is_null() && states().contains(&(state as usize));
        if !live {
            return Err(self.error(&format!(
                "{function}: {state:?} is not an FMU state of a live container (never given, or freed)"
            )));
        }
        let saved = unsafe { &mut *(state as *mut Saved) };
        if saved.guid != self.spec.guid {
            return Err(self.error(&format!(
                "{function}: the FMU state is one of the container {}, not of this one ({})",
                saved.guid, self.spec.guid
            )));
        }
        Ok(saved)
    }

    fn component_refused(&mut self, function: &str, i: usize, e: Fmi2Error) -> fmi2Status {
        let name = self.sim.component_descriptions()[i].0.to_owned();
        let t = self.time;
        let e = Error::fmi(&name, function, &e, Some(t), "");
        self.refused(function, e)
    }

    /// Every component's current FMU state, in `slots` (updated) or in new ones.
    fn take_components(&mut self, slots: Option<Vec<FmuState>>) -> Result<Vec<FmuState>, fmi2Status> {
        match slots {
            Some(slots) => {
                for (i, slot) in slots.iter().enumerate() {
                    if let Err(e) = self.sim.instance_mut(i).update_fmu_state(slot) {
                        self.free.push(slots);
                        return Err(self.component_refused("fmi2GetFMUstate", i, e));
                    }
                }
                Ok(slots)
            }
            None => {
                let mut slots = Vec::with_capacity(self.sim.len());
                for i in 0..self.sim.len() {
                    match self.sim.instance_mut(i).get_fmu_state() {
                        Ok(s) => slots.push(s),
                        Err(e) => return Err(self.component_refused("fmi2GetFMUstate", i, e)),
                    }
                }
                Ok(slots)
            }
        }
    }

    /// The serialized form of every component's state in `slots` (None where one cannot).
    fn serialize_components(&mut self, slots: &[FmuState]) -> Result<Option<Vec<Vec<u8>>>, fmi2Status> {
        if !self.all_components(|cs| cs.can_serialize_fmu_state) {
            return Ok(None);
        }
        let mut out = Vec::with_capacity(slots.len());
        for (i, slot) in slots.iter().enumerate() {
            match self.sim.instance_mut(i).serialize_fmu_state(slot) {
                Ok(b) => out.push(b),
                Err(e) => return Err(self.component_refused("fmi2GetFMUstate", i, e)),
            }
        }
        Ok(Some(out))
    }
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    with(c, "fmi2GetFMUstate", |me| {
        me.check(Call::FmuState, "fmi2GetFMUstate")?;
        me.can_state("fmi2GetFMUstate")?;
        if state.is_null() {
            return Err(me.error("fmi2GetFMUstate: the FMUstate pointer is NULL"));
        }
        let existing = unsafe { *state };
        if !existing.is_null() {
            // fmi2GetFMUstate with *FMUstate != NULL: that state is overwritten.
            let saved = me.saved(existing, "fmi2GetFMUstate")?;
            let mine = saved.owner == me.id;
            let slots = if mine {
                Some(std::mem::take(&mut saved.components))
            } else {
                me.free.pop()
            };
            let components = me.take_components(slots)?;
            let bytes = me.serialize_components(&components)?;
            saved.owner = me.id;
            saved.components = components;
            saved.bytes = bytes;
            saved.time = me.time;
            saved.state = me.state;
            saved.dirty = me.dirty;
            saved.last_successful = me.last_successful;
            saved.stop_time = me.stop_time;
            return Ok(fmi2OK);
        }
        let slots = me.free.pop();
        let components = me.take_components(slots)?;
        let bytes = me.serialize_components(&components)?;
        let p = Box::into_raw(Box::new(Saved {
            owner: me.id,
            guid: me.spec.guid.clone(),
            components,
            bytes,
            time: me.time,
            state: me.state,
            dirty: me.dirty,
            last_successful: me.last_successful,
            stop_time: me.stop_time,
        }));
        states().push(p as usize);
        unsafe { *state = p as fmi2FMUstate };
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    with(c, "fmi2SetFMUstate", |me| {
        me.check(Call::FmuState, "fmi2SetFMUstate")?;
        me.can_state("fmi2SetFMUstate")?;
        let saved = me.saved(state, "fmi2SetFMUstate")?;
        if saved.owner == me.id {
            for i in 0..me.sim.len() {
                if let Err(e) = me.sim.instance_mut(i).set_fmu_state(&saved.components[i]) {
                    return Err(me.component_refused("fmi2SetFMUstate", i, e));
                }
            }
        } else {
            // Another instance's state: taken up from its serialized form.
            let Some(bytes) = &saved.bytes else {
                return Err(me.error(
                    "fmi2SetFMUstate: the FMU state is another instance's, and a component cannot serialize its state to carry it over",
                ));
            };
            for (i, b) in bytes.iter().enumerate() {
                let r = me.sim.instance_mut(i).deserialize_fmu_state(b);
                let slot = match r {
                    Ok(slot) => slot,
                    Err(e) => return Err(me.component_refused("fmi2SetFMUstate", i, e)),
                };
                let set = me.sim.instance_mut(i).set_fmu_state(&slot);
                let _ = me.sim.instance_mut(i).free_fmu_state(slot);
                if let Err(e) = set {
                    return Err(me.component_refused("fmi2SetFMUstate", i, e));
                }
            }
        }
        me.time = saved.time;
        me.state = saved.state;
        me.dirty = saved.dirty;
        me.last_successful = saved.last_successful;
        me.stop_time = saved.stop_time;
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    with(c, "fmi2FreeFMUstate", |me| {
        me.check(Call::FmuState, "fmi2FreeFMUstate")?;
        if state.is_null() || unsafe { *state }.is_null() {
            return Ok(fmi2OK);
        }
        let p = unsafe { *state };
        let saved = me.saved(p, "fmi2FreeFMUstate")?;
        {
            let mut live = states();
            live.retain(|s| *s != p as usize);
            if live.is_empty() {
                // No heap block left behind when the library is unloaded (valgrind).
                *live = Vec::new();
            }
        }
        let saved = unsafe { Box::from_raw(saved as *mut Saved) };
        if saved.owner == me.id {
            me.free.push(saved.components);
        }
        unsafe { *state = std::ptr::null_mut() };
        Ok(fmi2OK)
    })
}

/// A serialized container state: this magic, the container's GUID, time, last successful time,
/// mode, the stop time (a flag and the value), then each component's serialized state with its length.
const MAGIC: &[u8; 8] = b"RFMUCNT2";

fn serialize(me: &Container, saved: &Saved, function: &str) -> Result<Vec<u8>, fmi2Status> {
    let Some(parts) = &saved.bytes else {
        return Err(me.error(&format!("{function}: a component cannot serialize its FMU state")));
    };
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    let guid = me.spec.guid.as_bytes();
    out.extend_from_slice(&(guid.len() as u32).to_le_bytes());
    out.extend_from_slice(guid);
    out.extend_from_slice(&saved.time.to_le_bytes());
    out.extend_from_slice(&saved.last_successful.to_le_bytes());
    out.push(saved.state as u8);
    out.push(u8::from(saved.dirty));
    out.push(u8::from(saved.stop_time.is_some()));
    out.extend_from_slice(&saved.stop_time.unwrap_or(0.0).to_le_bytes());
    out.extend_from_slice(&(parts.len() as u32).to_le_bytes());
    for part in parts {
        out.extend_from_slice(&(part.len() as u64).to_le_bytes());
        out.extend_from_slice(part);
    }
    Ok(out)
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    with(c, "fmi2SerializedFMUstateSize", |me| {
        me.check(Call::FmuState, "fmi2SerializedFMUstateSize")?;
        me.can_serialize("fmi2SerializedFMUstateSize")?;
        let saved = me.saved(state, "fmi2SerializedFMUstateSize")?;
        if size.is_null() {
            return Err(me.error("fmi2SerializedFMUstateSize: size is NULL"));
        }
        let bytes = serialize(me, saved, "fmi2SerializedFMUstateSize")?;
        unsafe { *size = bytes.len() };
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    state: fmi2FMUstate,
    bytes: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    with(c, "fmi2SerializeFMUstate", |me| {
        me.check(Call::FmuState, "fmi2SerializeFMUstate")?;
        me.can_serialize("fmi2SerializeFMUstate")?;
        let saved = me.saved(state, "fmi2SerializeFMUstate")?;
        let data = serialize(me, saved, "fmi2SerializeFMUstate")?;
        if bytes.is_null() || size < data.len() {
            return Err(me.error(&format!(
                "fmi2SerializeFMUstate: the buffer holds {size} bytes, the state needs {} (fmi2SerializedFMUstateSize)",
                data.len()
            )));
        }
        slice_mut(bytes as *mut u8, data.len()).copy_from_slice(&data);
        Ok(fmi2OK)
    })
}

/// A serialized container state read back (the components' parts not yet checked: each
/// component checks its own).
struct Parsed {
    time: f64,
    last_successful: f64,
    stop_time: Option<f64>,
    state: State,
    dirty: bool,
    parts: Vec<Vec<u8>>,
}

fn parse_state(me: &Container, data: &[u8]) -> Result<Parsed, String> {
    let mut at = 0usize;
    let mut take = |n: usize| -> Result<&[u8], String> {
        let end = at.checked_add(n).ok_or("a length past the end")?;
        let s = data
            .get(at..end)
            .ok_or_else(|| format!("the state is {} bytes long, it names {end}", data.len()))?;
        at = end;
        Ok(s)
    };
    if take(8)? != MAGIC {
        return Err("not a serialized container state (its first bytes)".into());
    }
    let n = u32::from_le_bytes(take(4)?.try_into().expect("4")) as usize;
    let guid = take(n)?;
    if guid != me.spec.guid.as_bytes() {
        return Err(format!(
            "a state of the container '{}', not of this one ({})",
            String::from_utf8_lossy(guid),
            me.spec.guid
        ));
    }
    let time = f64::from_le_bytes(take(8)?.try_into().expect("8"));
    let last_successful = f64::from_le_bytes(take(8)?.try_into().expect("8"));
    let code = take(1)?[0];
    let state = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::Terminated,
        State::Error,
    ]
    .into_iter()
    .find(|s| *s as u8 == code)
    .ok_or_else(|| format!("mode code {code} is not one of a container"))?;
    let dirty = match take(1)?[0] {
        0 => false,
        1 => true,
        x => return Err(format!("flag {x} is not 0 or 1")),
    };
    let has_stop = match take(1)?[0] {
        0 => false,
        1 => true,
        x => return Err(format!("flag {x} is not 0 or 1")),
    };
    let stop = f64::from_le_bytes(take(8)?.try_into().expect("8"));
    let stop_time = has_stop.then_some(stop);
    let count = u32::from_le_bytes(take(4)?.try_into().expect("4")) as usize;
    if count != me.sim.len() {
        return Err(format!(
            "the state has {count} components, the container {}",
            me.sim.len()
        ));
    }
    let mut parts = Vec::with_capacity(count);
    for _ in 0..count {
        let len = u64::from_le_bytes(take(8)?.try_into().expect("8"));
        let len = usize::try_from(len).map_err(|_| format!("a component's length {len}"))?;
        parts.push(take(len)?.to_vec());
    }
    if at != data.len() {
        return Err(format!("{} bytes after the state", data.len() - at));
    }
    if !time.is_finite() || !last_successful.is_finite() || !stop.is_finite() {
        return Err(format!(
            "time {time}, last successful time {last_successful}, stop time {stop}"
        ));
    }
    Ok(Parsed {
        time,
        last_successful,
        stop_time,
        state,
        dirty,
        parts,
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    with(c, "fmi2DeSerializeFMUstate", |me| {
        me.check(Call::FmuState, "fmi2DeSerializeFMUstate")?;
        me.can_serialize("fmi2DeSerializeFMUstate")?;
        if state.is_null() || (bytes.is_null() && size > 0) {
            return Err(me.error("fmi2DeSerializeFMUstate: NULL pointer"));
        }
        let data = slice(bytes as *const u8, size);
        let parsed =
            parse_state(me, data).map_err(|e| me.error(&format!("fmi2DeSerializeFMUstate: {e}; nothing changed")))?;
        let mut components = Vec::with_capacity(parsed.parts.len());
        for (i, part) in parsed.parts.iter().enumerate() {
            match me.sim.instance_mut(i).deserialize_fmu_state(part) {
                Ok(s) => components.push(s),
                Err(e) => return Err(me.component_refused("fmi2DeSerializeFMUstate", i, e)),
            }
        }
        let p = Box::into_raw(Box::new(Saved {
            owner: me.id,
            guid: me.spec.guid.clone(),
            components,
            bytes: Some(parsed.parts),
            time: parsed.time,
            state: parsed.state,
            dirty: parsed.dirty,
            last_successful: parsed.last_successful,
            stop_time: parsed.stop_time,
        }));
        states().push(p as usize);
        unsafe { *state = p as fmi2FMUstate };
        Ok(fmi2OK)
    })
}

/// Keeps `c_void` in the ABI's imports used on every platform.
#[doc(hidden)]
pub type Opaque = c_void;
