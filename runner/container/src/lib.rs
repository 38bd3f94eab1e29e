//! The binary of every container FMU: `cargo fmu container SYSTEM.ssp` copies this library,
//! renamed to the container's model identifier, into an FMU whose `resources/` hold the system
//! (`resources/system/`: SystemStructure.ssd and the component FMUs) and its
//! `resources/container.toml` ([`rustfmu_runner::container::Spec`]). One binary serves both FMI
//! versions: it exports the FMI 2.0 co-simulation functions ([`fmi2`]) and the FMI 3.0 ones
//! ([`fmi3`]); the archive's modelDescription.xml says which one an importer uses.
//!
//! Instantiation reads the spec (its GUID must be the importer's GUID or instantiation token),
//! loads the system with rustfmu-runner ([`rustfmu_runner::Simulation::from_dir`]: every
//! component FMU unpacked and instantiated) and sets the system's parameter set. Then every call
//! is checked against the standard's state table of its version (the FMU runtime's,
//! `rustfmu::core::machine`) and the exposed variables' causality and variability, and forwarded
//! by the version-neutral [`Container`] here:
//!
//! - sets and gets of an exposed variable go to its component (all or nothing: every value
//!   reference, type, bound and finite value is checked before the first is set); an output read
//!   after an input changed, or after a step, first propagates the connections (the runner's
//!   Gauss-Seidel order), so a container output equals the runner's at the same point;
//! - leaving initialization propagates the connections once per component, as the runner;
//! - a step (t, H) makes n = ceil(H / step) internal steps of H / n (the connections
//!   propagated before each), so at the spec's step and H a multiple of it the components see
//!   the runner's calls exactly;
//! - an FMU state is every component's FMU state plus the container's time and mode;
//! - the components' log messages go to the importer's logger, "[component] message", with
//!   their status; the container's own refusals say what was wrong and where.
//!
//! No panic crosses the C boundary: each function runs under `catch_unwind` and returns Fatal
//! (logged) if anything in it panicked.
#![allow(
    non_snake_case,
    non_upper_case_globals,
    clippy::missing_safety_doc,
    clippy::result_large_err,
    // get_values and set_values take the C arguments as they come, and what to do with them.
    clippy::too_many_arguments
)]

pub mod fmi2;
pub mod fmi3;

use fmi_description::fmi2::Type;
use fmi_description::{Causality, Variability};
use rustfmu::__private::{TERMS2, TERMS3};
use rustfmu::core::Terms;
use rustfmu::core::Version;
use rustfmu::core::machine::{Call, State, contains, state_names};
use rustfmu::fmi2::abi::{
    fmi2CallbackLogger, fmi2ComponentEnvironment, fmi2Discard, fmi2Error, fmi2Fatal, fmi2OK, fmi2Status, fmi2Warning,
};
use rustfmu::fmi3::abi::{fmi3InstanceEnvironment, fmi3LogMessageCallback};
use rustfmu_runner::container::{LOG_CATEGORIES, SPEC_FILE, SYSTEM_FOLDER, Spec};
use rustfmu_runner::fmi2::{Fmi2Error, FmuState, InstanceCS};
use rustfmu_runner::{Error, Simulation};
use std::cell::Cell;
use std::ffi::{CStr, CString, c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

/// A status of either version: FMI 2.0's and 3.0's codes are the same for OK, Warning, Discard,
/// Error and Fatal (0 .. 4), the only ones a container returns.
pub(crate) type Status = fmi2Status;

/// The importer's logger, as the version it speaks gave it.
enum Logger {
    V2 {
        logger: fmi2CallbackLogger,
        environment: fmi2ComponentEnvironment,
        name: CString,
    },
    V3 {
        logger: fmi3LogMessageCallback,
        environment: fmi3InstanceEnvironment,
    },
}

/// Where the messages of the call in progress go (the importer's logger and environment).
struct Sink {
    logger: Logger,
    logging_on: Cell<bool>,
}

impl Sink {
    fn log(&self, status: Status, category: &str, message: &str) {
        let category = CString::new(category).unwrap_or_default();
        let message = CString::new(message.replace('\0', "?")).unwrap_or_default();
        match &self.logger {
            Logger::V2 {
                logger: Some(f),
                environment,
                name,
            } => {
                // "%s": a message is never a format.
                unsafe {
                    f(
                        *environment,
                        name.as_ptr(),
                        status,
                        category.as_ptr(),
                        c"%s".as_ptr(),
                        message.as_ptr(),
                    )
                };
            }
            Logger::V3 {
                logger: Some(f),
                environment,
            } => unsafe { f(*environment, status, category.as_ptr(), message.as_ptr()) },
            _ => {}
        }
    }
}

thread_local! {
    /// The sink of the container whose call runs on this thread (null between calls).
    static CURRENT: Cell<*const Sink> = const { Cell::new(std::ptr::null()) };
}

/// The `log` crate's logger: the runner's importer hands each component's message to it
/// (module path "logger", target the component's instance name); it goes to the container's
/// importer.
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

/// The component index of FMI 3.0's independent variable `time` (the container's own).
const TIME: usize = usize::MAX;

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

pub(crate) struct Container {
    /// This instance among all of the process (FMU states name their owner by it).
    id: u64,
    /// The FMI version the importer speaks to this instance.
    version: Version,
    sink: Box<Sink>,
    spec: Spec,
    /// By value reference: the spec's variables, then (FMI 3.0) `time`.
    ports: Vec<Port>,
    /// By value reference: the further component inputs (component, value reference) a system
    /// input sets besides its port's (empty for most).
    also: Vec<Vec<(usize, u32)>>,
    sim: Simulation,
    state: State,
    /// The current communication point, s.
    time: f64,
    /// Something was set (or stepped) since the connections were last propagated.
    dirty: bool,
    /// The stop time the importer gave, if it gave one.
    stop_time: Option<f64>,
    /// The end of the last step completed (fmi2LastSuccessfulTime, fmi3DoStep's lastSuccessfulTime).
    last_successful: f64,
    /// The strings a string getter returned last (valid until the next call).
    strings: Vec<CString>,
    /// By value reference: the values set in Instantiated (read back there in FMI 3.0).
    held: Vec<Option<Held>>,
    /// By value reference: the strings set in Instantiated.
    held_strings: Vec<Option<CString>>,
    /// Component state slots of freed FMU states, reused by the next FMU state taken.
    free: Vec<Vec<FmuState>>,
    /// Every component's state before the call in progress that moves them (a step, the
    /// initialization), restored if one of them fails: a failed call changes nothing.
    rollback: Option<Vec<FmuState>>,
}

/// The most internal steps one step of the importer makes: a longer step is discarded before it
/// begins (Discard, the last successful time its start), so that a huge step cannot hang the
/// importer.
pub const MAX_INTERNAL_STEPS: f64 = 1.0e6;

/// Every live FMU state of every container of the process (their addresses): a pointer that is
/// not one is refused, and a state may be set into another instance of the same container.
static STATES: std::sync::Mutex<Vec<usize>> = std::sync::Mutex::new(Vec::new());
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn states() -> std::sync::MutexGuard<'static, Vec<usize>> {
    STATES.lock().unwrap_or_else(|e| e.into_inner())
}

type Outcome = Result<Status, Status>;

/// A variable's type as `version` names it.
fn type_name(version: Version, ty: Type) -> &'static str {
    match version {
        Version::Fmi2 => ty.name(),
        Version::Fmi3 => match ty {
            Type::Real => "Float64",
            Type::Integer => "Int32",
            Type::Boolean => "Boolean",
            Type::String => "String",
            Type::Enumeration => "Enumeration",
        },
    }
}

fn status_of(e: &Error) -> Status {
    match e.status.as_deref() {
        Some("Discard") => fmi2Discard,
        Some("Fatal") => fmi2Fatal,
        _ => fmi2Error,
    }
}

impl Container {
    fn terms(&self) -> &'static Terms {
        match self.version {
            Version::Fmi2 => &TERMS2,
            Version::Fmi3 => &TERMS3,
        }
    }

    fn error(&self, message: &str) -> Status {
        self.sink.log(fmi2Error, "logStatusError", message);
        fmi2Error
    }

    fn debug(&self, message: &str) {
        if self.sink.logging_on.get() {
            self.sink.log(fmi2OK, "logAll", message);
        }
    }

    /// The name of the variable of value reference `vr` (checked before).
    fn name(&self, vr: u32) -> &str {
        self.spec.variables.get(vr as usize).map_or("time", |e| e.name.as_str())
    }

    /// A component's refusal of a call that changed nothing (a setup, an FMU state): logged; the
    /// container stays where it was, unless the component answered Fatal.
    fn refused(&mut self, function: &str, e: Error) -> Status {
        let status = status_of(&e);
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
    /// the container's state follows the worst status (Error: Error, as some components may have
    /// moved and others not).
    fn failed(&mut self, function: &str, e: Error) -> Status {
        let status = status_of(&e);
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
    /// call found it if they can be (the container stays in its state: Error changes nothing),
    /// else the container follows the failure's status ([`Container::failed`]).
    fn undo(&mut self, function: &str, e: Error, saved: bool) -> Status {
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

    fn check(&self, call: Call, function: &str) -> Result<(), Status> {
        let allowed = call.allowed(self.version);
        if contains(allowed, self.state) {
            return Ok(());
        }
        Err(self.error(&format!(
            "{function} is not allowed in state {}; it is allowed in: {}",
            self.terms().state_name(self.state),
            state_names(self.terms(), allowed)
        )))
    }

    /// The variable of `vr`, checked to be of type `ty` (`asked`: the type the function reads
    /// or writes, as its version names it). FMI 2.0's Integer functions take Enumerations too.
    fn port(&self, vr: u32, ty: Type, asked: &str, function: &str) -> Result<Port, Status> {
        let Some(p) = self.ports.get(vr as usize) else {
            return Err(self.error(&format!(
                "{function}: value reference {vr} is not a variable of {} (0 .. {})",
                self.spec.model_identifier,
                self.ports.len().saturating_sub(1)
            )));
        };
        let same = p.ty == ty || (self.version == Version::Fmi2 && ty == Type::Integer && p.ty == Type::Enumeration);
        if !same {
            return Err(self.error(&format!(
                "{function}: '{}' (vr {vr}) is {}, not {asked}",
                self.name(vr),
                type_name(self.version, p.ty),
            )));
        }
        Ok(*p)
    }

    /// Whether the variable of `vr` may be set now (FMI 2.0, 4.2.4; FMI 3.0, 4.2).
    fn settable(&self, vr: u32, p: &Port, function: &str) -> Result<(), Status> {
        let name = self.name(vr);
        if p.component == TIME {
            return Err(self.error(&format!(
                "{function}: '{name}' (vr {vr}) is the independent variable: it is not set"
            )));
        }
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
            self.terms().state_name(self.state)
        )))
    }

    /// Propagates the connections if anything changed since they last were (before values are
    /// read). A component that fails it leaves every component as it was (when they can get and
    /// set their state), and the container where it was.
    fn settle(&mut self, function: &str) -> Result<(), Status> {
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

    fn component_call<T>(&mut self, function: &str, vr: u32, r: Result<T, Fmi2Error>) -> Result<T, Status> {
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

    fn all_components(&self, f: fn(&fmi_description::fmi2::CoSimulation) -> bool) -> bool {
        self.sim
            .component_descriptions()
            .iter()
            .all(|(_, d)| d.cs.as_ref().is_some_and(f))
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

fn text(p: *const c_char) -> Option<String> {
    if p.is_null() {
        None
    } else {
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }
}

/// Runs `f` on the container `c` with its sink set and panics caught.
fn with(c: *mut c_void, function: &str, f: impl FnOnce(&mut Container) -> Outcome) -> Status {
    if c.is_null() {
        return fmi2Error;
    }
    let container = unsafe { &mut *(c as *mut Container) };
    let sink: *const Sink = &*container.sink;
    let _using = Using::new(unsafe { &*sink });
    match catch_unwind(AssertUnwindSafe(|| f(container))) {
        Ok(Ok(s)) | Ok(Err(s)) => {
            // FMI 3.0, 2.3.1: "If any function called in super state FMU State Setable returns
            // fmi3Error, the FMU enters state Terminated" (fmi3Reset or fmi3SetFMUState lead
            // back), as the FMU runtime does. FMI 2.0 instances stay where they were.
            if container.version == Version::Fmi3 && s == fmi2Error && container.state != State::Fatal {
                container.state = State::Terminated;
            }
            s
        }
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

/// What an instantiation function was given, in either version.
struct Request<'a> {
    version: Version,
    function: &'a str,
    name: Option<String>,
    /// The GUID (2.0) or instantiation token (3.0).
    token: Option<String>,
    /// The resources folder (from 2.0's URI or 3.0's path), or why there is none.
    resources: Result<std::path::PathBuf, String>,
    logging_on: bool,
}

/// A new container, or None (the reason logged).
fn instantiate(sink: Box<Sink>, req: Request) -> Option<Box<Container>> {
    let function = req.function;
    let _using = Using::new(&sink);
    let fail = |m: String| {
        sink.log(fmi2Error, "logStatusError", &format!("{function}: {m}"));
        None
    };
    let name = req.name.unwrap_or_default();
    if name.is_empty() {
        return fail("instanceName is NULL or empty".into());
    }
    let dir = match req.resources {
        Ok(d) => d,
        Err(e) => return fail(e),
    };
    let spec_path = dir.join(SPEC_FILE);
    let spec = match std::fs::read_to_string(&spec_path)
        .map_err(|e| format!("{}: {e}", spec_path.display()))
        .and_then(|t| Spec::from_toml(&t))
    {
        Ok(s) => s,
        Err(e) => return fail(e),
    };
    let token = match req.version {
        Version::Fmi2 => "fmuGUID",
        Version::Fmi3 => "instantiationToken",
    };
    let given = req.token.unwrap_or_default();
    if given != spec.guid {
        return fail(format!(
            "{token} '{given}' is not this container's ({}): the modelDescription.xml and the resources are of different builds",
            spec.guid
        ));
    }
    let mut sim = match Simulation::from_dir(&dir.join(SYSTEM_FOLDER)) {
        Ok(s) => s,
        Err(e) => return fail(e.message),
    };
    let mut ports = Vec::with_capacity(spec.variables.len() + 1);
    let mut also = Vec::with_capacity(spec.variables.len() + 1);
    {
        let descriptions = sim.component_descriptions();
        for e in &spec.variables {
            // The further inputs a system input sets: the same type, the bounds of all of them.
            let (mut min, mut max) = (None::<f64>, None::<f64>);
            let mut more = Vec::new();
            for (c, name) in &e.also {
                let target = descriptions
                    .iter()
                    .position(|(n, _)| n == c)
                    .and_then(|ci| Some((ci, descriptions[ci].1.variable(name)?)));
                let Some((ci, v)) = target.filter(|(_, v)| v.ty == e.ty() && v.causality == Causality::Input) else {
                    return fail(format!(
                        "{SPEC_FILE}: '{}': '{c}.{name}' is not an input of its type in the system",
                        e.name
                    ));
                };
                min = match (min, v.min) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                };
                max = match (max, v.max) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                };
                more.push((ci, v.vr));
            }
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
                min: match (v.min, min) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                },
                max: match (v.max, max) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                },
            });
            also.push(more);
        }
    }
    if req.version == Version::Fmi3 {
        // FMI 3.0's independent variable, after the spec's (value reference: their count).
        ports.push(Port {
            component: TIME,
            vr: 0,
            ty: Type::Real,
            causality: Causality::Independent,
            variability: Variability::Continuous,
            min: None,
            max: None,
        });
        also.push(Vec::new());
    }
    if req.logging_on {
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
        version: req.version,
        sink,
        spec,
        ports,
        also,
        sim,
        state: State::Instantiated,
        time: 0.0,
        dirty: true,
        stop_time: None,
        last_successful: 0.0,
        strings: Vec::new(),
        held: Vec::new(),
        held_strings: Vec::new(),
        free: Vec::new(),
        rollback: None,
    });
    c.debug(&format!(
        "instantiated: {} components, {} variables, internal step {} s",
        c.sim.len(),
        c.spec.variables.len(),
        c.spec.step
    ));
    Some(c)
}

/// Frees a container (its FMU states stay valid through their bytes; the importer frees them).
fn free_instance(c: *mut c_void) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        let container = unsafe { Box::from_raw(c as *mut Container) };
        let _using = Using::new(&container.sink);
        drop(container);
    }));
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
) -> Result<(), Status> {
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

/// A value set before initialization (FMI 3.0 reads it back in Instantiated, where the FMI 2.0
/// components cannot be read).
#[derive(Clone, Debug)]
pub(crate) enum Held {
    Number(f64),
    Integer(i64),
    Boolean(bool),
}

/// A value of a getter's or setter's type: read from a start value of the spec, or from a value
/// set before initialization.
pub(crate) trait Scalar: Sized + Copy {
    fn from_start(text: &str) -> Option<Self>;
    fn held(self) -> Held;
    fn from_held(h: &Held) -> Option<Self>;
}

impl Scalar for f64 {
    fn from_start(text: &str) -> Option<f64> {
        text.trim().parse().ok()
    }
    fn held(self) -> Held {
        Held::Number(self)
    }
    fn from_held(h: &Held) -> Option<f64> {
        match h {
            Held::Number(x) => Some(*x),
            _ => None,
        }
    }
}
impl Scalar for i32 {
    fn from_start(text: &str) -> Option<i32> {
        text.trim().parse().ok()
    }
    fn held(self) -> Held {
        Held::Integer(i64::from(self))
    }
    fn from_held(h: &Held) -> Option<i32> {
        match h {
            Held::Integer(x) => i32::try_from(*x).ok(),
            _ => None,
        }
    }
}
impl Scalar for i64 {
    fn from_start(text: &str) -> Option<i64> {
        text.trim().parse().ok()
    }
    fn held(self) -> Held {
        Held::Integer(self)
    }
    fn from_held(h: &Held) -> Option<i64> {
        match h {
            Held::Integer(x) => Some(*x),
            _ => None,
        }
    }
}
impl Scalar for bool {
    fn from_start(text: &str) -> Option<bool> {
        match text.trim() {
            "true" | "1" => Some(true),
            "false" | "0" => Some(false),
            _ => None,
        }
    }
    fn held(self) -> Held {
        Held::Boolean(self)
    }
    fn from_held(h: &Held) -> Option<bool> {
        match h {
            Held::Boolean(x) => Some(*x),
            _ => None,
        }
    }
}

impl Container {
    fn set_debug_logging(&mut self, function: &str, on: bool, categories: &[*const c_char]) -> Outcome {
        self.check(Call::SetDebugLogging, function)?;
        for &p in categories {
            match text(p) {
                Some(n) if LOG_CATEGORIES.iter().any(|(c, _)| *c == n) => {}
                Some(n) => {
                    let known: Vec<&str> = LOG_CATEGORIES.iter().map(|(c, _)| *c).collect();
                    return Err(self.error(&format!(
                        "{function}: unknown log category '{n}' (this FMU's: {})",
                        known.join(", ")
                    )));
                }
                None => return Err(self.error(&format!("{function}: a category is NULL"))),
            }
        }
        self.sink.logging_on.set(on);
        for i in 0..self.sim.len() {
            let _ = self.sim.instance_mut(i).set_debug_logging(on, &[]);
        }
        Ok(fmi2OK)
    }

    /// The experiment's tolerance, start and stop time, checked and handed to every component
    /// (fmi2SetupExperiment; the first half of fmi3EnterInitializationMode).
    fn setup(&mut self, function: &str, tol: Option<f64>, start: f64, stop: Option<f64>) -> Result<(), Status> {
        if !start.is_finite() {
            return Err(self.error(&format!("{function}: startTime = {start}")));
        }
        if let Some(tol) = tol
            && !(tol.is_finite() && tol > 0.0)
        {
            return Err(self.error(&format!("{function}: tolerance = {tol} must be finite and > 0")));
        }
        if let Some(s) = stop
            && !(s.is_finite() && s >= start)
        {
            return Err(self.error(&format!(
                "{function}: stopTime = {s} must be finite and not before startTime = {start}"
            )));
        }
        for i in 0..self.sim.len() {
            let r = self.sim.instance_mut(i).setup_experiment(tol, start, stop);
            if let Err(e) = r {
                let name = self.sim.component_descriptions()[i].0.to_owned();
                let e = Error::fmi(&name, "fmi2SetupExperiment", &e, None, "");
                return Err(self.refused(function, e));
            }
        }
        self.time = start;
        self.last_successful = start;
        self.stop_time = stop;
        Ok(())
    }

    fn enter_initialization_mode(&mut self, function: &str) -> Outcome {
        let saved = self.snapshot();
        if let Err(e) = each_raw(self, "fmi2EnterInitializationMode", |i| i.enter_initialization_mode()) {
            return Err(self.undo(function, e, saved));
        }
        self.state = State::InitializationMode;
        self.dirty = true;
        Ok(fmi2OK)
    }

    fn exit_initialization_mode(&mut self, function: &str) -> Outcome {
        self.check(Call::ExitInitializationMode, function)?;
        let saved = self.snapshot();
        // As the runner: the connections once per component, then every component leaves.
        for _ in 0..self.sim.len() {
            let t = self.time;
            if let Err(e) = self.sim.propagate(t) {
                return Err(self.undo(function, e, saved));
            }
        }
        if let Err(e) = each_raw(self, "fmi2ExitInitializationMode", |i| i.exit_initialization_mode()) {
            return Err(self.undo(function, e, saved));
        }
        self.state = State::StepComplete;
        self.dirty = true;
        Ok(fmi2OK)
    }

    fn terminate(&mut self, function: &str) -> Outcome {
        self.check(Call::Terminate, function)?;
        each(self, "fmi2Terminate", |i| i.terminate())?;
        self.state = State::Terminated;
        Ok(fmi2OK)
    }

    fn reset(&mut self, function: &str) -> Outcome {
        self.check(Call::Reset, function)?;
        each(self, "fmi2Reset", |i| i.reset())?;
        if let Err(e) = self.sim.apply_starts() {
            return Err(self.failed(function, e));
        }
        self.state = State::Instantiated;
        self.time = 0.0;
        self.last_successful = 0.0;
        self.stop_time = None;
        self.dirty = true;
        self.held.clear();
        self.held_strings.clear();
        Ok(fmi2OK)
    }

    /// Keeps a value set in Instantiated, to be read back there.
    fn hold(&mut self, vr: u32, h: Held) {
        let n = self.ports.len();
        self.held.resize(n, None);
        self.held[vr as usize] = Some(h);
    }

    /// The ports of `vrs`, each checked to be of type `ty`.
    fn ports_of(&self, vrs: &[u32], ty: Type, asked: &str, function: &str) -> Result<Vec<Port>, Status> {
        vrs.iter().map(|&v| self.port(v, ty, asked, function)).collect()
    }

    /// A value before initialization (FMI 3.0 getters in Instantiated): the one set since
    /// instantiation (or reset), else the spec's start value.
    fn start_of<T: Scalar>(&self, vr: u32, p: &Port, function: &str) -> Result<T, Status> {
        if let Some(Some(h)) = self.held.get(vr as usize)
            && let Some(x) = T::from_held(h)
        {
            return Ok(x);
        }
        let e = (p.component != TIME).then(|| &self.spec.variables[vr as usize]);
        match e.and_then(|e| e.start.as_deref()).and_then(T::from_start) {
            Some(x) => Ok(x),
            None => Err(self.error(&format!(
                "{function}: '{}' (vr {vr}) has no start value: it is known after initialization begins",
                self.name(vr)
            ))),
        }
    }

    /// Reads `vrs` of type `ty` into `out` (one value per value reference) with `get`; `time`
    /// gives the independent variable's value in the getter's type (FMI 3.0 Float64 only).
    fn get_values<T: Scalar>(
        &mut self,
        function: &str,
        ty: Type,
        asked: &str,
        vrs: &[u32],
        out: &mut [T],
        get: impl Fn(&mut InstanceCS, &[u32], &mut [T]) -> Result<(), Fmi2Error>,
        finite: impl Fn(&T) -> bool,
        time: impl Fn(f64) -> Option<T>,
    ) -> Outcome {
        self.check(Call::GetValues, function)?;
        let ports = self.ports_of(vrs, ty, asked, function)?;
        let nvr = vrs.len();
        if self.state == State::Instantiated {
            // FMI 3.0 only (2.0's table refuses it): the start values.
            for k in 0..nvr {
                out[k] = match (ports[k].component, time(self.time)) {
                    (TIME, Some(t)) => t,
                    _ => self.start_of(vrs[k], &ports[k], function)?,
                };
            }
            return Ok(fmi2OK);
        }
        if nvr > 0 {
            self.settle(function)?;
        }
        // One call per run of variables of the same component.
        let mut i = 0;
        let mut component_vrs = Vec::with_capacity(nvr);
        while i < nvr {
            let c = ports[i].component;
            let j = i + ports[i..].iter().take_while(|p| p.component == c).count();
            if c == TIME {
                let t = time(self.time).expect("time is Float64");
                out[i..j].fill(t);
                i = j;
                continue;
            }
            component_vrs.clear();
            component_vrs.extend(ports[i..j].iter().map(|p| p.vr));
            let r = get(self.sim.instance_mut(c), &component_vrs, &mut out[i..j]);
            self.component_call(function, vrs[i], r)?;
            i = j;
        }
        for k in 0..nvr {
            if !finite(&out[k]) {
                return Err(self.error(&format!(
                    "{function}: '{}' (vr {}) is not a finite number",
                    self.name(vrs[k]),
                    vrs[k]
                )));
            }
        }
        Ok(fmi2OK)
    }

    /// Reads the String variables `vrs` into `self.strings`.
    fn get_strings(&mut self, function: &str, vrs: &[u32]) -> Outcome {
        self.check(Call::GetValues, function)?;
        let ports = self.ports_of(vrs, Type::String, "String", function)?;
        let mut strings = Vec::with_capacity(vrs.len());
        if self.state == State::Instantiated {
            for &vr in vrs {
                if let Some(Some(s)) = self.held_strings.get(vr as usize) {
                    strings.push(s.clone());
                    continue;
                }
                match self.spec.variables[vr as usize].start.as_deref() {
                    Some(s) => strings.push(CString::new(s).unwrap_or_default()),
                    None => {
                        return Err(self.error(&format!(
                            "{function}: '{}' (vr {vr}) has no start value: it is known after initialization begins",
                            self.name(vr)
                        )));
                    }
                }
            }
            self.strings = strings;
            return Ok(fmi2OK);
        }
        if !vrs.is_empty() {
            self.settle(function)?;
        }
        for (k, p) in ports.iter().enumerate() {
            let mut s = vec![CString::default()];
            let r = self.sim.instance_mut(p.component).get_string(&[p.vr], &mut s);
            self.component_call(function, vrs[k], r)?;
            strings.push(s.pop().unwrap_or_default());
        }
        self.strings = strings;
        Ok(fmi2OK)
    }

    /// Sets `vrs` of type `ty`: every value reference and value checked first (all or nothing).
    fn set_values<T: Scalar>(
        &mut self,
        function: &str,
        ty: Type,
        asked: &str,
        vrs: &[u32],
        values: &[T],
        number: impl Fn(&T) -> Option<f64>,
        set: impl Fn(&mut InstanceCS, u32, T) -> Result<(), Fmi2Error>,
    ) -> Outcome {
        let call = if ty == Type::Real {
            Call::SetValues
        } else {
            Call::SetDiscreteValues
        };
        self.check(call, function)?;
        let mut ports = Vec::with_capacity(vrs.len());
        for (k, &v) in vrs.iter().enumerate() {
            let p = self.port(v, ty, asked, function)?;
            self.settable(v, &p, function)?;
            if let Some(x) = number(&values[k]) {
                let name = self.name(v);
                if !x.is_finite() {
                    return Err(self.error(&format!(
                        "{function}: '{name}' (vr {v}) = {x}: not a finite number; nothing set"
                    )));
                }
                if p.min.is_some_and(|m| x < m) || p.max.is_some_and(|m| x > m) {
                    return Err(self.error(&format!(
                        "{function}: '{name}' (vr {v}) = {x} is outside [{}, {}]; nothing set",
                        p.min.map_or("-inf".into(), |m| m.to_string()),
                        p.max.map_or("inf".into(), |m| m.to_string())
                    )));
                }
            }
            ports.push(p);
        }
        for (k, p) in ports.iter().enumerate() {
            let r = set(self.sim.instance_mut(p.component), p.vr, values[k]);
            self.component_call(function, vrs[k], r)?;
            for i in 0..self.also[vrs[k] as usize].len() {
                let (c, vr) = self.also[vrs[k] as usize][i];
                let r = set(self.sim.instance_mut(c), vr, values[k]);
                self.component_call(function, vrs[k], r)?;
            }
            if self.state == State::Instantiated {
                self.hold(vrs[k], values[k].held());
            }
        }
        if !vrs.is_empty() {
            self.dirty = true;
        }
        Ok(fmi2OK)
    }

    /// Sets the String variables `vrs` (all or nothing).
    fn set_strings(&mut self, function: &str, vrs: &[u32], values: &[*const c_char]) -> Outcome {
        self.check(Call::SetDiscreteValues, function)?;
        let mut sets = Vec::with_capacity(vrs.len());
        for (k, &v) in vrs.iter().enumerate() {
            let p = self.port(v, Type::String, "String", function)?;
            self.settable(v, &p, function)?;
            if values[k].is_null() {
                return Err(self.error(&format!(
                    "{function}: '{}' (vr {v}): the value is NULL; nothing set",
                    self.name(v)
                )));
            }
            sets.push((p, unsafe { CStr::from_ptr(values[k]) }.to_owned()));
        }
        for (k, (p, s)) in sets.iter().enumerate() {
            let r = self
                .sim
                .instance_mut(p.component)
                .set_string(&[p.vr], std::slice::from_ref(s));
            self.component_call(function, vrs[k], r)?;
            for i in 0..self.also[vrs[k] as usize].len() {
                let (c, vr) = self.also[vrs[k] as usize][i];
                let r = self.sim.instance_mut(c).set_string(&[vr], std::slice::from_ref(s));
                self.component_call(function, vrs[k], r)?;
            }
            if self.state == State::Instantiated {
                let n = self.ports.len();
                self.held_strings.resize(n, None);
                self.held_strings[vrs[k] as usize] = Some(s.clone());
            }
        }
        if !vrs.is_empty() {
            self.dirty = true;
        }
        Ok(fmi2OK)
    }

    /// A communication step from `t` by `big_h`: n internal steps of the components.
    fn do_step(&mut self, function: &str, t: f64, big_h: f64) -> Outcome {
        self.check(Call::DoStep, function)?;
        if !(big_h > 0.0 && big_h.is_finite()) {
            return Err(self.error(&format!(
                "{function}: communicationStepSize = {big_h} must be finite and > 0; time stays {}",
                self.time
            )));
        }
        // As the FMU runtime: a tolerance for importers that sum their steps.
        let tol = 1e-8 * self.time.abs().max(1.0) + 4.0 * f64::EPSILON * big_h;
        if !t.is_finite() || (t - self.time).abs() > tol {
            return Err(self.error(&format!(
                "{function}: currentCommunicationPoint = {t} does not match the container's time {}",
                self.time
            )));
        }
        let end = t + big_h;
        if end <= t {
            return Err(self.error(&format!(
                "{function}: communicationStepSize = {big_h} is too small to advance time from {t}"
            )));
        }
        if let Some(stop) = self.stop_time
            && end > stop + 1e-8 * stop.abs().max(big_h)
        {
            let given = match self.version {
                Version::Fmi2 => "fmi2SetupExperiment",
                Version::Fmi3 => "fmi3EnterInitializationMode",
            };
            return Err(self.error(&format!(
                "{function}: the step from {t} by {big_h} ends after stopTime = {stop} set in {given}"
            )));
        }
        let ratio = big_h / self.spec.step;
        let n = if (ratio - ratio.round()).abs() <= 1e-9 * ratio.max(1.0) {
            ratio.round().max(1.0)
        } else {
            ratio.ceil().max(1.0)
        };
        if n > MAX_INTERNAL_STEPS {
            self.state = State::StepFailed;
            self.last_successful = t;
            self.sink.log(
                fmi2Discard,
                "logStatusDiscard",
                &format!(
                    "{function}: a step of {big_h} s from t = {t} is {n} internal steps of {} s, more than {MAX_INTERNAL_STEPS}: discarded, nothing stepped",
                    self.spec.step
                ),
            );
            return Err(fmi2Discard);
        }
        let n = n as usize;
        let h = big_h / n as f64;
        if !(t + h > t && end - h < end) {
            // Far from 0 the internal step is below the resolution of time: a component would
            // be asked to step without its time moving. Nothing has moved yet.
            self.state = State::StepFailed;
            self.last_successful = t;
            self.sink.log(
                fmi2Discard,
                "logStatusDiscard",
                &format!(
                    "{function}: a step of {big_h} s from t = {t} is {n} internal steps of {h} s, too small to advance time there: discarded, nothing stepped (a longer communication step, or a container of a longer internal step)"
                ),
            );
            return Err(fmi2Discard);
        }
        let saved = self.snapshot();
        let (time0, dirty0) = (self.time, self.dirty);
        for k in 0..n {
            let tk = t + k as f64 * h;
            self.time = tk;
            if k > 0 {
                self.dirty = true;
            }
            let r = if self.dirty {
                self.sim.propagate(tk).map(|_| self.dirty = false)
            } else {
                Ok(())
            };
            let last = k + 1 == n;
            let r = r.and_then(|_| self.sim.do_step_with(tk, h, false)).and_then(|_| {
                // The connections at the step's end, inside the step (undone with it): what the
                // runner does before it reads the outputs.
                if last {
                    self.sim.propagate(end).map(|_| self.dirty = false)
                } else {
                    Ok(())
                }
            });
            if let Err(e) = r {
                let discard = e.status.as_deref() == Some("Discard");
                let status = self.undo(function, e, saved);
                if saved && self.state != State::Error && self.state != State::Fatal {
                    // Back at the step's start: nothing of it happened.
                    (self.time, self.dirty) = (time0, dirty0);
                    self.last_successful = time0;
                    if discard {
                        self.state = State::StepFailed;
                    }
                } else {
                    self.last_successful = tk;
                    if discard && self.state != State::Fatal {
                        self.state = State::StepFailed;
                    }
                }
                return Err(status);
            }
        }
        self.last_successful = end;
        self.time = end;
        Ok(fmi2OK)
    }
}

// FMU states (the same in both versions: FMI 3.0 renamed FMUstate to FMUState).
impl Container {
    fn can_state(&self, function: &str) -> Result<(), Status> {
        if self.all_components(|cs| cs.can_get_and_set_fmu_state) {
            Ok(())
        } else {
            Err(self.error(&format!(
                "{function}: a component cannot get and set its FMU state (canGetAndSetFMUstate = false)"
            )))
        }
    }

    fn can_serialize(&self, function: &str) -> Result<(), Status> {
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
    fn saved(&self, state: *mut c_void, function: &str) -> Result<&'static mut Saved, Status> {
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

    fn component_refused(&mut self, function: &str, i: usize, e: Fmi2Error) -> Status {
        let name = self.sim.component_descriptions()[i].0.to_owned();
        let t = self.time;
        let e = Error::fmi(&name, function, &e, Some(t), "");
        self.refused(function, e)
    }

    /// Every component's current FMU state, in `slots` (updated) or in new ones.
    fn take_components(&mut self, function: &str, slots: Option<Vec<FmuState>>) -> Result<Vec<FmuState>, Status> {
        match slots {
            Some(slots) => {
                for (i, slot) in slots.iter().enumerate() {
                    if let Err(e) = self.sim.instance_mut(i).update_fmu_state(slot) {
                        self.free.push(slots);
                        return Err(self.component_refused(function, i, e));
                    }
                }
                Ok(slots)
            }
            None => {
                let mut slots = Vec::with_capacity(self.sim.len());
                for i in 0..self.sim.len() {
                    match self.sim.instance_mut(i).get_fmu_state() {
                        Ok(s) => slots.push(s),
                        Err(e) => return Err(self.component_refused(function, i, e)),
                    }
                }
                Ok(slots)
            }
        }
    }

    /// The serialized form of every component's state in `slots` (None where one cannot).
    fn serialize_components(&mut self, function: &str, slots: &[FmuState]) -> Result<Option<Vec<Vec<u8>>>, Status> {
        if !self.all_components(|cs| cs.can_serialize_fmu_state) {
            return Ok(None);
        }
        let mut out = Vec::with_capacity(slots.len());
        for (i, slot) in slots.iter().enumerate() {
            match self.sim.instance_mut(i).serialize_fmu_state(slot) {
                Ok(b) => out.push(b),
                Err(e) => return Err(self.component_refused(function, i, e)),
            }
        }
        Ok(Some(out))
    }

    fn get_fmu_state(&mut self, function: &str, state: *mut *mut c_void) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_state(function)?;
        if state.is_null() {
            return Err(self.error(&format!("{function}: the FMU state pointer is NULL")));
        }
        let existing = unsafe { *state };
        if !existing.is_null() {
            // With *FMUstate != NULL: that state is overwritten.
            let saved = self.saved(existing, function)?;
            let mine = saved.owner == self.id;
            let slots = if mine {
                Some(std::mem::take(&mut saved.components))
            } else {
                self.free.pop()
            };
            let components = self.take_components(function, slots)?;
            let bytes = self.serialize_components(function, &components)?;
            saved.owner = self.id;
            saved.components = components;
            saved.bytes = bytes;
            saved.time = self.time;
            saved.state = self.state;
            saved.dirty = self.dirty;
            saved.last_successful = self.last_successful;
            saved.stop_time = self.stop_time;
            return Ok(fmi2OK);
        }
        let slots = self.free.pop();
        let components = self.take_components(function, slots)?;
        let bytes = self.serialize_components(function, &components)?;
        let p = Box::into_raw(Box::new(Saved {
            owner: self.id,
            guid: self.spec.guid.clone(),
            components,
            bytes,
            time: self.time,
            state: self.state,
            dirty: self.dirty,
            last_successful: self.last_successful,
            stop_time: self.stop_time,
        }));
        states().push(p as usize);
        unsafe { *state = p as *mut c_void };
        Ok(fmi2OK)
    }

    fn set_fmu_state(&mut self, function: &str, state: *mut c_void) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_state(function)?;
        let saved = self.saved(state, function)?;
        if saved.owner == self.id {
            for i in 0..self.sim.len() {
                if let Err(e) = self.sim.instance_mut(i).set_fmu_state(&saved.components[i]) {
                    return Err(self.component_refused(function, i, e));
                }
            }
        } else {
            // Another instance's state: taken up from its serialized form.
            let Some(bytes) = &saved.bytes else {
                return Err(self.error(&format!(
                    "{function}: the FMU state is another instance's, and a component cannot serialize its state to carry it over"
                )));
            };
            for (i, b) in bytes.iter().enumerate() {
                let r = self.sim.instance_mut(i).deserialize_fmu_state(b);
                let slot = match r {
                    Ok(slot) => slot,
                    Err(e) => return Err(self.component_refused(function, i, e)),
                };
                let set = self.sim.instance_mut(i).set_fmu_state(&slot);
                let _ = self.sim.instance_mut(i).free_fmu_state(slot);
                if let Err(e) = set {
                    return Err(self.component_refused(function, i, e));
                }
            }
        }
        self.time = saved.time;
        self.state = saved.state;
        self.dirty = saved.dirty;
        self.last_successful = saved.last_successful;
        self.stop_time = saved.stop_time;
        Ok(fmi2OK)
    }

    fn free_fmu_state(&mut self, function: &str, state: *mut *mut c_void) -> Outcome {
        self.check(Call::FmuState, function)?;
        if state.is_null() || unsafe { *state }.is_null() {
            return Ok(fmi2OK);
        }
        let p = unsafe { *state };
        let saved = self.saved(p, function)?;
        {
            let mut live = states();
            live.retain(|s| *s != p as usize);
            if live.is_empty() {
                // No heap block left behind when the library is unloaded (valgrind).
                *live = Vec::new();
            }
        }
        let saved = unsafe { Box::from_raw(saved as *mut Saved) };
        if saved.owner == self.id {
            self.free.push(saved.components);
        }
        unsafe { *state = std::ptr::null_mut() };
        Ok(fmi2OK)
    }

    fn serialized_size(&mut self, function: &str, state: *mut c_void, size: *mut usize) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_serialize(function)?;
        let saved = self.saved(state, function)?;
        if size.is_null() {
            return Err(self.error(&format!("{function}: size is NULL")));
        }
        let bytes = serialize(self, saved, function)?;
        unsafe { *size = bytes.len() };
        Ok(fmi2OK)
    }

    fn serialize_state(&mut self, function: &str, state: *mut c_void, bytes: *mut u8, size: usize) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_serialize(function)?;
        let saved = self.saved(state, function)?;
        let data = serialize(self, saved, function)?;
        if bytes.is_null() || size < data.len() {
            return Err(self.error(&format!(
                "{function}: the buffer holds {size} bytes, the state needs {} (the serialized size)",
                data.len()
            )));
        }
        slice_mut(bytes, data.len()).copy_from_slice(&data);
        Ok(fmi2OK)
    }

    fn deserialize_state(&mut self, function: &str, bytes: *const u8, size: usize, state: *mut *mut c_void) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_serialize(function)?;
        if state.is_null() || (bytes.is_null() && size > 0) {
            return Err(self.error(&format!("{function}: NULL pointer")));
        }
        let data = slice(bytes, size);
        let parsed = parse_state(self, data).map_err(|e| self.error(&format!("{function}: {e}; nothing changed")))?;
        let mut components = Vec::with_capacity(parsed.parts.len());
        for (i, part) in parsed.parts.iter().enumerate() {
            match self.sim.instance_mut(i).deserialize_fmu_state(part) {
                Ok(s) => components.push(s),
                Err(e) => return Err(self.component_refused(function, i, e)),
            }
        }
        let p = Box::into_raw(Box::new(Saved {
            owner: self.id,
            guid: self.spec.guid.clone(),
            components,
            bytes: Some(parsed.parts),
            time: parsed.time,
            state: parsed.state,
            dirty: parsed.dirty,
            last_successful: parsed.last_successful,
            stop_time: parsed.stop_time,
        }));
        states().push(p as usize);
        unsafe { *state = p as *mut c_void };
        Ok(fmi2OK)
    }
}

/// A serialized container state: this magic, the container's GUID, time, last successful time,
/// mode, the stop time (a flag and the value), then each component's serialized state with its length.
const MAGIC: &[u8; 8] = b"RFMUCNT2";

fn serialize(me: &Container, saved: &Saved, function: &str) -> Result<Vec<u8>, Status> {
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

/// The resources folder of a `file:` URI (FMI 2.0's fmuResourceLocation).
fn resources_of_uri(uri: Option<String>) -> Result<std::path::PathBuf, String> {
    let Some(uri) = uri else {
        return Err("fmuResourceLocation is NULL: the container's system is in its resources".into());
    };
    rustfmu::core::resources::resource_dir(&uri)
        .ok_or_else(|| format!("fmuResourceLocation '{uri}' is not a file: URI of a folder"))
}

/// The resources folder of FMI 3.0's resourcePath (a native absolute path).
fn resources_of_path(path: Option<String>) -> Result<std::path::PathBuf, String> {
    let Some(path) = path else {
        return Err("resourcePath is NULL: the container's system is in its resources".into());
    };
    let p = Path::new(&path);
    if p.is_absolute() {
        Ok(p.to_path_buf())
    } else {
        Err(format!("resourcePath '{path}' is not an absolute path"))
    }
}

/// Keeps `c_void` in the ABI's imports used on every platform.
#[doc(hidden)]
pub type Opaque = c_void;
