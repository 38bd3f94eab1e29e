//! The composed loops the benchmarks run, derived from the one description of the systems in
//! [`rustfmu::systems`] (the same data `fmu-build` writes as `target/fmu/<system>.ssp`): the FMU
//! instances, every parameter and start value (Real, Integer, Boolean), and the connections.
//! Names are resolved against each FMU's modelDescription.xml when a master starts.
//!
//! | topology | system | FMUs |
//! |---|---|---|
//! | `controller-plant` | `PendulumLQR` | Pendulum, Controller (mode LQR; torques M1, M2 to the plant) |
//! | `full` | `PendulumMotors` | Pendulum, Controller (LQR + PID, voltages), 2 × DCMotor (200:1 gear) |
//!
//! The native master ([`crate::master`]) and the Python masters (`bench/python/composed_loop.py`,
//! which reads this table from `composed-loop --topology-json`, and runs the SSP file of the same
//! system in fmpy.ssp and libcosim) run the same loop.

use rustfmu::Value;
use rustfmu::systems::{self, System};

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
    /// The system of [`rustfmu::systems`] this loop runs (and of its SSP file).
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
    /// The loop of `system`, after checking the system against the FMUs' declarations.
    pub fn from_system(name: &'static str, system: System) -> Result<Topology, String> {
        system.check()?;
        Ok(Topology {
            name,
            system: system.name,
            description: system.description,
            slaves: system
                .components
                .iter()
                .map(|c| Slave {
                    instance: c.name,
                    fmu: c.fmu,
                })
                .collect(),
            connections: system
                .connections
                .iter()
                .map(|&(from, out, to, inp)| ((from, out), (to, inp)))
                .collect(),
            start_values: system
                .components
                .iter()
                .flat_map(|c| c.parameters.iter().map(|&(var, value)| ((c.name, var), value)))
                .collect(),
            plant: systems::PLANT,
        })
    }
}

/// The loop called `name` (see [`TOPOLOGIES`]).
pub fn by_name(name: &str) -> Result<Topology, String> {
    let (name, system) = TOPOLOGIES.iter().find(|(n, _)| *n == name).ok_or_else(|| {
        let names: Vec<&str> = TOPOLOGIES.iter().map(|(n, _)| *n).collect();
        format!("unknown topology '{name}' (there are: {})", names.join(", "))
    })?;
    Topology::from_system(name, systems::system(system)?)
}

/// Pendulum FMU + Controller FMU (LQR), the controller's torques straight into the plant.
pub fn controller_plant() -> Topology {
    by_name("controller-plant").expect("rustfmu::systems has PendulumLQR and it checks")
}

/// The paper's loop: Controller (LQR + PID) -> voltages -> two geared DC motors -> torques ->
/// plant -> angles and speeds.
pub fn full() -> Topology {
    by_name("full").expect("rustfmu::systems has PendulumMotors and it checks")
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
            systems::STATE.map(json_str).join(", "),
            slaves.join(", "),
            connections.join(", "),
            starts.join(", ")
        )
    }
}
