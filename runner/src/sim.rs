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
//! system's order; components whose feedthrough closes a cycle are an algebraic loop, placed as
//! one block and solved by Newton's method where the block's turn comes ([`loops`]). Each
//! component's inputs from the components before it are set (one fmi2SetReal per source
//! component), then its outputs are read (one fmi2GetReal); inputs from components later in the
//! order are set last. [`Scheme::Jacobi`] reads every output first, then sets every input (a loop
//! then has a step of delay, as every other connection).
//!
//! All buffers are made when the simulation is built: a communication step allocates nothing
//! but the recorded row.

use crate::common::{Directional, Fmi2Error, FmuState};
use crate::fmu::{Fmu, type_name};
use crate::instance::InstanceCS;
use crate::ssp::{Archive, Connection};
use crate::{Error, Value};
use md_reader::Causality;
use md_reader::fmi2::Type;
use std::ffi::CString;
use std::path::Path;

mod clocks;
mod exchange;
mod intermediate;
pub mod loops;
mod options;
mod queries;
mod run;
mod typed;

pub use loops::{LoopOptions, LoopReport};
pub use options::{Adaptive, Failure, Override, RunOptions, RunResult, Scheme, Terminated};

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
    /// Run with eventModeUsed and earlyReturnAllowed ([`Simulation::use_event_mode`]).
    events: bool,
    /// Run in Scheduled Execution ([`Simulation::use_scheduled_execution`]).
    scheduled: bool,
    /// The recorded variables its intermediateUpdate callback reads, (component.variable, value
    /// reference) ([`Simulation::record_intermediate_values`]; empty: no callback).
    intermediate: Vec<(String, u32)>,
    /// The values the system gives its structural parameters that size arrays, (value
    /// reference, value): set in Configuration Mode at every run, they size its arrays on
    /// connections, parameters and records ([`crate::fmi3::Var3::sized`]); a structural
    /// parameter not among them keeps its start value.
    sizes: Vec<(u32, usize)>,
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
    /// An FMI 3.0 variable of any type and shape ([`typed`]).
    Values(crate::values::Values),
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
    /// The algebraic loops, in the evaluation order ([`loops`]).
    loops: Vec<loops::Loop>,
    /// How they are solved (set per run from [`RunOptions::loops`]).
    pub loop_options: LoopOptions,
    /// The connections of FMI 3.0 values that are not Float64 scalars ([`typed`]).
    typed: Box<typed::TypedLinks>,
    /// The clock connections ([`clocks`]).
    clock_links: Vec<clocks::ClockLink>,
    /// Where a step ended short: a component's request to end the simulation, early returns
    /// taken back ([`StepBack`]; boxed: off the hot path).
    back: Box<StepBack>,
}

/// What a step that ended short of its end keeps.
#[derive(Default)]
struct StepBack {
    /// After a step a component asked to end the simulation in: the time every component then
    /// reached (the others stepped to it, [`Simulation::complete_ended_step`]), where the run's
    /// last row is read; `Some(None)` where they are not at one time; None: no step decided it.
    ending: Option<Option<f64>>,
    /// Each event-mode component's FMU state (and its clocks' importer side) at the start of
    /// the step, where two or more may return early ([`Simulation::do_step_events`]: the one
    /// that went past the other's early return is taken back); freed after the run.
    early_states: Vec<Option<(FmuState, Option<crate::instance::ClockSnapshot>)>>,
}

fn fmi_err(slave: &str, function: &str, time: Option<f64>, what: &str) -> impl Fn(Fmi2Error) -> Error {
    let (slave, function, what) = (slave.to_owned(), function.to_owned(), what.to_owned());
    move |e| Error::fmi(&slave, &function, &e, time, &what)
}

/// A component's instance for `interface` (co-simulation, model exchange, Event Mode or
/// Scheduled Execution), here or in a child process.
fn make_instance(
    fmu: &Fmu,
    component: &str,
    interface: crate::isolate::Interface,
    isolation: Option<&crate::isolate::Isolation>,
) -> Result<InstanceCS, Error> {
    use crate::isolate::Interface;
    match (isolation, interface) {
        (Some(iso), _) => fmu.instantiate_isolated(component, interface, iso),
        (None, Interface::CoSimulation) => fmu.instantiate(component),
        (None, Interface::ModelExchange) => fmu.instantiate_me(component),
        (None, Interface::EventMode) => fmu.instantiate_events(component),
        (None, Interface::ScheduledExecution) => fmu.instantiate_scheduled(component),
    }
}

impl Slave {
    /// The interface it runs in.
    fn interface(&self) -> crate::isolate::Interface {
        use crate::isolate::Interface;
        match (self.me, self.events, self.scheduled) {
            (true, _, _) => Interface::ModelExchange,
            (_, true, _) => Interface::EventMode,
            (_, _, true) => Interface::ScheduledExecution,
            _ => Interface::CoSimulation,
        }
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
        for c in &ssd.components {
            for (connector, ty, dims) in &c.declared {
                sim.check_declared(&c.name, connector, ty, dims).map_err(|e| Error {
                    message: format!("{}: {}", archive.path, e.message),
                    ..e
                })?;
            }
        }
        for c in ssd.components.iter().filter(|c| c.co_simulation) {
            sim.require_co_simulation(&c.name).map_err(|e| Error {
                message: format!("{}: {}", archive.path, e.message),
                ..e
            })?;
        }
        for c in ssd.components.iter().filter(|c| c.scheduled) {
            sim.use_scheduled_execution(&c.name).map_err(|e| Error {
                message: format!("{}: {}", archive.path, e.message),
                ..e
            })?;
        }
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
        sim.build_clock_links(&ssd.clock_connections)
            .and_then(|()| sim.check_clocked_connections(&ssd.connections))
            .map_err(|e| Error {
                message: format!("{}: {}", archive.path, e.message),
                ..e
            })?;
        sim.system_connectors = ssd.connectors;
        Ok(sim)
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
            // A model-exchange-only FMU is integrated by the runner; one of Scheduled Execution
            // only runs so.
            let scheduled = fmu.scheduled_execution_only();
            let me = fmu.description.cs.is_none() && !scheduled;
            let interface = match (scheduled, me) {
                (true, _) => crate::isolate::Interface::ScheduledExecution,
                (_, true) => crate::isolate::Interface::ModelExchange,
                _ => crate::isolate::Interface::CoSimulation,
            };
            let instance = make_instance(fmu, c, interface, isolation.as_ref())?;
            slaves.push(Slave {
                name: c.clone(),
                fmu: *f,
                instance: Some(instance),
                v3: fmu.fmi_version() == "3.0",
                me,
                events: false,
                scheduled,
                intermediate: Vec::new(),
                sizes: Vec::new(),
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
            loops: Vec::new(),
            loop_options: LoopOptions::default(),
            typed: Default::default(),
            clock_links: Vec::new(),
            back: Box::default(),
        };
        // The structural parameters' values first: they size the arrays the connections join.
        for (c, v, value) in &parameters {
            sim.note_size(c, v, value)?;
        }
        sim.build_ports(connections)?;
        for (c, v, value) in parameters {
            let (target, setter) = match sim.typed_start(&c, &v, &value)? {
                Some(typed) => typed,
                None => {
                    let target = sim.resolve(&c, &v)?;
                    let value = typed::one_item(value);
                    (target, sim.typed_setter(&c, &v, target.ty, &value)?)
                }
            };
            sim.starts.push((format!("{c}.{v}"), target, setter));
        }
        Ok(sim)
    }

    /// The system's folder form: `dir/SystemStructure.ssd` and the files it names below `dir`
    /// (an SSP archive unpacked; a container FMU's `resources/system`).
    pub fn from_dir(dir: &Path) -> Result<Simulation, Error> {
        Simulation::from_archive(Archive::open_dir(dir)?, None)
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

    /// An SSP 2.0 connector's declared type (`ty`, "" if none) and dimensions against its
    /// variable: "if the type of the connector differs from the type of the underlying FMU
    /// variable this constitutes an error" (SSP 2.0, `SystemStructureDescription.xsd`, the
    /// connector's type). SSP 1.0's Real and Integer stand for Float64 and Int32.
    fn check_declared(&self, c: &str, connector: &str, ty: &str, dims: &[Option<u64>]) -> Result<(), Error> {
        let slave = self.slave_index(c)?;
        let fmu = self.fmu_of(slave);
        let clock = match &fmu.import {
            crate::fmu::Import::V3(i) => i.clock_plan().and_then(|p| p.clock(connector)),
            _ => None,
        };
        if ty == "Clock" || clock.is_some() {
            if ty == "Clock" && clock.is_some() {
                return Ok(());
            }
            return Err(Error::variable(
                c,
                connector,
                format!(
                    "component '{c}': connector '{connector}' is declared {} in the SSD, and its variable {} in the FMU's modelDescription.xml (SSP 2.0: a connector's type differing from its variable's is an error)",
                    if ty.is_empty() { "(no type)" } else { ty },
                    if clock.is_some() { "is a Clock" } else { "is no Clock" }
                ),
            ));
        }
        let (actual, shape): (String, Vec<usize>) = match fmu.var3(connector) {
            // Its dimensions as the component's structural parameters set them.
            Some(v) => (v.ty.name().to_owned(), v.sized(&self.slaves[slave].sizes).shape),
            None => {
                let v = fmu.variable(c, connector)?;
                let name = match v.ty {
                    Type::Real => "Float64",
                    Type::Integer => "Int32",
                    t => type_name(t),
                };
                (name.to_owned(), Vec::new())
            }
        };
        let declared = match ty {
            "Real" => "Float64",
            "Integer" => "Int32",
            t => t,
        };
        let kind = |t: &str, d: &[String]| {
            if d.is_empty() {
                t.to_owned()
            } else {
                format!("{t}[{}]", d.join(","))
            }
        };
        let shown: Vec<String> = dims.iter().map(|d| d.map_or("?".into(), |n| n.to_string())).collect();
        let real: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
        let same_shape =
            dims.len() == shape.len() && dims.iter().zip(&shape).all(|(d, n)| d.is_none_or(|d| d as usize == *n));
        if (!declared.is_empty() && declared != actual) || !same_shape {
            return Err(Error::variable(
                c,
                connector,
                format!(
                    "component '{c}': connector '{connector}' is declared {} in the SSD, and its variable is {} in the FMU's modelDescription.xml (SSP 2.0: a connector's type differing from its variable's is an error)",
                    kind(if ty.is_empty() { "(no type)" } else { ty }, &shown),
                    kind(&actual, &real)
                ),
            ));
        }
        Ok(())
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
            // SSP: "the actual numeric value this value is mapped to at run time will depend on
            // the item mapping of the enumeration type of the variables being parameterized".
            (Type::Enumeration, Value::Enumeration(item)) => {
                let fmu = self.fmu_of(self.slave_index(c)?);
                let var = fmu.variable(c, v)?;
                let e = fmu.description.enumeration_of(var).ok_or_else(|| {
                    Error::variable(
                        c,
                        v,
                        format!(
                            "component '{c}' ({id}): {v} = ssv:Enumeration '{item}': its declaredType names no enumeration type of the FMU's TypeDefinitions"
                        ),
                    )
                })?;
                let (_, value) = e.items.iter().find(|(n, _)| n == item).ok_or_else(|| {
                    let items: Vec<&str> = e.items.iter().map(|(n, _)| n.as_str()).collect();
                    Error::variable(
                        c,
                        v,
                        format!(
                            "component '{c}' ({id}): {v} = ssv:Enumeration '{item}': {} has no such item (it has: {})",
                            e.name,
                            items.join(", ")
                        ),
                    )
                })?;
                Setter::Integer(*value)
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

    // ~150 lines: the connections checked (types, causalities, one source per input) and turned
    // into the read and write lists of each component in one pass, so that every refusal names
    // the connection it is about.
    fn build_ports(&mut self, connections: &[Connection]) -> Result<(), Error> {
        // Sources: each component's connected outputs, in the order the connections name them.
        let mut source_vars: Vec<Vec<u32>> = vec![Vec::new(); self.slaves.len()];
        // (target, source) -> [(input vr, source vr)], in order of first appearance.
        let mut pairs: Pairs = Vec::new();
        // (target, source, input) of the typed connections, for the evaluation order.
        let mut typed = Vec::new();
        for k in connections {
            let text = format!("{}.{} -> {}.{}", k.start.0, k.start.1, k.end.0, k.end.1);
            if let Some(link) = self.typed_connection(k, &text)? {
                typed.push(link);
                continue;
            }
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
            let declared = |t: Target, name: &str| {
                self.fmu_of(t.slave)
                    .description
                    .variables
                    .iter()
                    .find(|v| v.name == name)
            };
            let causality = |t: Target, name: &str| declared(t, name).map(|v| v.causality.name()).unwrap_or_default();
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
            let unit = |t: Target, name: &str| declared(t, name).and_then(|v| v.unit.clone());
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
        // The evaluation order: a topological sort of the direct-feedthrough graph's strongly
        // connected components ([`loops::order`]).
        let n = self.slaves.len();
        let mut feeds: Vec<Vec<usize>> = vec![Vec::new(); n];
        for ((target, source), list) in &pairs {
            let ft = &self.fmu_of(*target).feedthrough;
            if list.iter().any(|(tvr, _)| ft.contains(tvr)) && !feeds[*target].contains(source) {
                feeds[*target].push(*source);
            }
        }
        self.typed_feeds(&typed, &mut feeds)?;
        self.arrange(&pairs, &feeds)?;
        self.order_typed();
        Ok(())
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
            Setter::Values(v) => ("fmi3Set", inst.set_typed(&vr, v)),
        };
        // An isolated component answers a set with its next call: wait here, so that a refused
        // parameter or start value is reported with its name and value.
        let r = r.and_then(|_| {
            inst.sync().map_err(|e| match e {
                Fmi2Error::Deferred(d) => d.error,
                e => e,
            })
        });
        let function = match value {
            Setter::Values(v) => format!("{function}{}", v.type_name()),
            _ => fname(v3, function).to_owned(),
        };
        r.map_err(|err| Error {
            variable: Some(variable.clone()),
            ..Error::fmi(&name, &function, &err, None, &format!("{variable} = {value}"))
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

    /// An SSD's `implementation="CoSimulation"`: `component`'s FMU must offer co-simulation. SSP
    /// (SystemStructureDescription.xsd, ssd:Component/@implementation): "the corresponding FMU
    /// implementation must be used. It is an error if the specified type of FMU implementation
    /// is not present in the FMU." Without it the runner would pick the FMU's only interface
    /// (model exchange, or Scheduled Execution).
    pub fn require_co_simulation(&self, component: &str) -> Result<(), Error> {
        let i = self.slave_index(component)?;
        let fmu = self.fmu_of(i);
        if fmu.description.cs.is_some() {
            return Ok(());
        }
        Err(Error::unsupported(
            Some(component),
            None,
            format!(
                "component '{component}' ({}): implementation=\"CoSimulation\", but its modelDescription.xml has no <CoSimulation> (SSP: the implementation named must be used; \"any\" lets the runner choose)",
                fmu.model_identifier()
            ),
        ))
    }

    /// Runs `component` as model exchange, integrated by the runner (an SSD's
    /// `implementation="ModelExchange"`): its FMU must offer model exchange (FMI 2.0).
    pub fn use_model_exchange(&mut self, component: &str) -> Result<(), Error> {
        let i = self.slave_index(component)?;
        if self.slaves[i].me {
            return Ok(());
        }
        self.slaves[i].instance = None;
        let inst = make_instance(
            self.fmu_of(i),
            component,
            crate::isolate::Interface::ModelExchange,
            self.isolation.as_ref(),
        )?;
        self.slaves[i].instance = Some(inst);
        self.slaves[i].me = true;
        Ok(())
    }

    /// Runs the FMI 3.0 co-simulation `component` with eventModeUsed and earlyReturnAllowed
    /// (`sim/clocks.rs`): the events it reports are handled in Event Mode at the time it
    /// reports them, and a step it ends early ends every component's step there.
    pub fn use_event_mode(&mut self, component: &str) -> Result<(), Error> {
        let i = self.slave_index(component)?;
        if self.slaves[i].events {
            return Ok(());
        }
        if self.slaves[i].me || self.slaves[i].scheduled {
            return Err(Error::usage(format!(
                "component '{component}': event mode is for a co-simulation component (not run as model exchange or in Scheduled Execution)"
            )));
        }
        self.slaves[i].instance = None;
        let iso = self.isolation.as_ref();
        let inst = match make_instance(self.fmu_of(i), component, crate::isolate::Interface::EventMode, iso) {
            Ok(inst) => inst,
            Err(e) => {
                let again = make_instance(self.fmu_of(i), component, self.slaves[i].interface(), iso)?;
                self.slaves[i].instance = Some(again);
                return Err(e);
            }
        };
        self.slaves[i].instance = Some(inst);
        self.slaves[i].events = true;
        Ok(())
    }

    /// Runs the FMI 3.0 `component` in Scheduled Execution (an SSD's
    /// `implementation="ScheduledExecution"`; `fmi3/scheduled.rs`): the runner activates the
    /// model partition of each input clock at its ticks, the inputs set before and the outputs
    /// read after; its FMU must have `<ScheduledExecution>`.
    pub fn use_scheduled_execution(&mut self, component: &str) -> Result<(), Error> {
        let i = self.slave_index(component)?;
        if self.slaves[i].scheduled {
            return Ok(());
        }
        let inst = make_instance(
            self.fmu_of(i),
            component,
            crate::isolate::Interface::ScheduledExecution,
            self.isolation.as_ref(),
        )?;
        let s = &mut self.slaves[i];
        s.instance = Some(inst);
        (s.scheduled, s.me, s.events) = (true, false, false);
        Ok(())
    }

    /// Whether `component` runs in Scheduled Execution.
    pub fn is_scheduled(&self, component: &str) -> bool {
        self.slave_index(component).is_ok_and(|i| self.slaves[i].scheduled)
    }

    /// Whether `component` runs as model exchange, integrated by the runner.
    pub fn is_model_exchange(&self, component: &str) -> bool {
        self.slave_index(component).is_ok_and(|i| self.slaves[i].me)
    }
}

impl std::fmt::Display for Setter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Setter::Real(x) => write!(f, "{x}"),
            Setter::Integer(x) => write!(f, "{x}"),
            Setter::Boolean(x) => write!(f, "{x}"),
            Setter::String(s) => write!(f, "{s:?}"),
            Setter::Values(v) => write!(f, "{v}"),
        }
    }
}
