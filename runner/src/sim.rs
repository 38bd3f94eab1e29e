//! The master: a fixed communication step, the connections evaluated in dependency order.
//!
//! Its call sequence is that of the project's fmpy master (`examples/cosim/master.py`,
//! `Loop.run`), call for call, so that the two compute the same numbers:
//!
//! 1. fmi2Reset of every instance (from the second run on);
//! 2. the system's parameter and start values (its parameter bindings, in the order written),
//!    the run's overrides on top (an override of a bound variable takes its place, others follow);
//! 3. fmi2SetupExperiment(no tolerance, 0, n·h) and fmi2EnterInitializationMode of every instance;
//!    the connections propagated once per instance; fmi2ExitInitializationMode;
//! 4. at every communication point t = k·h, k = 0..n: the connections propagated, the recorded
//!    variables read, then (k < n) fmi2DoStep(t, h) of every instance;
//! 5. fmi2Terminate.
//!
//! Propagation ([`Scheme::GaussSeidel`]): the components are sorted so that each comes after
//! those whose outputs reach an input it feeds through to an output (ModelStructure
//! `dependencies`; an output without the attribute depends on every input), stable in the
//! system's order; a cycle is an algebraic loop and is refused. Each component's inputs from
//! the components before it are set (one fmi2SetReal per source component), then its outputs
//! are read (one fmi2GetReal); inputs from components later in the order are set last.
//! [`Scheme::Jacobi`] reads every output first, then sets every input.
//!
//! All buffers are made when the simulation is built: a communication step allocates nothing
//! but the recorded row.

use crate::fmi2::{Fmi2Error, FmuState, InstanceCS};
use crate::fmu::{Fmu, type_name};
use crate::ssp::{Archive, Connection};
use crate::{Error, Value};
use fmi_description::Causality;
use fmi_description::fmi2::Type;
use std::ffi::CString;
use std::path::Path;

/// How a communication point is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// In dependency order: each instance's inputs from the outputs read just before (the default).
    GaussSeidel,
    /// Every output read, then every input set: a one-step delay at each feedthrough in a loop.
    Jacobi,
}

/// A per-run value for "component.variable", converted to the variable's type.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Override {
    Real(f64),
    Integer(i64),
    Boolean(bool),
    /// Text, as the command line gives it: parsed as the variable's type.
    Text(String),
}

/// One run.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RunOptions {
    /// s; the run makes n = round(stop_time / step) steps.
    pub stop_time: f64,
    /// Communication step, s.
    pub step: f64,
    /// "component.variable" = value, on top of the system's parameter bindings.
    pub overrides: Vec<(String, Override)>,
    /// "component.variable" to read at every communication point (Real, Integer, Boolean).
    pub record: Vec<String>,
    /// Stop the run after the first communication point where |value| > limit, for a recorded
    /// "component.variable" (a fallen pendulum, a diverged run).
    pub stop_when_above: Vec<(String, f64)>,
    /// Error-controlled communication steps ([`Adaptive`]); `None`: fixed steps of `step`.
    pub adaptive: Option<Adaptive>,
    /// A first-order hold on the connections: see [`Simulation::input_derivatives`].
    pub input_derivatives: bool,
}

/// Error-controlled communication steps: each step of h is made once whole and once as two
/// halves from the same FMU states (step doubling); the difference of the connected outputs at
/// its end estimates the coupling error of the halves. A step whose scaled difference
/// max |a - b| / (tolerance (1 + |b|)) exceeds 1 is rejected (every FMU set back to its state at
/// the step's start) and retried shorter; an accepted one keeps the halves' result, and the next
/// step grows or shrinks by 0.9 err^(-1/2) (the local coupling error of a held input is O(h^2)),
/// between 1/5 and 2 times, within [min_step, max_step]. Needs every component to get and set its
/// FMU state and to take variable steps; otherwise the run is made with fixed steps and
/// [`RunResult::note`] says why.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Adaptive {
    pub tolerance: f64,
    /// s (default: the run's `step` / 1000).
    pub min_step: Option<f64>,
    /// s (default: the run's stop time / 10).
    pub max_step: Option<f64>,
    /// The Real variables ("component.variable") whose difference is the estimate; empty: every
    /// connected output.
    pub error_on: Vec<String>,
}

impl RunOptions {
    pub fn new(stop_time: f64, step: f64) -> RunOptions {
        RunOptions {
            stop_time,
            step,
            overrides: Vec::new(),
            record: Vec::new(),
            stop_when_above: Vec::new(),
            adaptive: None,
            input_derivatives: false,
        }
    }
}

/// What a run recorded: one row per communication point.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct RunResult {
    pub names: Vec<String>,
    /// s
    pub time: Vec<f64>,
    /// Row-major, `time.len() × names.len()`.
    pub values: Vec<f64>,
    /// Whether a `stop_when_above` condition ended the run before `stop_time`.
    pub stopped: bool,
    /// fmi2DoStep calls of the run (each is one call per component): the steps made, accepted
    /// or not.
    pub fmu_steps: usize,
    /// Error-controlled steps rejected (and made again shorter).
    pub rejected: usize,
    /// Why an error-controlled run was made with fixed steps, if it was.
    pub note: Option<String>,
}

impl RunResult {
    /// The recorded values of column `i`.
    pub fn column(&self, i: usize) -> Vec<f64> {
        let m = self.names.len();
        (0..self.time.len()).map(|k| self.values[k * m + i]).collect()
    }
}

/// A run that failed: the error, and what was recorded up to the failure.
#[derive(Debug, Clone)]
pub struct Failure {
    pub error: Error,
    pub partial: RunResult,
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.error.fmt(f)
    }
}

impl From<Error> for Failure {
    fn from(error: Error) -> Failure {
        Failure {
            error,
            partial: RunResult::default(),
        }
    }
}

/// (target, source) components -> [(input vr, output vr)] they connect.
type Pairs = Vec<((usize, usize), Vec<(u32, u32)>)>;

struct Slave {
    name: String,
    /// Index into `Simulation::fmus`.
    fmu: usize,
    instance: Option<InstanceCS>,
    /// An FMI 3.0 FMU: its functions' names in messages are FMI 3.0's ([`fname`]).
    v3: bool,
    /// Run as model exchange, integrated by the runner ([`crate::me`]).
    me: bool,
}

/// The name of the FMI 2.0 function `name` in an FMU of FMI 3.0 (`v3`), for messages.
pub(crate) fn fname(v3: bool, name: &'static str) -> &'static str {
    if !v3 {
        return name;
    }
    match name {
        "fmi2SetReal" => "fmi3SetFloat64",
        "fmi2GetReal" => "fmi3GetFloat64",
        "fmi2SetInteger" => "fmi3SetInt32/fmi3SetInt64",
        "fmi2GetInteger" => "fmi3GetInt32/fmi3GetInt64",
        "fmi2SetBoolean" => "fmi3SetBoolean",
        "fmi2GetBoolean" => "fmi3GetBoolean",
        "fmi2SetString" => "fmi3SetString",
        "fmi2Reset" => "fmi3Reset",
        "fmi2SetupExperiment" | "fmi2EnterInitializationMode" => "fmi3EnterInitializationMode",
        "fmi2ExitInitializationMode" => "fmi3ExitInitializationMode",
        "fmi2DoStep" => "fmi3DoStep",
        "fmi2Terminate" => "fmi3Terminate",
        "fmi2GetFMUstate" => "fmi3GetFMUState",
        "fmi2SetFMUstate" => "fmi3SetFMUState",
        other => other,
    }
}

/// Real value references of one instance and their values.
struct Port {
    slave: usize,
    vrs: Vec<u32>,
    buf: Vec<f64>,
}

/// The inputs one (target, source) pair of components connects, set from `reads[source]`.
struct Write {
    port: Port,
    source: usize,
    /// For each input: index into the source's read buffer.
    idx: Vec<usize>,
}

/// A resolved value to set.
#[derive(Debug, Clone)]
enum Setter {
    Real(f64),
    Integer(i32),
    Boolean(bool),
    String(CString),
}

/// A resolved variable: (slave, value reference, type).
#[derive(Debug, Clone, Copy)]
struct Target {
    slave: usize,
    vr: u32,
    ty: Type,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Real,
    Integer,
    Boolean,
}

/// The recorded variables of one instance and one type.
struct RecordGroup {
    slave: usize,
    kind: Kind,
    vrs: Vec<u32>,
    reals: Vec<f64>,
    ints: Vec<i32>,
    /// Column of each.
    columns: Vec<usize>,
}

pub struct Simulation {
    pub name: String,
    /// How a communication point is evaluated (default [`Scheme::GaussSeidel`]).
    pub scheme: Scheme,
    /// The FMUs (one per distinct source; instances may share one).
    pub fmus: Vec<Fmu>,
    slaves: Vec<Slave>,
    reads: Vec<Port>,
    read_of: Vec<Option<usize>>,
    writes: Vec<Write>,
    /// The components in dependency order, each with the writes set before its outputs are read.
    steps: Vec<(usize, Vec<usize>)>,
    /// Writes from components later in the order.
    late: Vec<usize>,
    /// The system's parameter and start values: ("component.variable", target, value).
    starts: Vec<(String, Target, Setter)>,
    /// Runs begun on the current instances (a run after the first starts with fmi2Reset).
    runs: usize,
    /// An instance returned fmi2Fatal: the next run instantiates every FMU again.
    broken: bool,
    /// A first-order hold on the connections (set per run from [`RunOptions::input_derivatives`]):
    /// after each propagation the connected outputs' first time derivatives are computed in the
    /// evaluation order, each component's own (fmi2GetRealOutputDerivatives, inputs held) plus
    /// its directional derivative along its connected inputs' derivatives (the chain rule through
    /// a feedthrough), twice (the second sweep with every input final), and set as input
    /// derivatives (fmi2SetRealInputDerivatives) on every FMI 2.0 component that can interpolate
    /// its inputs: it then ramps them over the step. A component that gives no output derivatives
    /// passes 0 (a zero-order hold of its outputs).
    pub input_derivatives: bool,
    /// The derivatives of each read port's outputs (as `reads[r].buf`).
    dbufs: Vec<Vec<f64>>,
    /// The connections, as the system names them.
    connections: Vec<Connection>,
    /// The system's own connectors (the runner runs without them; a container exposes them).
    system_connectors: Vec<crate::ssp::SystemConnector>,
    /// Each component in a child process of its own ([`crate::isolate`]), or None: in this one.
    isolation: Option<crate::isolate::Isolation>,
}

fn fmi_err(slave: &str, function: &str, time: Option<f64>, what: &str) -> impl Fn(Fmi2Error) -> Error {
    let (slave, function, what) = (slave.to_owned(), function.to_owned(), what.to_owned());
    move |e| Error::fmi(&slave, &function, &e, time, &what)
}

/// A component's instance: model exchange (`me`) or co-simulation, here or in a child process.
fn make_instance(
    fmu: &Fmu,
    component: &str,
    me: bool,
    isolation: Option<&crate::isolate::Isolation>,
) -> Result<InstanceCS, Error> {
    match isolation {
        Some(iso) => {
            if me && fmu.description.me.is_none() {
                // The in-process refusal, with its reason.
                return fmu.instantiate_me(component);
            }
            fmu.instantiate_isolated(component, me, iso)
        }
        None if me => fmu.instantiate_me(component),
        None => fmu.instantiate(component),
    }
}

impl Simulation {
    /// The system of an SSP file: every component's FMU read from the archive, its parameter
    /// bindings applied at every run.
    pub fn from_ssp(path: &Path) -> Result<Simulation, Error> {
        Simulation::from_archive(Archive::open(path)?, None)
    }

    /// As [`Simulation::from_ssp`], each component instantiated and called in a child process of
    /// its own ([`crate::isolate`]): an FMU that crashes or hangs fails the run, not this process.
    pub fn from_ssp_isolated(path: &Path, isolation: crate::isolate::Isolation) -> Result<Simulation, Error> {
        Simulation::from_archive(Archive::open(path)?, Some(isolation))
    }

    /// Whether the components run in child processes.
    pub fn isolation(&self) -> Option<&crate::isolate::Isolation> {
        self.isolation.as_ref()
    }

    fn from_archive(mut archive: Archive, isolation: Option<crate::isolate::Isolation>) -> Result<Simulation, Error> {
        let ssd = archive.ssd.clone();
        let mut fmus: Vec<Fmu> = Vec::new();
        let mut sources: Vec<String> = Vec::new();
        let mut components = Vec::new();
        for c in &ssd.components {
            let i = match sources.iter().position(|s| *s == c.source) {
                Some(i) => i,
                None => {
                    let fmu = match archive.unpacked_fmu(&c.name)? {
                        Some(dir) => Fmu::from_dir(&c.name, &c.source, &dir),
                        None => Fmu::from_bytes(&c.name, &c.source, archive.fmu_bytes(&c.name)?),
                    };
                    fmus.push(fmu.map_err(|e| Error {
                        message: format!("{}: {}", archive.path, e.message),
                        ..e
                    })?);
                    sources.push(c.source.clone());
                    fmus.len() - 1
                }
            };
            components.push((c.name.clone(), i));
        }
        let parameters = ssd
            .components
            .iter()
            .flat_map(|c| c.parameters.iter().map(|(v, x)| (c.name.clone(), v.clone(), x.clone())))
            .collect();
        let mut sim = Simulation::new_with(&ssd.name, fmus, components, &ssd.connections, parameters, isolation)
            .map_err(|e| Error {
                message: format!("{}: {}", archive.path, e.message),
                ..e
            })?;
        for c in ssd.components.iter().filter(|c| c.model_exchange) {
            sim.use_model_exchange(&c.name).map_err(|e| Error {
                message: format!("{}: {}", archive.path, e.message),
                ..e
            })?;
        }
        for sc in &ssd.connectors {
            for (c, v) in &sc.links {
                sim.resolve(c, v).map_err(|e| Error {
                    message: format!("{}: the system's connector '{}': {}", archive.path, sc.name, e.message),
                    ..e
                })?;
            }
        }
        sim.system_connectors = ssd.connectors;
        Ok(sim)
    }

    /// The system's own connectors (an SSD's `ssd:System/ssd:Connectors`) with the component
    /// variables they are connected to.
    pub fn system_connectors(&self) -> &[crate::ssp::SystemConnector] {
        &self.system_connectors
    }

    /// A system of `fmus`: `components` are (instance name, index into `fmus`); `parameters`
    /// (component, variable, value) are set at every run, in order.
    pub fn new(
        name: &str,
        fmus: Vec<Fmu>,
        components: Vec<(String, usize)>,
        connections: &[Connection],
        parameters: Vec<(String, String, Value)>,
    ) -> Result<Simulation, Error> {
        Simulation::new_with(name, fmus, components, connections, parameters, None)
    }

    /// [`Simulation::new`], the components isolated in child processes with `isolation`.
    pub fn new_with(
        name: &str,
        fmus: Vec<Fmu>,
        components: Vec<(String, usize)>,
        connections: &[Connection],
        parameters: Vec<(String, String, Value)>,
        isolation: Option<crate::isolate::Isolation>,
    ) -> Result<Simulation, Error> {
        let mut slaves = Vec::new();
        for (c, f) in &components {
            if c.is_empty() || slaves.iter().any(|s: &Slave| &s.name == c) {
                return Err(Error::usage(format!(
                    "system '{name}': component name '{c}' is empty or not unique"
                )));
            }
            let fmu = fmus
                .get(*f)
                .ok_or_else(|| Error::usage(format!("component '{c}': no FMU {f}")))?;
            // A model-exchange-only FMU is integrated by the runner.
            let me = fmu.description.cs.is_none();
            slaves.push(Slave {
                name: c.clone(),
                fmu: *f,
                instance: Some(make_instance(fmu, c, me, isolation.as_ref())?),
                v3: fmu.fmi_version() == "3.0",
                me,
            });
        }
        let mut sim = Simulation {
            name: name.to_owned(),
            scheme: Scheme::GaussSeidel,
            fmus,
            slaves,
            reads: Vec::new(),
            read_of: vec![None; components.len()],
            writes: Vec::new(),
            steps: Vec::new(),
            late: Vec::new(),
            starts: Vec::new(),
            runs: 0,
            broken: false,
            input_derivatives: false,
            dbufs: Vec::new(),
            connections: connections.to_vec(),
            system_connectors: Vec::new(),
            isolation,
        };
        sim.build_ports(connections)?;
        for (c, v, value) in parameters {
            let target = sim.resolve(&c, &v)?;
            let setter = sim.typed_setter(&c, &v, target.ty, &value)?;
            sim.starts.push((format!("{c}.{v}"), target, setter));
        }
        Ok(sim)
    }

    /// The system's folder form: `dir/SystemStructure.ssd` and the files it names below `dir`
    /// (an SSP archive unpacked; a container FMU's `resources/system`).
    pub fn from_dir(dir: &Path) -> Result<Simulation, Error> {
        Simulation::from_archive(Archive::open_dir(dir)?, None)
    }

    /// Each component's name and its FMU's description, in the system's order.
    pub fn component_descriptions(&self) -> Vec<(&str, &fmi_description::fmi2::ModelDescription)> {
        self.slaves
            .iter()
            .map(|s| (s.name.as_str(), &self.fmus[s.fmu].description))
            .collect()
    }

    /// Whether a connection drives input `variable` of `component`.
    pub fn is_connected_input(&self, component: &str, variable: &str) -> bool {
        self.source_of(component, variable).is_some()
    }

    /// The output (component, variable) connected to input `variable` of `component`.
    pub fn source_of(&self, component: &str, variable: &str) -> Option<(String, String)> {
        self.connections
            .iter()
            .find(|k| k.end.0 == component && k.end.1 == variable)
            .map(|k| k.start.clone())
    }

    /// The inputs of `component` its variable `output` depends on directly (ModelStructure;
    /// an output without `dependencies` depends on every input, as in fmpy).
    pub fn direct_inputs(&self, component: &str, output: &str) -> Vec<String> {
        let Ok(i) = self.slave_index(component) else {
            return Vec::new();
        };
        let d = &self.fmu_of(i).description;
        let inputs = || {
            d.variables
                .iter()
                .filter(|v| v.causality == Causality::Input)
                .map(|v| v.name.clone())
                .collect::<Vec<_>>()
        };
        let Some(index) = d.variables.iter().position(|v| v.name == output) else {
            return Vec::new();
        };
        match d.model_structure.outputs.iter().find(|u| u.index == index + 1) {
            None => Vec::new(),
            Some(u) => match &u.dependencies {
                None => inputs(),
                Some(deps) => deps
                    .iter()
                    .filter_map(|k| d.by_index(*k))
                    .filter(|v| v.causality == Causality::Input)
                    .map(|v| v.name.clone())
                    .collect(),
            },
        }
    }

    /// The system's own value of `component.variable` (its parameter set), as an XML start value.
    pub fn start_value(&self, component: &str, variable: &str) -> Option<String> {
        let key = format!("{component}.{variable}");
        self.starts.iter().find(|(k, _, _)| *k == key).map(|(_, _, s)| match s {
            Setter::Real(x) => format!("{x:?}"),
            Setter::Integer(x) => x.to_string(),
            Setter::Boolean(x) => x.to_string(),
            Setter::String(s) => s.to_string_lossy().into_owned(),
        })
    }

    /// The instance of component number `i` (the system's order).
    pub fn instance_mut(&mut self, i: usize) -> &mut InstanceCS {
        self.instance(i)
    }

    /// The number of components.
    pub fn len(&self) -> usize {
        self.slaves.len()
    }

    pub fn is_empty(&self) -> bool {
        self.slaves.is_empty()
    }

    /// Sets the system's parameter and start values (its parameter set), in order.
    pub fn apply_starts(&mut self) -> Result<(), Error> {
        let starts = self.starts.clone();
        for (key, target, value) in &starts {
            self.set(key, *target, value)?;
        }
        Ok(())
    }

    /// The index of `component` in the system's order.
    pub fn slave_index(&self, component: &str) -> Result<usize, Error> {
        self.slaves.iter().position(|s| s.name == component).ok_or_else(|| {
            let names: Vec<&str> = self.slaves.iter().map(|s| s.name.as_str()).collect();
            Error::variable(
                component,
                "",
                format!(
                    "system '{}' has no component '{component}' (it has: {})",
                    self.name,
                    names.join(", ")
                ),
            )
        })
    }

    fn fmu_of(&self, slave: usize) -> &Fmu {
        &self.fmus[self.slaves[slave].fmu]
    }

    /// `component.variable`, resolved.
    fn resolve(&self, component: &str, variable: &str) -> Result<Target, Error> {
        let slave = self.slave_index(component)?;
        let v = self.fmu_of(slave).variable(component, variable)?;
        Ok(Target {
            slave,
            vr: v.vr,
            ty: v.ty,
        })
    }

    /// "component.variable" (the component's name is what precedes the first '.').
    fn resolve_qualified(&self, qualified: &str) -> Result<Target, Error> {
        let (c, v) = qualified
            .split_once('.')
            .ok_or_else(|| Error::variable(qualified, "", format!("'{qualified}': expected component.variable")))?;
        self.resolve(c, v)
    }

    fn typed_setter(&self, c: &str, v: &str, ty: Type, value: &Value) -> Result<Setter, Error> {
        let id = self.fmu_of(self.slave_index(c)?).model_identifier().to_owned();
        let mismatch = || {
            Error::variable(
                c,
                v,
                format!(
                    "component '{c}' ({id}): '{v}' is {} in its modelDescription.xml, not {} (the value {value:?})",
                    type_name(ty),
                    value.type_name()
                ),
            )
        };
        Ok(match (ty, value) {
            (Type::Real, Value::Real(x)) => Setter::Real(*x),
            (Type::Integer | Type::Enumeration, Value::Integer(x)) => {
                Setter::Integer(i32::try_from(*x).map_err(|_| {
                    Error::variable(c, v, format!("component '{c}': {v} = {x} is out of the Integer range"))
                })?)
            }
            (Type::Boolean, Value::Boolean(x)) => Setter::Boolean(*x),
            (Type::String, Value::String(s)) => Setter::String(
                CString::new(s.as_str())
                    .map_err(|_| Error::variable(c, v, format!("component '{c}': {v}: a String with a NUL")))?,
            ),
            (Type::Enumeration, Value::Enumeration(item)) => {
                return Err(Error::unsupported(
                    Some(c),
                    Some(v),
                    format!(
                        "component '{c}': {v} = ssv:Enumeration '{item}': item names are not supported, give the item's value as ssv:Integer"
                    ),
                ));
            }
            _ => return Err(mismatch()),
        })
    }

    /// An override converted to the variable's type.
    fn override_setter(&self, qualified: &str, ty: Type, value: &Override) -> Result<Setter, Error> {
        let (c, v) = qualified.split_once('.').unwrap_or((qualified, ""));
        let bad = |why: &str| {
            Error::variable(
                c,
                v,
                format!("{qualified} = {value:?}: {why} (the variable is {})", type_name(ty)),
            )
        };
        let int = |x: i64| i32::try_from(x).map_err(|_| bad("out of the Integer range"));
        Ok(match (ty, value) {
            (Type::Real, Override::Real(x)) => Setter::Real(*x),
            (Type::Real, Override::Integer(x)) => Setter::Real(*x as f64),
            (Type::Real, Override::Text(s)) => Setter::Real(s.trim().parse().map_err(|_| bad("not a number"))?),
            (Type::Integer | Type::Enumeration, Override::Integer(x)) => Setter::Integer(int(*x)?),
            (Type::Integer | Type::Enumeration, Override::Real(x)) if x.fract() == 0.0 && x.is_finite() => {
                Setter::Integer(int(*x as i64)?)
            }
            (Type::Integer | Type::Enumeration, Override::Text(s)) => {
                Setter::Integer(int(s.trim().parse().map_err(|_| {
                    bad(if ty == Type::Enumeration {
                        "not an integer (give the item's value)"
                    } else {
                        "not an integer"
                    })
                })?)?)
            }
            (Type::Boolean, Override::Boolean(b)) => Setter::Boolean(*b),
            (Type::Boolean, Override::Integer(x @ (0 | 1))) => Setter::Boolean(*x == 1),
            (Type::Boolean, Override::Text(s)) => Setter::Boolean(match s.trim() {
                "true" | "1" => true,
                "false" | "0" => false,
                _ => return Err(bad("not a Boolean (true, false, 1, 0)")),
            }),
            (Type::String, Override::Text(s)) => {
                Setter::String(CString::new(s.as_str()).map_err(|_| bad("a String with a NUL"))?)
            }
            _ => return Err(bad("of the wrong type")),
        })
    }

    fn build_ports(&mut self, connections: &[Connection]) -> Result<(), Error> {
        // Sources: each component's connected outputs, in the order the connections name them.
        let mut source_vars: Vec<Vec<u32>> = vec![Vec::new(); self.slaves.len()];
        // (target, source) -> [(input vr, source vr)], in order of first appearance.
        let mut pairs: Pairs = Vec::new();
        for k in connections {
            let text = format!("{}.{} -> {}.{}", k.start.0, k.start.1, k.end.0, k.end.1);
            let from = self.resolve(&k.start.0, &k.start.1).map_err(|e| Error {
                message: format!("connection {text}: {}", e.message),
                ..e
            })?;
            let to = self.resolve(&k.end.0, &k.end.1).map_err(|e| Error {
                message: format!("connection {text}: {}", e.message),
                ..e
            })?;
            for (t, (c, v)) in [(from, &k.start), (to, &k.end)] {
                if t.ty != Type::Real {
                    return Err(Error::unsupported(
                        Some(c),
                        Some(v),
                        format!(
                            "connection {text}: {c}.{v} is {}; the runner connects Real variables only",
                            type_name(t.ty)
                        ),
                    ));
                }
            }
            let causality = |t: Target, name: &str| {
                self.fmu_of(t.slave)
                    .description
                    .variables
                    .iter()
                    .find(|v| v.name == name)
                    .map(|v| v.causality.name())
                    .unwrap_or_default()
            };
            if causality(to, &k.end.1) != Causality::Input.name() {
                return Err(Error::unsupported(
                    Some(&k.end.0),
                    Some(&k.end.1),
                    format!(
                        "connection {text}: {}.{} is not an input (causality '{}')",
                        k.end.0,
                        k.end.1,
                        causality(to, &k.end.1)
                    ),
                ));
            }
            // Units: both declared and different is a conversion the runner does not make.
            let unit = |t: Target, name: &str| {
                self.fmu_of(t.slave)
                    .description
                    .variables
                    .iter()
                    .find(|v| v.name == name)
                    .and_then(|v| v.unit.clone())
            };
            if let (Some(a), Some(b)) = (unit(from, &k.start.1), unit(to, &k.end.1))
                && a != b
            {
                return Err(Error::unsupported(
                    Some(&k.end.0),
                    Some(&k.end.1),
                    format!("connection {text}: from unit '{a}' to unit '{b}': the runner converts no units"),
                ));
            }
            if !source_vars[from.slave].contains(&from.vr) {
                source_vars[from.slave].push(from.vr);
            }
            match pairs.iter_mut().find(|(p, _)| *p == (to.slave, from.slave)) {
                Some((_, list)) => list.push((to.vr, from.vr)),
                None => pairs.push(((to.slave, from.slave), vec![(to.vr, from.vr)])),
            }
        }
        for (slave, vrs) in source_vars.into_iter().enumerate() {
            if !vrs.is_empty() {
                self.read_of[slave] = Some(self.reads.len());
                let n = vrs.len();
                self.reads.push(Port {
                    slave,
                    vrs,
                    buf: vec![0.0; n],
                });
            }
        }
        for ((target, source), list) in &pairs {
            let read = self.read_of[*source].expect("a source has a read port");
            let idx = list
                .iter()
                .map(|(_, svr)| self.reads[read].vrs.iter().position(|v| v == svr).expect("read"))
                .collect();
            let vrs: Vec<u32> = list.iter().map(|(tvr, _)| *tvr).collect();
            let n = vrs.len();
            self.writes.push(Write {
                port: Port {
                    slave: *target,
                    vrs,
                    buf: vec![0.0; n],
                },
                source: read,
                idx,
            });
        }
        // The evaluation order: a topological sort of the direct-feedthrough graph.
        let n = self.slaves.len();
        let mut feeds: Vec<Vec<usize>> = vec![Vec::new(); n];
        for ((target, source), list) in &pairs {
            let ft = &self.fmu_of(*target).feedthrough;
            if list.iter().any(|(tvr, _)| ft.contains(tvr)) && !feeds[*target].contains(source) {
                feeds[*target].push(*source);
            }
        }
        let mut order: Vec<usize> = Vec::new();
        while order.len() < n {
            let ready = (0..n).find(|i| !order.contains(i) && feeds[*i].iter().all(|s| order.contains(s)));
            match ready {
                Some(i) => order.push(i),
                None => {
                    let left: Vec<&str> = (0..n)
                        .filter(|i| !order.contains(i))
                        .map(|i| self.slaves[i].name.as_str())
                        .collect();
                    return Err(Error::unsupported(
                        left.first().copied(),
                        None,
                        format!(
                            "system '{}': algebraic loop (direct feedthrough in a cycle) among {left:?}",
                            self.name
                        ),
                    ));
                }
            }
        }
        let position = |i: usize| order.iter().position(|&s| s == i).expect("sorted");
        for &c in &order {
            let before = pairs
                .iter()
                .enumerate()
                .filter(|(_, ((t, s), _))| *t == c && position(*s) < position(c))
                .map(|(w, _)| w)
                .collect();
            self.steps.push((c, before));
        }
        self.late = pairs
            .iter()
            .enumerate()
            .filter(|(_, ((t, s), _))| position(*s) >= position(*t))
            .map(|(w, _)| w)
            .collect();
        Ok(())
    }

    /// The components in the order [`Scheme::GaussSeidel`] evaluates them.
    pub fn evaluation_order(&self) -> Vec<&str> {
        self.steps.iter().map(|(i, _)| self.slaves[*i].name.as_str()).collect()
    }

    /// The components: (instance name, the FMU's model identifier).
    /// Whether component `i` (in [`Simulation::components`] order) is an FMI 3.0 FMU.
    pub fn is_fmi3(&self, i: usize) -> bool {
        self.slaves[i].v3
    }

    pub fn components(&self) -> Vec<(&str, &str)> {
        self.slaves
            .iter()
            .map(|s| (s.name.as_str(), self.fmus[s.fmu].model_identifier()))
            .collect()
    }

    /// The outputs of every component, "component.variable" (what the command line records by default).
    pub fn outputs(&self) -> Vec<String> {
        let mut out = Vec::new();
        for s in &self.slaves {
            for v in &self.fmus[s.fmu].description.variables {
                if v.causality == Causality::Output
                    && matches!(v.ty, Type::Real | Type::Integer | Type::Boolean | Type::Enumeration)
                {
                    out.push(format!("{}.{}", s.name, v.name));
                }
            }
        }
        out
    }

    /// The system's parameter and start values, "component.variable".
    pub fn parameters(&self) -> Vec<&str> {
        self.starts.iter().map(|(k, _, _)| k.as_str()).collect()
    }

    fn instance(&mut self, slave: usize) -> &mut InstanceCS {
        self.slaves[slave].instance.as_mut().expect("instantiated")
    }

    fn set(&mut self, key: &str, t: Target, value: &Setter) -> Result<(), Error> {
        let name = self.slaves[t.slave].name.clone();
        let v3 = self.slaves[t.slave].v3;
        let variable = key.split_once('.').map_or(key, |(_, v)| v).to_owned();
        let inst = self.instance(t.slave);
        let vr = [t.vr];
        let (function, r) = match value {
            Setter::Real(x) => ("fmi2SetReal", inst.set_real(&vr, &[*x]).map(|_| ())),
            Setter::Integer(x) => ("fmi2SetInteger", inst.set_integer(&vr, &[*x]).map(|_| ())),
            Setter::Boolean(x) => ("fmi2SetBoolean", inst.set_boolean(&vr, &[i32::from(*x)]).map(|_| ())),
            Setter::String(s) => ("fmi2SetString", inst.set_string(&vr, std::slice::from_ref(s))),
        };
        // An isolated component answers a set with its next call: wait here, so that a refused
        // parameter or start value is reported with its name and value.
        let r = r.and_then(|_| {
            inst.sync().map_err(|e| match e {
                Fmi2Error::Deferred(d) => d.error,
                e => e,
            })
        });
        r.map_err(|err| Error {
            variable: Some(variable.clone()),
            ..Error::fmi(&name, fname(v3, function), &err, None, &format!("{variable} = {value}"))
        })
    }

    fn read(&mut self, r: usize, t: f64) -> Result<(), Error> {
        let port = &mut self.reads[r];
        let s = &mut self.slaves[port.slave];
        s.instance
            .as_mut()
            .expect("instantiated")
            .get_real(&port.vrs, &mut port.buf)
            .map(|_| ())
            .map_err(|e| Error::fmi(&s.name, fname(s.v3, "fmi2GetReal"), &e, Some(t), "connected outputs"))
    }

    fn write(&mut self, w: usize, t: f64) -> Result<(), Error> {
        let write = &mut self.writes[w];
        let src = &self.reads[write.source].buf;
        for (j, &i) in write.idx.iter().enumerate() {
            write.port.buf[j] = src[i];
        }
        let s = &mut self.slaves[write.port.slave];
        s.instance
            .as_mut()
            .expect("instantiated")
            .set_real(&write.port.vrs, &write.port.buf)
            .map(|_| ())
            .map_err(|e| Error::fmi(&s.name, fname(s.v3, "fmi2SetReal"), &e, Some(t), "connected inputs"))
    }

    /// Sets every connected input from its output, as [`Simulation::scheme`] says (and, with
    /// [`Simulation::input_derivatives`], their first derivatives).
    pub fn propagate(&mut self, t: f64) -> Result<(), Error> {
        crate::isolate::crumb_time(t);
        self.propagate_values(t)?;
        if self.input_derivatives {
            self.propagate_derivatives(t)?;
        }
        Ok(())
    }

    /// The first-order hold of [`Simulation::input_derivatives`].
    fn propagate_derivatives(&mut self, t: f64) -> Result<(), Error> {
        if self.dbufs.len() != self.reads.len() {
            self.dbufs = self.reads.iter().map(|r| vec![0.0; r.vrs.len()]).collect();
        }
        for _sweep in 0..2 {
            for i in 0..self.steps.len() {
                let c = self.steps[i].0;
                let Some(r) = self.read_of[c] else { continue };
                let fmu = &self.fmus[self.slaves[c].fmu].description;
                let own = fmu.cs.as_ref().is_some_and(|cs| cs.max_output_derivative_order >= 1) && !self.slaves[c].me;
                let directional = fmu.cs.as_ref().is_some_and(|cs| cs.provides_directional_derivative);
                let vrs = self.reads[r].vrs.clone();
                let mut dy = vec![0.0; vrs.len()];
                let s = &mut self.slaves[c];
                let inst = s.instance.as_mut().expect("instantiated");
                if own {
                    inst.get_output_derivatives(&vrs, &mut dy).map_err(|e| {
                        Error::fmi(
                            &s.name,
                            fname(s.v3, "fmi2GetRealOutputDerivatives"),
                            &e,
                            Some(t),
                            "first-order hold",
                        )
                    })?;
                }
                // The chain rule through the component's feedthrough: J du of its connected inputs.
                let (knowns, du) = self.input_derivative_values(c);
                if directional && du.iter().any(|x| *x != 0.0) {
                    let ft = &self.fmus[self.slaves[c].fmu].feedthrough;
                    if knowns.iter().any(|k| ft.contains(k)) {
                        let mut jdu = vec![0.0; vrs.len()];
                        let s = &mut self.slaves[c];
                        s.instance
                            .as_mut()
                            .expect("instantiated")
                            .get_directional_derivative(&vrs, &knowns, &du, &mut jdu)
                            .map_err(|e| {
                                Error::fmi(
                                    &s.name,
                                    fname(s.v3, "fmi2GetDirectionalDerivative"),
                                    &e,
                                    Some(t),
                                    "first-order hold",
                                )
                            })?;
                        for (a, b) in dy.iter_mut().zip(jdu) {
                            *a += b;
                        }
                    }
                }
                if let Some((k, x)) = dy.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                    return Err(Error::fmi(
                        &self.slaves[c].name,
                        "fmi2GetRealOutputDerivatives",
                        &crate::fmi2::Fmi2Error::Importer(format!(
                            "the derivative of value reference {} is {x}",
                            vrs[k]
                        )),
                        Some(t),
                        "first-order hold",
                    ));
                }
                self.dbufs[r] = dy;
            }
        }
        for c in 0..self.slaves.len() {
            let interpolates = !self.slaves[c].v3
                && !self.slaves[c].me
                && self.fmus[self.slaves[c].fmu]
                    .description
                    .cs
                    .as_ref()
                    .is_some_and(|cs| cs.can_interpolate_inputs);
            if !interpolates {
                continue;
            }
            let (vrs, du) = self.input_derivative_values(c);
            if vrs.is_empty() {
                continue;
            }
            let s = &mut self.slaves[c];
            s.instance
                .as_mut()
                .expect("instantiated")
                .set_input_derivatives(&vrs, &du)
                .map_err(|e| Error::fmi(&s.name, "fmi2SetRealInputDerivatives", &e, Some(t), "first-order hold"))?;
        }
        Ok(())
    }

    /// The connected inputs of component `c` and their derivatives (its sources' current ones).
    fn input_derivative_values(&self, c: usize) -> (Vec<u32>, Vec<f64>) {
        let mut vrs = Vec::new();
        let mut du = Vec::new();
        for w in self.writes.iter().filter(|w| w.port.slave == c) {
            let src = self.dbufs.get(w.source);
            for (j, vr) in w.port.vrs.iter().enumerate() {
                vrs.push(*vr);
                du.push(src.map_or(0.0, |d| d[w.idx[j]]));
            }
        }
        (vrs, du)
    }

    /// Sets every connected input from its output, as [`Simulation::scheme`] says.
    fn propagate_values(&mut self, t: f64) -> Result<(), Error> {
        match self.scheme {
            Scheme::GaussSeidel => {
                for i in 0..self.steps.len() {
                    for j in 0..self.steps[i].1.len() {
                        let w = self.steps[i].1[j];
                        self.write(w, t)?;
                    }
                    if let Some(r) = self.read_of[self.steps[i].0] {
                        self.read(r, t)?;
                    }
                }
                for j in 0..self.late.len() {
                    let w = self.late[j];
                    self.write(w, t)?;
                }
            }
            Scheme::Jacobi => {
                for r in 0..self.reads.len() {
                    self.read(r, t)?;
                }
                for w in 0..self.writes.len() {
                    self.write(w, t)?;
                }
            }
        }
        Ok(())
    }

    /// Instantiates every FMU again (after fmi2Fatal).
    fn reinstantiate(&mut self) -> Result<(), Error> {
        for i in 0..self.slaves.len() {
            self.slaves[i].instance = None; // fmi2FreeInstance
            let name = self.slaves[i].name.clone();
            let inst = make_instance(self.fmu_of(i), &name, self.slaves[i].me, self.isolation.as_ref())?;
            self.slaves[i].instance = Some(inst);
        }
        self.runs = 0;
        self.broken = false;
        Ok(())
    }

    /// Steps 1-3 of a run (see the module): (re)starts every instance at t = 0 for a run to
    /// `stop_time`, with `overrides` on top of the system's values.
    pub fn initialize(&mut self, stop_time: f64, overrides: &[(String, Override)]) -> Result<(), Error> {
        let values = self.start_values(overrides)?;
        self.initialize_with(stop_time, &values)
    }

    /// The system's values with `overrides` on top, resolved.
    fn start_values(&self, overrides: &[(String, Override)]) -> Result<Vec<(String, Target, Setter)>, Error> {
        let mut values = self.starts.clone();
        for (key, value) in overrides {
            let target = self.resolve_qualified(key)?;
            let setter = self.override_setter(key, target.ty, value)?;
            match values.iter_mut().find(|(k, _, _)| k == key) {
                Some(slot) => slot.2 = setter,
                None => values.push((key.clone(), target, setter)),
            }
        }
        Ok(values)
    }

    fn initialize_with(&mut self, stop_time: f64, values: &[(String, Target, Setter)]) -> Result<(), Error> {
        if self.broken {
            self.reinstantiate()?;
        }
        // No derivatives in Initialization Mode (FMI 2.0, 4.2.4): the first-order hold begins
        // at the first communication point.
        let derivatives = std::mem::replace(&mut self.input_derivatives, false);
        let result = self.initialize_inner(stop_time, values);
        self.input_derivatives = derivatives;
        if let Err(e) = &result {
            self.note(e);
        }
        result
    }

    fn note(&mut self, e: &Error) {
        if e.status.as_deref() == Some("Fatal") {
            self.broken = true;
        }
    }

    fn initialize_inner(&mut self, stop_time: f64, values: &[(String, Target, Setter)]) -> Result<(), Error> {
        if self.runs > 0 {
            for i in 0..self.slaves.len() {
                let name = self.slaves[i].name.clone();
                self.instance(i)
                    .reset()
                    .map_err(fmi_err(&name, fname(self.slaves[i].v3, "fmi2Reset"), None, ""))?;
            }
        }
        self.runs += 1;
        for (key, target, value) in values {
            self.set(key, *target, value)?;
        }
        for i in 0..self.slaves.len() {
            let name = self.slaves[i].name.clone();
            self.instance(i)
                .setup_experiment(None, 0.0, Some(stop_time))
                .map_err(fmi_err(
                    &name,
                    fname(self.slaves[i].v3, "fmi2SetupExperiment"),
                    None,
                    "",
                ))?;
        }
        for i in 0..self.slaves.len() {
            let name = self.slaves[i].name.clone();
            self.instance(i).enter_initialization_mode().map_err(fmi_err(
                &name,
                fname(self.slaves[i].v3, "fmi2EnterInitializationMode"),
                None,
                "",
            ))?;
        }
        for _ in 0..self.slaves.len() {
            self.propagate(0.0)?;
        }
        for i in 0..self.slaves.len() {
            let name = self.slaves[i].name.clone();
            self.instance(i).exit_initialization_mode().map_err(fmi_err(
                &name,
                fname(self.slaves[i].v3, "fmi2ExitInitializationMode"),
                None,
                "",
            ))?;
        }
        Ok(())
    }

    /// One communication step from `t` to `t + h`: propagate, then fmi2DoStep of every instance.
    pub fn step(&mut self, t: f64, h: f64) -> Result<(), Error> {
        let r = self.propagate(t).and_then(|_| self.do_step(t, h));
        if let Err(e) = &r {
            self.note(e);
        }
        r
    }

    /// fmi2DoStep(t, h) of every instance, in the system's order (noSetFMUStatePriorToCurrentPoint
    /// = true: nothing is set back before this point).
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), Error> {
        self.do_step_with(t, h, true)
    }

    /// fmi2DoStep(t, h, no_set_prior) of every instance, in the system's order; `no_set_prior =
    /// false` when an FMU state of before this point may be set afterwards (a rollback).
    pub fn do_step_with(&mut self, t: f64, h: f64, no_set_prior: bool) -> Result<(), Error> {
        crate::isolate::crumb_time(t);
        for s in &mut self.slaves {
            s.instance
                .as_mut()
                .expect("instantiated")
                .do_step(t, h, no_set_prior)
                .map_err(|e| Error::fmi(&s.name, fname(s.v3, "fmi2DoStep"), &e, Some(t), &format!("step {h} s")))?;
        }
        Ok(())
    }

    /// fmi2Terminate of every instance.
    pub fn terminate(&mut self) -> Result<(), Error> {
        for i in 0..self.slaves.len() {
            let name = self.slaves[i].name.clone();
            self.instance(i).terminate().map_err(fmi_err(
                &name,
                fname(self.slaves[i].v3, "fmi2Terminate"),
                None,
                "",
            ))?;
        }
        Ok(())
    }

    /// Current Real values of a component's variables (value references).
    pub fn get_real(&mut self, component: &str, vrs: &[u32]) -> Result<Vec<f64>, Error> {
        let i = self.slave_index(component)?;
        let mut out = vec![0.0; vrs.len()];
        self.instance(i).get_real(vrs, &mut out).map_err(fmi_err(
            component,
            fname(self.slaves[i].v3, "fmi2GetReal"),
            None,
            "",
        ))?;
        Ok(out)
    }

    /// The value reference of `component.variable`.
    pub fn vr(&self, component: &str, variable: &str) -> Result<u32, Error> {
        Ok(self.resolve(component, variable)?.vr)
    }

    fn record_groups(&self, record: &[String]) -> Result<Vec<RecordGroup>, Error> {
        let mut groups: Vec<RecordGroup> = Vec::new();
        for (col, key) in record.iter().enumerate() {
            let t = self.resolve_qualified(key)?;
            let kind = match t.ty {
                Type::Real => Kind::Real,
                Type::Integer | Type::Enumeration => Kind::Integer,
                Type::Boolean => Kind::Boolean,
                Type::String => {
                    let (c, v) = key.split_once('.').unwrap_or((key, ""));
                    return Err(Error::variable(
                        c,
                        v,
                        format!("{key} is a String: it cannot be recorded"),
                    ));
                }
            };
            let i = match groups.iter().position(|g| g.slave == t.slave && g.kind == kind) {
                Some(i) => i,
                None => {
                    groups.push(RecordGroup {
                        slave: t.slave,
                        kind,
                        vrs: Vec::new(),
                        reals: Vec::new(),
                        ints: Vec::new(),
                        columns: Vec::new(),
                    });
                    groups.len() - 1
                }
            };
            groups[i].vrs.push(t.vr);
            groups[i].columns.push(col);
        }
        for g in &mut groups {
            g.reals = vec![0.0; g.vrs.len()];
            g.ints = vec![0; g.vrs.len()];
        }
        Ok(groups)
    }

    /// One run (see the module): returns the recorded variables at every communication point,
    /// or the failure with what was recorded up to it. `progress(k, n)` is called at every
    /// communication point k = 0..n.
    pub fn run(&mut self, opts: &RunOptions, progress: &mut dyn FnMut(usize, usize)) -> Result<RunResult, Failure> {
        if !(opts.step > 0.0 && opts.step.is_finite()) {
            return Err(Error::usage(format!("step = {} s: must be a positive number", opts.step)).into());
        }
        if !(opts.stop_time >= 0.0 && opts.stop_time.is_finite()) {
            return Err(Error::usage(format!("stop time = {} s: must be a number >= 0", opts.stop_time)).into());
        }
        let n = (opts.stop_time / opts.step).round() as usize;
        crate::fmu_log::install();
        crate::fmu_log::clear();
        self.run_inner(opts, n, progress).map_err(|mut f| {
            let log = crate::fmu_log::take();
            if !log.is_empty() {
                f.error.message = format!("{} | FMU log: {}", f.error.message, log.join(" / "));
            }
            f
        })
    }

    fn run_inner(
        &mut self,
        opts: &RunOptions,
        n: usize,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<RunResult, Failure> {
        if opts.input_derivatives && self.scheme == Scheme::Jacobi {
            return Err(Error::usage(
                "input derivatives (a first-order hold) follow the Gauss-Seidel order: not with the Jacobi scheme",
            )
            .into());
        }
        self.input_derivatives = opts.input_derivatives;
        self.dbufs.clear();
        let values = self.start_values(&opts.overrides)?;
        let mut groups = self.record_groups(&opts.record)?;
        let mut stops = Vec::new();
        for (key, limit) in &opts.stop_when_above {
            let col = opts.record.iter().position(|r| r == key).ok_or_else(|| {
                let (c, v) = key.split_once('.').unwrap_or((key, ""));
                Error::variable(
                    c,
                    v,
                    format!("stop condition on {key}: it must be one of the recorded variables"),
                )
            })?;
            stops.push((col, *limit));
        }
        let m = opts.record.len();
        let mut result = RunResult {
            names: opts.record.clone(),
            time: Vec::with_capacity(n + 1),
            values: Vec::with_capacity((n + 1) * m),
            stopped: false,
            fmu_steps: 0,
            rejected: 0,
            note: None,
        };
        if let Some(a) = &opts.adaptive {
            match self.why_fixed_steps() {
                None => return self.run_adaptive(opts, a, &values, &mut groups, &stops, result, progress),
                Some(why) => result.note = Some(why),
            }
        }
        if let Err(error) = self.initialize_with(n as f64 * opts.step, &values) {
            return Err(Failure { error, partial: result });
        }
        let mut row = vec![0.0; m];
        for k in 0..=n {
            let t = k as f64 * opts.step;
            let r = self
                .propagate(t)
                .and_then(|_| self.read_record(&mut groups, &mut row, t));
            if let Err(error) = r {
                self.note(&error);
                return Err(Failure { error, partial: result });
            }
            result.time.push(t);
            result.values.extend_from_slice(&row);
            progress(k, n);
            if stops.iter().any(|&(c, limit)| row[c].abs() > limit) {
                result.stopped = k < n;
                break;
            }
            if k == n {
                break;
            }
            if let Err(error) = self.do_step(t, opts.step) {
                self.note(&error);
                return Err(Failure { error, partial: result });
            }
            result.fmu_steps += 1;
        }
        if let Err(error) = self.terminate() {
            self.note(&error);
            return Err(Failure { error, partial: result });
        }
        Ok(result)
    }

    /// Runs `component` as model exchange, integrated by the runner (an SSD's
    /// `implementation="ModelExchange"`): its FMU must offer model exchange (FMI 2.0).
    pub fn use_model_exchange(&mut self, component: &str) -> Result<(), Error> {
        let i = self.slave_index(component)?;
        if self.slaves[i].me {
            return Ok(());
        }
        self.slaves[i].instance = None;
        let inst = make_instance(self.fmu_of(i), component, true, self.isolation.as_ref())?;
        self.slaves[i].instance = Some(inst);
        self.slaves[i].me = true;
        Ok(())
    }

    /// Whether `component` runs as model exchange, integrated by the runner.
    pub fn is_model_exchange(&self, component: &str) -> bool {
        self.slave_index(component).is_ok_and(|i| self.slaves[i].me)
    }

    /// Why this system cannot take error-controlled steps (None: it can).
    pub fn why_fixed_steps(&self) -> Option<String> {
        for s in &self.slaves {
            let d = &self.fmus[s.fmu].description;
            if s.me {
                // The runner's own integration takes any step; the FMU's state must be settable.
                if !d.me.as_ref().is_some_and(|me| me.can_get_and_set_fmu_state) {
                    return Some(format!(
                        "fixed steps: component '{}' cannot get and set its FMU state (canGetAndSetFMUstate = false), so a step cannot be made again",
                        s.name
                    ));
                }
                continue;
            }
            let Some(cs) = d.cs.as_ref() else {
                return Some(format!("fixed steps: component '{}' is no co-simulation FMU", s.name));
            };
            if !cs.can_get_and_set_fmu_state {
                return Some(format!(
                    "fixed steps: component '{}' cannot get and set its FMU state (canGetAndSetFMUstate = false), so a step cannot be made again",
                    s.name
                ));
            }
            if !cs.can_handle_variable_step {
                return Some(format!(
                    "fixed steps: component '{}' cannot take steps of varying size (canHandleVariableCommunicationStepSize = false)",
                    s.name
                ));
            }
        }
        None
    }

    /// Every component's FMU state into `slots` (taken anew, or updated).
    fn save_states(&mut self, slots: &mut Vec<FmuState>, t: f64) -> Result<(), Error> {
        if slots.is_empty() {
            for i in 0..self.slaves.len() {
                let name = self.slaves[i].name.clone();
                let st = self.instance(i).get_fmu_state().map_err(fmi_err(
                    &name,
                    fname(self.slaves[i].v3, "fmi2GetFMUstate"),
                    Some(t),
                    "",
                ))?;
                slots.push(st);
            }
        } else {
            for (i, slot) in slots.iter().enumerate() {
                let name = self.slaves[i].name.clone();
                self.instance(i).update_fmu_state(slot).map_err(fmi_err(
                    &name,
                    fname(self.slaves[i].v3, "fmi2GetFMUstate"),
                    Some(t),
                    "",
                ))?;
            }
        }
        Ok(())
    }

    fn load_states(&mut self, slots: &[FmuState], t: f64) -> Result<(), Error> {
        for (i, slot) in slots.iter().enumerate() {
            let name = self.slaves[i].name.clone();
            self.instance(i).set_fmu_state(slot).map_err(fmi_err(
                &name,
                fname(self.slaves[i].v3, "fmi2SetFMUstate"),
                Some(t),
                "rolling back a rejected step",
            ))?;
        }
        Ok(())
    }

    /// What the error is estimated on: the `watched` variables, read now, or (none watched)
    /// every connected output as the last propagation read them.
    fn estimated(&mut self, watched: &[Target], out: &mut Vec<f64>, t: f64) -> Result<(), Error> {
        out.clear();
        if watched.is_empty() {
            for r in &self.reads {
                out.extend_from_slice(&r.buf);
            }
            return Ok(());
        }
        let mut x = [0.0];
        for w in watched {
            let s = &mut self.slaves[w.slave];
            s.instance
                .as_mut()
                .expect("instantiated")
                .get_real(&[w.vr], &mut x)
                .map_err(|e| Error::fmi(&s.name, fname(s.v3, "fmi2GetReal"), &e, Some(t), "error estimate"))?;
            out.push(x[0]);
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn run_adaptive(
        &mut self,
        opts: &RunOptions,
        a: &Adaptive,
        values: &[(String, Target, Setter)],
        groups: &mut [RecordGroup],
        stops: &[(usize, f64)],
        mut result: RunResult,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<RunResult, Failure> {
        let stop = opts.stop_time;
        let min_step = a.min_step.unwrap_or(opts.step / 1000.0);
        let max_step = a.max_step.unwrap_or(stop / 10.0).max(min_step);
        if !(a.tolerance > 0.0 && a.tolerance.is_finite() && min_step > 0.0 && min_step.is_finite()) {
            return Err(Error::usage(format!(
                "error-controlled steps: tolerance = {}, min_step = {min_step}: both must be positive numbers",
                a.tolerance
            ))
            .into());
        }
        let mut watched = Vec::with_capacity(a.error_on.len());
        for key in &a.error_on {
            let target = self.resolve_qualified(key)?;
            if target.ty != Type::Real {
                let (c, v) = key.split_once('.').unwrap_or((key, ""));
                return Err(Error::variable(c, v, format!("error_on {key}: not a Real variable")).into());
            }
            watched.push(target);
        }
        if let Err(error) = self.initialize_with(stop, values) {
            return Err(Failure { error, partial: result });
        }
        let scale = 1000usize;
        let m = opts.record.len();
        let mut row = vec![0.0; m];
        let (mut whole, mut halves) = (Vec::new(), Vec::new());
        let mut slots: Vec<FmuState> = Vec::new();
        let mut t = 0.0f64;
        let mut h = opts.step.clamp(min_step, max_step);
        let outcome: Result<(), Error> = (|| {
            loop {
                self.propagate(t)?;
                self.read_record(groups, &mut row, t)?;
                result.time.push(t);
                result.values.extend_from_slice(&row);
                progress(((t / stop.max(f64::MIN_POSITIVE)) * scale as f64) as usize, scale);
                if stops.iter().any(|&(c, limit)| row[c].abs() > limit) {
                    result.stopped = t < stop;
                    return Ok(());
                }
                if t >= stop {
                    return Ok(());
                }
                loop {
                    // The last step ends at the stop time (a remainder under a tenth of a step joins it).
                    let mut step = h.min(stop - t);
                    if stop - (t + step) < 0.1 * step {
                        step = stop - t;
                    }
                    self.save_states(&mut slots, t)?;
                    self.do_step_with(t, step, false)?;
                    self.propagate(t + step)?;
                    self.estimated(&watched, &mut whole, t + step)?;
                    self.load_states(&slots, t)?;
                    let mid = t + step / 2.0;
                    self.do_step_with(t, step / 2.0, false)?;
                    self.propagate(mid)?;
                    self.do_step_with(mid, t + step - mid, false)?;
                    self.propagate(t + step)?;
                    self.estimated(&watched, &mut halves, t + step)?;
                    result.fmu_steps += 3;
                    let err = whole
                        .iter()
                        .zip(&halves)
                        .map(|(w, b)| (w - b).abs() / (a.tolerance * (1.0 + b.abs())))
                        .fold(0.0f64, f64::max);
                    let grow = if err > 0.0 { 0.9 / err.sqrt() } else { 2.0 };
                    if err <= 1.0 || step <= min_step * (1.0 + 1e-9) {
                        t = if step == stop - t { stop } else { t + step };
                        h = (step * grow.clamp(0.2, 2.0)).clamp(min_step, max_step);
                        break;
                    }
                    result.rejected += 1;
                    self.load_states(&slots, t)?;
                    h = (step * grow.clamp(0.2, 0.9)).max(min_step);
                }
            }
        })();
        for (i, slot) in slots.into_iter().enumerate() {
            let _ = self.instance(i).free_fmu_state(slot);
        }
        if let Err(error) = outcome {
            self.note(&error);
            return Err(Failure { error, partial: result });
        }
        if let Err(error) = self.terminate() {
            self.note(&error);
            return Err(Failure { error, partial: result });
        }
        Ok(result)
    }

    fn read_record(&mut self, groups: &mut [RecordGroup], row: &mut [f64], t: f64) -> Result<(), Error> {
        for g in groups.iter_mut() {
            let s = &mut self.slaves[g.slave];
            let inst = s.instance.as_mut().expect("instantiated");
            let (f, r) = match g.kind {
                Kind::Real => ("fmi2GetReal", inst.get_real(&g.vrs, &mut g.reals)),
                Kind::Integer => ("fmi2GetInteger", inst.get_integer(&g.vrs, &mut g.ints)),
                Kind::Boolean => ("fmi2GetBoolean", inst.get_boolean(&g.vrs, &mut g.ints)),
            };
            r.map_err(|e| Error::fmi(&s.name, fname(s.v3, f), &e, Some(t), "recorded variables"))?;
            for (j, c) in g.columns.iter().enumerate() {
                row[*c] = match g.kind {
                    Kind::Real => g.reals[j],
                    Kind::Integer => f64::from(g.ints[j]),
                    Kind::Boolean => f64::from(u8::from(g.ints[j] != 0)),
                };
            }
        }
        Ok(())
    }
}

impl std::fmt::Display for Setter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Setter::Real(x) => write!(f, "{x}"),
            Setter::Integer(x) => write!(f, "{x}"),
            Setter::Boolean(x) => write!(f, "{x}"),
            Setter::String(s) => write!(f, "{s:?}"),
        }
    }
}
