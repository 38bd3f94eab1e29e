//! The paper's composed systems, described once, as data: which FMU instances, the parameter and
//! start values each gets, and which output drives which input.
//!
//! `fmu-build` writes each system as an SSP file (`target/fmu/<system>.ssp`), and the benchmarks
//! (`bench/`) run the same systems in their co-simulation masters; both read [`systems`], so the
//! SSP files and the benchmarked loops cannot drift apart. [`System::check`] checks a system
//! against the FMUs' own variable declarations ([`crate::fmus::ALL`]).

use crate::fmi2::FmuEntry;
use crate::fmi2::variables::{Causality, Value, VarDecl};

/// One FMU instance of a system, with the parameter and start values it gets.
#[derive(Debug, Clone)]
pub struct Component {
    pub name: &'static str,
    /// modelIdentifier of the FMU.
    pub fmu: &'static str,
    pub parameters: Vec<(&'static str, Value)>,
}

/// (start element, its output, end element, its input).
pub type Connection = (&'static str, &'static str, &'static str, &'static str);

/// A system: components, and connections from outputs to inputs.
#[derive(Debug, Clone)]
pub struct System {
    pub name: &'static str,
    pub description: &'static str,
    /// Stop time of the SSP file's DefaultExperiment [s].
    pub stop_time: f64,
    pub components: Vec<Component>,
    pub connections: Vec<Connection>,
}

/// The demo motor: the paper's electrical constants with a 200:1 gearbox and a friction typical
/// of small DC motors (the paper's motors cannot hold the pendulum; docs/composition.md).
pub const GEAR_RATIO: f64 = 200.0;
/// Viscous friction of the demo motor [N·m·s/rad].
pub const MOTOR_FRICTION: f64 = 1e-6;
/// Initial state of the demos [rad].
pub const ALPHA1_0: f64 = 0.1;
pub const ALPHA2_0: f64 = -0.05;

/// The plant's state, in the order of eq. (12).
pub const STATE: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];

/// Name of the plant (the Pendulum FMU instance) in every system.
pub const PLANT: &str = "pendulum";

/// The paper's two closed loops: `PendulumLQR` (Controller torques straight to the plant) and
/// `PendulumMotors` (Controller voltages through two geared DC motors).
pub fn systems() -> Vec<System> {
    let pendulum = || Component {
        name: PLANT,
        fmu: "Pendulum",
        parameters: vec![("alpha1", Value::Real(ALPHA1_0)), ("alpha2", Value::Real(ALPHA2_0))],
    };
    let measured = STATE.iter().map(|s| (PLANT, *s, "controller", *s));
    let mut lqr_connections: Vec<_> = measured.clone().collect();
    lqr_connections.extend([("controller", "M1", PLANT, "M1"), ("controller", "M2", PLANT, "M2")]);
    let mut motor_connections: Vec<_> = measured.collect();
    motor_connections.extend([
        ("controller", "U1", "motor1", "U"),
        ("controller", "U2", "motor2", "U"),
        (PLANT, "omega1", "motor1", "omega"),
        (PLANT, "omega2", "motor2", "omega"),
        ("motor1", "tau", PLANT, "M1"),
        ("motor2", "tau", PLANT, "M2"),
    ]);
    let motor = |name| Component {
        name,
        fmu: "DCMotor",
        parameters: vec![
            ("gear_ratio", Value::Real(GEAR_RATIO)),
            ("B", Value::Real(MOTOR_FRICTION)),
        ],
    };
    vec![
        System {
            name: "PendulumLQR",
            description: "Double inverted pendulum stabilized by the LQR controller of eq. (14), torques applied directly",
            stop_time: 5.0,
            components: vec![
                pendulum(),
                Component {
                    name: "controller",
                    fmu: "Controller",
                    parameters: vec![("mode", Value::Integer(1))],
                },
            ],
            connections: lqr_connections,
        },
        System {
            name: "PendulumMotors",
            description: "Double inverted pendulum stabilized by LQR + PID through two geared DC motors with 6 V supply",
            stop_time: 5.0,
            components: vec![
                pendulum(),
                Component {
                    name: "controller",
                    fmu: "Controller",
                    parameters: vec![
                        ("mode", Value::Integer(3)),
                        ("gear_ratio", Value::Real(GEAR_RATIO)),
                        ("motor_B", Value::Real(MOTOR_FRICTION)),
                        ("drives_motors", Value::Boolean(true)),
                    ],
                },
                motor("motor1"),
                motor("motor2"),
            ],
            connections: motor_connections,
        },
    ]
}

/// The system called `name`; the error lists the systems there are.
pub fn system(name: &str) -> Result<System, String> {
    let all = systems();
    let names: Vec<&str> = all.iter().map(|s| s.name).collect();
    let names = names.join(", ");
    all.into_iter()
        .find(|s| s.name == name)
        .ok_or_else(|| format!("no system named '{name}' (there are: {names})"))
}

/// The FMU with modelIdentifier `id` among those this project builds.
pub fn fmu_entry(id: &str) -> Result<&'static FmuEntry, String> {
    crate::fmus::ALL
        .iter()
        .find(|e| e.info.identifier == id)
        .ok_or_else(|| format!("no FMU named '{id}'"))
}

impl System {
    /// The component called `name`.
    pub fn component(&self, name: &str) -> Result<&Component, String> {
        self.components
            .iter()
            .find(|c| c.name == name)
            .ok_or_else(|| format!("{}: no component '{name}'", self.name))
    }

    /// The FMU of `component` and its declaration of `var`.
    pub fn decl(&self, component: &str, var: &str) -> Result<(&'static str, &'static VarDecl), String> {
        let c = self.component(component)?;
        let d = fmu_entry(c.fmu)?
            .variables
            .iter()
            .find(|d| d.name == var)
            .ok_or_else(|| format!("{}: {} ({}) has no variable '{var}'", self.name, component, c.fmu))?;
        Ok((c.fmu, d))
    }

    /// Checks the system against the FMUs' declarations: every connection goes from an output to
    /// an input of the same type, every parameter or start value names a variable that takes
    /// one (not an input: an input's value comes from its connection) and has its type.
    pub fn check(&self) -> Result<(), String> {
        for &(from, out, to, inp) in &self.connections {
            let (_, o) = self.decl(from, out)?;
            let (_, i) = self.decl(to, inp)?;
            if o.causality != Causality::Output || i.causality != Causality::Input || o.var_type != i.var_type {
                return Err(format!(
                    "{}: connection {from}.{out} -> {to}.{inp} must go from an output to an input of the same type",
                    self.name
                ));
            }
        }
        for c in &self.components {
            for (name, value) in &c.parameters {
                let (_, d) = self.decl(c.name, name)?;
                if d.var_type != value.var_type() || !d.has_start() || d.causality == Causality::Input {
                    return Err(format!(
                        "{}: {}.{name} cannot be given a start value of type {:?}",
                        self.name,
                        c.name,
                        value.var_type()
                    ));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_system_is_consistent_with_the_fmus() {
        for s in systems() {
            s.check().unwrap_or_else(|e| panic!("{}: {e}", s.name));
        }
    }

    #[test]
    fn a_connection_between_two_outputs_is_refused() {
        let mut s = system("PendulumLQR").unwrap();
        s.connections.push(("controller", "M1", PLANT, "alpha1"));
        let e = s.check().unwrap_err();
        assert!(
            e.contains("controller.M1 -> pendulum.alpha1"),
            "expected the bad connection named, got: {e}"
        );
    }

    #[test]
    fn a_parameter_of_the_wrong_type_is_refused() {
        let mut s = system("PendulumLQR").unwrap();
        s.components[1].parameters.push(("mode", Value::Real(1.0)));
        let e = s.check().unwrap_err();
        assert!(
            e.contains("controller.mode") && e.contains("Real"),
            "expected controller.mode named with the wrong type, got: {e}"
        );
    }

    #[test]
    fn an_unknown_system_is_reported_with_the_names_there_are() {
        let e = system("Nope").unwrap_err();
        assert!(
            e.contains("'Nope'") && e.contains("PendulumLQR") && e.contains("PendulumMotors"),
            "expected the unknown name and the list of systems, got: {e}"
        );
    }
}
