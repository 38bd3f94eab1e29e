//! `rustfmu-runner`: a co-simulation runner for SSP 1.0 and 2.0 systems of FMI 2.0 and FMI 3.0
//! FMUs (co-simulation, or model exchange integrated by the runner) — this project's FMUs and
//! any other exporter's.
//!
//! - [`ssp`] reads an SSP archive's `SystemStructure.ssd`: components (`source="resources/X.fmu"`),
//!   connections, parameter bindings (inline `ssv:ParameterSet` or a `.ssv` file in the archive),
//!   and refuses what it cannot run (system-level connectors, nested systems, transformations,
//!   unit conversions), naming component and connector; SSP 2.0 clock connections.
//! - [`fmu`] loads one FMU with the runner's own importers (FMI 2.0 and FMI 3.0: every type and
//!   array, Event Mode, input clocks of every kind and output clocks, early return).
//! - [`sim`] is the master: parameter and start values after fmi2Instantiate, initialization
//!   with the connections propagated once per instance, then at every communication point
//!   t = k·h the connections evaluated in dependency order (Gauss-Seidel along the connections
//!   by ModelStructure feedthrough, the order of `examples/cosim/master.py`; algebraic loops
//!   solved by Newton's method, [`sim::loops`]) and every FMU stepped; with clock connections
//!   or aperiodic clocks, also at every tick and early return (runner/README.md, Clocks); chosen
//!   variables recorded; parameters and start values overridden per run.
//!
//! The command line is `rustfmu-runner run SYSTEM.ssp --stop-time 10 --step 1e-3
//! --set pendulum.alpha1_0=0.2 --output out.csv`; the Python module (`runner/python`) runs the
//! same [`sim::Simulation`] in-process and returns numpy arrays.

// An Error carries component, variable, function, status and time for the caller (the Python
// exceptions, a study's row): 144 bytes, on the cold path only.
#![allow(clippy::result_large_err)]

pub mod common;
pub mod container;
pub mod fmi2;
pub mod fmi3;
pub mod fmu;
pub mod fmu_log;
pub mod instance;
pub mod isolate;
/// The libpython a PythonFMU binary needs, loaded before it (a crate shared with the conformance
/// checker); `--preload-lib` is its [`libpython::preload`].
pub use rustfmu_libpython as libpython;
pub mod me;
pub mod sim;
pub mod ssp;
pub mod values;

pub use sim::{Adaptive, LoopOptions, LoopReport, Override, RunOptions, RunResult, Scheme, Simulation};

use std::fmt;

/// What kind of problem an [`Error`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ErrorKind {
    /// A file that cannot be read, or an SSD/SSV/modelDescription.xml that cannot be parsed.
    Io,
    /// An SSP feature or FMU kind the runner does not run (it says which).
    Unsupported,
    /// A name that does not resolve (component, variable) or a value of the wrong type.
    Variable,
    /// An FMI call that did not return fmi2OK / fmi2Warning.
    Fmi,
    /// A request that makes no sense (a step <= 0, ...).
    Usage,
    /// An algebraic loop Newton's method did not solve at a communication point (singular, or
    /// not converged): the loop's components and unknowns, the residual and the time.
    Loop,
    /// Not a failure: a component asked to end the simulation (FMI 2.0.5 4.2.3, fmi2Terminated;
    /// FMI 3.0.2 `terminateSimulation`) at `time`, its last successful time. [`Simulation::run`]
    /// ends the run there and returns what it recorded ([`RunResult::terminated`]); only a
    /// caller of [`Simulation::step`] sees it as an error.
    Terminated,
}

/// An error of the runner: always a message naming the component (and variable or function)
/// concerned; for a failed FMI call also the function, the status and the time.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Error {
    pub kind: ErrorKind,
    pub component: Option<String>,
    pub variable: Option<String>,
    /// The FMI function that failed ("fmi2DoStep", ...).
    pub function: Option<String>,
    /// Its status: "Discard", "Error" or "Fatal".
    pub status: Option<String>,
    /// The communication point at which it failed, s.
    pub time: Option<f64>,
    pub message: String,
}

impl Error {
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Error {
        Error {
            kind,
            component: None,
            variable: None,
            function: None,
            status: None,
            time: None,
            message: message.into(),
        }
    }

    pub fn io(message: impl Into<String>) -> Error {
        Error::new(ErrorKind::Io, message)
    }

    pub fn usage(message: impl Into<String>) -> Error {
        Error::new(ErrorKind::Usage, message)
    }

    /// Something the runner does not run, at `component` (and `connector`, if any).
    pub fn unsupported(component: Option<&str>, connector: Option<&str>, message: impl Into<String>) -> Error {
        Error {
            component: component.map(str::to_owned),
            variable: connector.map(str::to_owned),
            ..Error::new(ErrorKind::Unsupported, message)
        }
    }

    pub fn variable(component: &str, variable: &str, message: impl Into<String>) -> Error {
        Error {
            component: Some(component.to_owned()),
            variable: Some(variable.to_owned()),
            ..Error::new(ErrorKind::Variable, message)
        }
    }

    /// A failed FMI call of `component`.
    pub fn fmi(component: &str, function: &str, err: &crate::fmi2::Fmi2Error, time: Option<f64>, what: &str) -> Error {
        if let crate::fmi2::Fmi2Error::Deferred(d) = err {
            // An isolated component's call that failed before this one: report that call.
            let v3 = function.starts_with("fmi3");
            let what = if matches!(d.error, crate::fmi2::Fmi2Error::Died(_)) {
                String::new()
            } else {
                format!("reported at {function}")
            };
            return Error::fmi(component, crate::sim::fname(v3, d.function), &d.error, d.time, &what);
        }
        if let crate::fmi2::Fmi2Error::Died(how) = err {
            let at = time.map(|t| format!(" at t = {t} s")).unwrap_or_default();
            return Error {
                component: Some(component.to_owned()),
                function: Some(function.to_owned()),
                status: Some("Fatal".to_owned()),
                time,
                ..Error::new(
                    ErrorKind::Fmi,
                    format!("component '{component}': {function}{at} did not return: {how}"),
                )
            };
        }
        if let crate::fmi2::Fmi2Error::Terminate(at) = err {
            let during = match time {
                Some(t) => format!("{function} from t = {t} s"),
                None => function.to_owned(),
            };
            return Error {
                component: Some(component.to_owned()),
                function: Some(function.to_owned()),
                time: Some(*at),
                ..Error::new(
                    ErrorKind::Terminated,
                    format!("component '{component}' asked to terminate the simulation at t = {at} s (in {during})"),
                )
            };
        }
        let status = match err {
            crate::fmi2::Fmi2Error::Discard => "Discard".to_owned(),
            crate::fmi2::Fmi2Error::Error => "Error".to_owned(),
            crate::fmi2::Fmi2Error::Fatal => "Fatal".to_owned(),
            other => format!("{other}"),
        };
        let at = time.map(|t| format!(" at t = {t} s")).unwrap_or_default();
        let what = if what.is_empty() {
            String::new()
        } else {
            format!(" ({what})")
        };
        // The importer's own refusal (a clock's tick inside a step, fmi3DoStep asking to
        // terminate): its words, not a status.
        let message = match err {
            crate::fmi2::Fmi2Error::Importer(m) => format!("component '{component}': {function}{what}{at}: {m}"),
            _ => format!("component '{component}': {function}{what} returned fmi2{status}{at}"),
        };
        Error {
            component: Some(component.to_owned()),
            function: Some(function.to_owned()),
            status: Some(status.clone()),
            time,
            ..Error::new(ErrorKind::Fmi, message)
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

impl From<Error> for String {
    fn from(e: Error) -> String {
        e.message
    }
}

/// A typed parameter or start value, as an SSV file or a systems table writes it.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Real(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    /// `ssv:Enumeration value="<item name>"`: set through fmi2SetInteger once resolved.
    Enumeration(String),
    /// An SSV 2.0 value the scalars above do not hold: an array (`value` a list, row-major), a
    /// UInt64 beyond i64, or a Binary (hexadecimal digits); `ty` the SSV element (`Float64`,
    /// `Int8`, ..., `Binary`), `text` the value as written. It binds to an FMI 3.0 variable of
    /// that type, its number of elements checked.
    List {
        ty: String,
        text: String,
    },
    /// An SSV 2.0 array of `ssv:Value` elements (SSP 2.0, SystemStructureParameterValues.xsd:
    /// String, Enumeration and Binary arrays, row-major): `ty` the element (`String`,
    /// `Enumeration`, `Binary`), `items` each element's `value` (a String as it is, an
    /// Enumeration item's name, a Binary as hexadecimal digits).
    Items {
        ty: String,
        items: Vec<String>,
    },
}

impl Value {
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::Real(_) => "Real",
            Value::Integer(_) => "Integer",
            Value::Boolean(_) => "Boolean",
            Value::String(_) => "String",
            Value::Enumeration(_) => "Enumeration",
            Value::List { .. } => "SSV 2.0 list",
            Value::Items { .. } => "SSV 2.0 list of ssv:Value elements",
        }
    }
}
