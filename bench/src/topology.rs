//! The composed loop as data: the FMU instances, the connections between their variables (by
//! name, resolved against each modelDescription.xml when the master starts), the start values,
//! and, while the Controller FMU is not packaged, a stand-in controller that the master computes.
//!
//! The native master ([`crate::master`]) and the Python masters (`bench/python/composed_loop.py`,
//! which reads this table from `composed-loop --topology-json`) run the same table, so a change
//! here changes every benchmark at once.

/// `instance.variable`
pub type Port = (&'static str, &'static str);

/// One FMU instance of the loop.
#[derive(Debug, Clone, Copy)]
pub struct Slave {
    pub instance: &'static str,
    /// Model identifier: the file `target/fmu/<fmu>.fmu`.
    pub fmu: &'static str,
}

/// u = −K (x − 0): state feedback the master computes from the plant's outputs and writes to
/// the plant's inputs before each step. Only in the `stand-in` topology.
#[derive(Debug, Clone, Copy)]
pub struct StateFeedback {
    pub plant: &'static str,
    /// Names of x, in K's column order.
    pub states: [&'static str; 4],
    /// Names of u, in K's row order.
    pub inputs: [&'static str; 2],
    pub k: [[f64; 4]; 2],
}

#[derive(Debug, Clone)]
pub struct Topology {
    pub name: &'static str,
    pub description: &'static str,
    pub slaves: Vec<Slave>,
    /// (from output, to input)
    pub connections: Vec<(Port, Port)>,
    /// Start values set in initialization mode.
    pub start_values: Vec<(Port, f64)>,
    pub feedback: Option<StateFeedback>,
}

/// LQR gain of the paper's eq. (14), for Q = CᵀC, R = I: rows M1, M2 [N·m]; columns α1 [rad],
/// ω1 [rad/s], α2 [rad], ω2 [rad/s]. Our own recomputation (lqr on eq. (12)) to 6 digits.
pub const LQR_GAIN_EQ14: [[f64; 4]; 2] = [
    [14.066567, 2.881627, 1.134796, 1.000988],
    [-3.181387, 0.116086, 4.845614, 0.995738],
];

/// The plant's state, in the order of eq. (12).
const STATES: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];

/// Start of every composed run: the plant tilted from upright, at rest; the controller brings
/// it back.
fn initial_tilt() -> Vec<(Port, f64)> {
    vec![(("Pendulum", "alpha1"), 0.1), (("Pendulum", "alpha2"), -0.05)]
}

/// Pendulum FMU + state feedback in the master (no controller FMU, no motors).
pub fn stand_in() -> Topology {
    Topology {
        name: "stand-in",
        description: "STAND-IN: Pendulum FMU, LQR state feedback u = -K x (paper eq. 14) computed inside the \
                      master; no Controller or DCMotor FMU",
        slaves: vec![Slave {
            instance: "Pendulum",
            fmu: "Pendulum",
        }],
        connections: vec![],
        start_values: initial_tilt(),
        feedback: Some(StateFeedback {
            plant: "Pendulum",
            states: STATES,
            inputs: ["M1", "M2"],
            k: LQR_GAIN_EQ14,
        }),
    }
}

/// Pendulum FMU + Controller FMU, the controller's torques straight into the plant.
pub fn controller_plant() -> Topology {
    let mut connections: Vec<(Port, Port)> = STATES.iter().map(|s| (("Pendulum", *s), ("Controller", *s))).collect();
    connections.push((("Controller", "M1"), ("Pendulum", "M1")));
    connections.push((("Controller", "M2"), ("Pendulum", "M2")));
    Topology {
        name: "controller-plant",
        description: "Pendulum FMU + Controller FMU (torques M1, M2 straight to the plant)",
        slaves: vec![
            Slave {
                instance: "Pendulum",
                fmu: "Pendulum",
            },
            Slave {
                instance: "Controller",
                fmu: "Controller",
            },
        ],
        connections,
        start_values: initial_tilt(),
        feedback: None,
    }
}

/// The paper's loop: Controller -> voltages -> two DC motors -> torques -> plant -> angles.
///
/// The DCMotor variable names below (`U`, `omega`, `M`) are this table's assumption; the master
/// checks each against the FMU's modelDescription.xml and names the ones that do not exist.
pub fn full() -> Topology {
    let mut connections: Vec<(Port, Port)> = STATES.iter().map(|s| (("Pendulum", *s), ("Controller", *s))).collect();
    connections.extend([
        (("Controller", "U1"), ("Motor1", "U")),
        (("Controller", "U2"), ("Motor2", "U")),
        (("Pendulum", "omega1"), ("Motor1", "omega")),
        (("Pendulum", "omega2"), ("Motor2", "omega")),
        (("Motor1", "M"), ("Pendulum", "M1")),
        (("Motor2", "M"), ("Pendulum", "M2")),
    ]);
    Topology {
        name: "full",
        description: "Pendulum + Controller + 2 x DCMotor FMUs (the paper's loop)",
        slaves: vec![
            Slave {
                instance: "Pendulum",
                fmu: "Pendulum",
            },
            Slave {
                instance: "Controller",
                fmu: "Controller",
            },
            Slave {
                instance: "Motor1",
                fmu: "DCMotor",
            },
            Slave {
                instance: "Motor2",
                fmu: "DCMotor",
            },
        ],
        connections,
        start_values: initial_tilt(),
        feedback: None,
    }
}

/// Every topology, by name.
pub fn by_name(name: &str) -> Option<Topology> {
    match name {
        "stand-in" => Some(stand_in()),
        "controller-plant" => Some(controller_plant()),
        "full" => Some(full()),
        _ => None,
    }
}

/// The richest loop whose FMUs are all packaged: `full`, else `controller-plant`, else
/// `stand-in`.
pub fn best_available() -> Topology {
    let have = |id: &str| crate::fmu_path(id).exists();
    if have("Controller") && have("DCMotor") {
        full()
    } else if have("Controller") {
        controller_plant()
    } else {
        stand_in()
    }
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

impl Topology {
    /// The table as JSON, for the Python masters (paths of the FMUs included).
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
            .map(|(p, v)| format!("[{}, {v:e}]", port(p)))
            .collect();
        let feedback = match &self.feedback {
            None => "null".to_string(),
            Some(f) => format!(
                "{{\"plant\": {}, \"states\": [{}], \"inputs\": [{}], \"K\": [{}]}}",
                json_str(f.plant),
                f.states.iter().map(|s| json_str(s)).collect::<Vec<_>>().join(", "),
                f.inputs.iter().map(|s| json_str(s)).collect::<Vec<_>>().join(", "),
                f.k.iter()
                    .map(|row| format!(
                        "[{}]",
                        row.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(", ")
                    ))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        format!(
            "{{\"name\": {}, \"description\": {}, \"slaves\": [{}], \"connections\": [{}], \"start_values\": [{}], \
             \"feedback\": {feedback}}}",
            json_str(self.name),
            json_str(self.description),
            slaves.join(", "),
            connections.join(", "),
            starts.join(", ")
        )
    }
}
