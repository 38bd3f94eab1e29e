//! The composed loops the benchmarks run, derived from the one description of the systems in
//! `holonomic/systems.toml` (the file `fmu-build` writes as `target/fmu/<system>.ssp`), read and
//! checked against the packaged FMUs by [`fmu_build::systems`]: the FMU instances, every
//! parameter and start value (Real, Integer, Boolean; an Enumeration as its Integer), and the
//! connections. Names are resolved against each FMU's modelDescription.xml when a master starts.
//!
//! | topology | system | FMUs |
//! |---|---|---|
//! | `controller-plant` | `PendulumLQR` | Pendulum, Controller (mode LQR; torques M1, M2 to the plant) |
//! | `full` | `PendulumMotors` | Pendulum, Controller (LQR + PID, voltages), 2 × DCMotor (200:1 gear) |
//!
//! The native master ([`crate::master`]) and the Python masters (`bench/python/composed_loop.py`,
//! which reads this table from `composed-loop --topology-json`, and runs the SSP file of the same
//! system in fmpy.ssp and libcosim) run the same loop.

use fmu_build::systems::{self as sys, System, Systems};
use rustfmu::Value;
use std::sync::OnceLock;

/// The systems file, relative to the workspace root.
pub const SYSTEMS_FILE: &str = "holonomic/systems.toml";

/// The plant's state, in the order of eq. (12).
pub const STATE: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];

/// Name of the plant (the Pendulum FMU instance) in every system.
pub const PLANT: &str = "pendulum";

/// The systems of [`SYSTEMS_FILE`], read once per process (the topologies borrow their names).
pub fn systems() -> Result<&'static Systems, String> {
    static SYSTEMS: OnceLock<Result<Systems, String>> = OnceLock::new();
    SYSTEMS
        .get_or_init(|| Systems::load(&crate::workspace_root().join(SYSTEMS_FILE)))
        .as_ref()
        .map_err(Clone::clone)
}

/// `instance.variable`
pub type Port = (&'static str, &'static str);

/// One FMU instance of the loop.
#[derive(Debug, Clone, Copy)]
pub struct Slave {
    pub instance: &'static str,
    /// Model identifier: the file `target/fmu/<fmu>.fmu`.
    pub fmu: &'static str,
}

#[derive(Debug, Clone)]
pub struct Topology {
    pub name: &'static str,
    /// The system of [`SYSTEMS_FILE`] this loop runs (and of its SSP file).
    pub system: &'static str,
    pub description: &'static str,
    pub slaves: Vec<Slave>,
    /// (from output, to input); Real variables.
    pub connections: Vec<(Port, Port)>,
    /// Parameter and start values, set after instantiation (before fmi2SetupExperiment).
    pub start_values: Vec<(Port, Value)>,
    /// The instance whose state (alpha1, omega1, alpha2, omega2) the benchmarks report.
    pub plant: &'static str,
}

/// Topology names, and the system each runs.
pub const TOPOLOGIES: [(&str, &str); 2] = [("controller-plant", "PendulumLQR"), ("full", "PendulumMotors")];

/// The loop the benchmarks run by default: the paper's whole system.
pub const DEFAULT: &str = "full";

impl Topology {
    /// The loop of `system`, after checking the system against the packaged FMUs' descriptions.
    pub fn from_system(name: &'static str, system: &'static System) -> Result<Topology, String> {
        let checked = system.check(&system.read_fmus(&crate::fmu_dir())?)?;
        let mut start_values = Vec::new();
        for (c, parameters) in system.components.iter().zip(&checked.parameters) {
            for (var, value) in parameters {
                let value = match value {
                    sys::Value::Real(x) => Value::Real(*x),
                    sys::Value::Integer(x) => Value::Integer(*x),
                    sys::Value::Boolean(x) => Value::Boolean(*x),
                    // FMI 2.0 sets an Enumeration through fmi2SetInteger.
                    sys::Value::Enumeration { value, .. } => Value::Integer(*value),
                    sys::Value::String(_) => {
                        return Err(format!(
                            "{}: {}.{var}: the native master sets no String",
                            system.name, c.name
                        ));
                    }
                };
                start_values.push(((c.name.as_str(), *var), value));
            }
        }
        Ok(Topology {
            name,
            system: &system.name,
            description: system.description.as_deref().unwrap_or(""),
            slaves: system
                .components
                .iter()
                .map(|c| Slave {
                    instance: &c.name,
                    fmu: &c.fmu,
                })
                .collect(),
            connections: system
                .connections
                .iter()
                .map(|c| {
                    (
                        (c.from.component.as_str(), c.from.variable.as_str()),
                        (c.to.component.as_str(), c.to.variable.as_str()),
                    )
                })
                .collect(),
            start_values,
            plant: PLANT,
        })
    }
}

/// The loop called `name` (see [`TOPOLOGIES`]).
pub fn by_name(name: &str) -> Result<Topology, String> {
    let (name, system) = TOPOLOGIES.iter().find(|(n, _)| *n == name).ok_or_else(|| {
        let names: Vec<&str> = TOPOLOGIES.iter().map(|(n, _)| *n).collect();
        format!("unknown topology '{name}' (there are: {})", names.join(", "))
    })?;
    Topology::from_system(name, systems()?.get(system)?)
}

/// Pendulum FMU + Controller FMU (LQR), the controller's torques straight into the plant.
pub fn controller_plant() -> Topology {
    by_name("controller-plant").unwrap_or_else(|e| panic!("{e}"))
}

/// The paper's loop: Controller (LQR + PID) -> voltages -> two geared DC motors -> torques ->
/// plant -> angles and speeds.
pub fn full() -> Topology {
    by_name("full").unwrap_or_else(|e| panic!("{e}"))
}

fn json_str(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn json_value(v: Value) -> String {
    match v {
        Value::Real(x) => format!("[\"Real\", {x:e}]"),
        Value::Integer(x) => format!("[\"Integer\", {x}]"),
        Value::Boolean(x) => format!("[\"Boolean\", {x}]"),
        other => unreachable!("the benchmark topologies hold FMI 2.0 values only, not {other:?}"),
    }
}

impl Topology {
    /// The table as JSON, for the Python masters (paths of the FMUs and of the system's SSP file
    /// included; start values as `[[instance, variable], [type, value]]`).
    pub fn to_json(&self) -> String {
        let slaves: Vec<String> = self
            .slaves
            .iter()
            .map(|s| {
                format!(
                    "{{\"instance\": {}, \"fmu\": {}, \"path\": {}}}",
                    json_str(s.instance),
                    json_str(s.fmu),
                    json_str(&crate::fmu_path(s.fmu).display().to_string())
                )
            })
            .collect();
        let port = |p: &Port| format!("[{}, {}]", json_str(p.0), json_str(p.1));
        let connections: Vec<String> = self
            .connections
            .iter()
            .map(|(a, b)| format!("[{}, {}]", port(a), port(b)))
            .collect();
        let starts: Vec<String> = self
            .start_values
            .iter()
            .map(|(p, v)| format!("[{}, {}]", port(p), json_value(*v)))
            .collect();
        let ssp = crate::fmu_dir().join(format!("{}.ssp", self.system));
        format!(
            "{{\"name\": {}, \"system\": {}, \"description\": {}, \"ssp\": {}, \"plant\": {}, \"states\": [{}], \
             \"slaves\": [{}], \"connections\": [{}], \"start_values\": [{}]}}",
            json_str(self.name),
            json_str(self.system),
            json_str(self.description),
            json_str(&ssp.display().to_string()),
            json_str(self.plant),
            STATE.map(json_str).join(", "),
            slaves.join(", "),
            connections.join(", "),
            starts.join(", ")
        )
    }
}
