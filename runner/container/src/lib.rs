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

mod export;
pub mod fmi2;
pub mod fmi3;
mod instantiate;
mod state;
mod values;

use instantiate::{Request, each, each_raw, free_instance, instantiate, resources_of_path, resources_of_uri};
use values::{Held, Scalar};

use md_reader::fmi2::Type;
use md_reader::{Causality, Variability};
use rustfmu::__private::{TERMS2, TERMS3};
use rustfmu::core::Terms;
use rustfmu::core::Version;
use rustfmu::core::machine::{Call, State, contains, state_names};
use rustfmu::fmi2::abi::{
    fmi2CallbackLogger, fmi2ComponentEnvironment, fmi2Discard, fmi2Error, fmi2Fatal, fmi2OK, fmi2Status, fmi2Warning,
};
use rustfmu::fmi3::abi::{fmi3InstanceEnvironment, fmi3LogMessageCallback};
use rustfmu_runner::common::{Fmi2Error, FmuState};
use rustfmu_runner::container::{LOG_CATEGORIES, SPEC_FILE, SYSTEM_FOLDER, Spec};
use rustfmu_runner::fmu_log;
use rustfmu_runner::instance::InstanceCS;
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
                // SAFETY: the importer's logger with its own environment, given at instantiation
                // (FMI 2.0, 2.1.5); every string is NUL-terminated and lives through the call.
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
            } => {
                // SAFETY: the importer's logger with its own environment, given at
                // instantiation (FMI 3.0, 2.3.1); the strings are NUL-terminated.
                unsafe { f(*environment, status, category.as_ptr(), message.as_ptr()) }
            }
            _ => {}
        }
    }
}

thread_local! {
    /// The sink of the container whose call runs on this thread (null between calls).
    static CURRENT: Cell<*const Sink> = const { Cell::new(std::ptr::null()) };
}

/// A component's message, as the runner's importer hands it to the `log` crate's logger (its
/// instance name and status), goes to the container's importer.
fn forward(instance: &str, status: fmu_log::Status, message: &std::fmt::Arguments) {
    let status = match status {
        fmu_log::Status::Ok => fmi2OK,
        fmu_log::Status::Warning => fmi2Warning,
        fmu_log::Status::Discard => fmi2Discard,
        fmu_log::Status::Error => fmi2Error,
    };
    CURRENT.with(|c| {
        let sink = c.get();
        if !sink.is_null() {
            // SAFETY: CURRENT holds a sink only while a `Using` of it lives (a call of the
            // container's, on this thread), and the sink outlives the call.
            let sink = unsafe { &*sink };
            sink.log(status, "logAll", &format!("[{instance}] {message}"));
        }
    });
}

static FORWARD: fmu_log::FmuMessages = fmu_log::FmuMessages(forward);

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

    /// A component's failure `e` in `function`, logged at the time of the container: its status.
    fn log_failure(&self, function: &str, e: &Error) -> Status {
        let status = status_of(e);
        self.sink.log(
            status,
            "logStatusError",
            &format!("{function} at t = {}: {}", self.time, e.message),
        );
        status
    }

    /// A component's refusal of a call that changed nothing (a setup, an FMU state): logged; the
    /// container stays where it was, unless the component answered Fatal.
    fn refused(&mut self, function: &str, e: Error) -> Status {
        let status = self.log_failure(function, &e);
        if status == fmi2Fatal {
            self.state = State::Fatal;
        }
        status
    }

    /// A component's failure in a call that moves the system (initialization, a step): logged;
    /// the container's state follows the worst status (Error: Error, as some components may have
    /// moved and others not).
    fn failed(&mut self, function: &str, e: Error) -> Status {
        let status = self.log_failure(function, &e);
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
        // A system that steps to its clocks' ticks: the components' states alone would not take
        // the clocks back (`Container::can_state`).
        if self.sim.steps_to_clock_ticks() || !self.all_components(|cs| cs.can_get_and_set_fmu_state) {
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

    fn all_components(&self, f: fn(&md_reader::fmi2::CoSimulation) -> bool) -> bool {
        self.sim
            .component_descriptions()
            .iter()
            .all(|(_, d)| d.cs.as_ref().is_some_and(f))
    }
}

// The C boundary: each raw pointer an importer passes is converted here, once. Every exported
// function is called by an importer that keeps the standard's promises about its arguments (FMI
// 2.0, 2.1.3; FMI 3.0, 2.2.2): an array is valid for the count passed with it, a string is
// NUL-terminated, an output points to writable memory, for the duration of the call. A NULL
// pointer is what an importer may still pass by mistake: refused (or read as nothing) here.

/// The importer's array `p` of `n` elements (empty if NULL or `n` is 0).
fn slice<'a, T>(p: *const T, n: usize) -> &'a [T] {
    if n == 0 || p.is_null() {
        &[]
    } else {
        // SAFETY: non-NULL, and valid for `n` elements for the call (the boundary's promise above).
        unsafe { std::slice::from_raw_parts(p, n) }
    }
}

/// The importer's output array `p` of `n` elements (empty if NULL or `n` is 0).
fn slice_mut<'a, T>(p: *mut T, n: usize) -> &'a mut [T] {
    if n == 0 || p.is_null() {
        &mut []
    } else {
        // SAFETY: non-NULL, and writable for `n` elements for the call (the boundary's promise).
        unsafe { std::slice::from_raw_parts_mut(p, n) }
    }
}

/// Writes `value` to the importer's output `p` (nothing if it is NULL: the callers refuse that
/// with a message first).
fn put<T>(p: *mut T, value: T) {
    if let Some(out) = slice_mut(p, 1).first_mut() {
        *out = value;
    }
}

/// What the importer's pointer `p` points to (None: NULL).
fn read<T: Copy>(p: *const T) -> Option<T> {
    slice(p, 1).first().copied()
}

/// The importer's string `p` (None: NULL).
fn text(p: *const c_char) -> Option<String> {
    if p.is_null() {
        None
    } else {
        // SAFETY: non-NULL and NUL-terminated (the boundary's promise).
        Some(unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    }
}

/// Runs `f` on the container `c` with its sink set and panics caught.
fn with(c: *mut c_void, function: &str, f: impl FnOnce(&mut Container) -> Outcome) -> Status {
    if c.is_null() {
        return fmi2Error;
    }
    // SAFETY: a non-NULL handle is one this library returned from an instantiation and has not
    // freed (the importer's promise); the importer calls one instance from one thread at a time.
    let container = unsafe { &mut *(c as *mut Container) };
    let sink: *const Sink = &*container.sink;
    // SAFETY: the container's boxed sink, which lives as long as the container.
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
            // SAFETY: as above: the sink outlives this call.
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
/// Keeps `c_void` in the ABI's imports used on every platform.
#[doc(hidden)]
pub type Opaque = c_void;
