//! A composed system as one co-simulation FMU (`cargo fmu container SYSTEM.ssp`).
//!
//! The container FMU holds the system's SSP tree under `resources/system/`
//! (`SystemStructure.ssd`, the parameter set, the component FMUs), a [`Spec`] in
//! `resources/container.toml` (the exposed variables and the internal step) and one binary, the
//! same for every system (`runner/container`), which runs this crate's [`crate::Simulation`] on
//! the folder. [`Spec::new`] decides what the container exposes; [`Spec::model_description`]
//! writes its FMI 2.0 `modelDescription.xml`. The binary reads the spec back and checks that
//! its GUID is the one the importer passes to fmi2Instantiate.
//!
//! What a container exposes: the SSD's own system connectors when it has any (each system input
//! sets every component input it is connected to; each system output is the component output
//! connected to it; named as the connectors), otherwise every unconnected input and every output
//! of every component, named `component.variable`; and in both cases every fixed and tunable
//! parameter of every component, named `component.variable`. In the system's connector order (or
//! component order and each component's variable order), with value references 0, 1, 2, ...
//! Their start values are the SSP's parameter set where it binds them, otherwise the component's.

use crate::Error;
use crate::sim::Simulation;
use md_reader::fmi2::{ModelDescription as Description, Type};
use md_reader::{Causality, Initial, Variability};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

mod xml;

/// Where the system's SSP tree lies inside the container's `resources/`.
pub const SYSTEM_FOLDER: &str = "system";
/// The log categories of a container: its own refusals and the components' messages.
pub const LOG_CATEGORIES: [(&str, &str); 4] = [
    (
        "logStatusError",
        "A call refused or failed: what was wrong and where (the component, the function, the time)",
    ),
    ("logStatusDiscard", "A step discarded"),
    ("logStatusFatal", "The instance cannot go on"),
    (
        "logAll",
        "The components' messages, \"[component] message\", and the container's own",
    ),
];

/// The spec's file inside `resources/`.
pub const SPEC_FILE: &str = "container.toml";

/// One variable of the container: a variable of one component.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Exposed {
    /// The container's value reference.
    pub vr: u32,
    /// `component.variable`.
    pub name: String,
    pub component: String,
    pub variable: String,
    /// Real, Integer, Boolean, String or Enumeration.
    #[serde(rename = "type")]
    pub ty: String,
    /// input, output or parameter.
    pub causality: String,
    pub variability: String,
    /// The start value as the XML writes it (none for a calculated output).
    #[serde(default)]
    pub start: Option<String>,
    /// A system input connected to several component inputs: the others (component,
    /// variable), each set with the first.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub also: Vec<(String, String)>,
}

impl Exposed {
    pub fn ty(&self) -> Type {
        match self.ty.as_str() {
            "Real" => Type::Real,
            "Integer" => Type::Integer,
            "Boolean" => Type::Boolean,
            "String" => Type::String,
            _ => Type::Enumeration,
        }
    }
    pub fn causality(&self) -> Causality {
        Causality::from_name(&self.causality).unwrap_or(Causality::Local)
    }
    pub fn variability(&self) -> Variability {
        match self.variability.as_str() {
            "constant" => Variability::Constant,
            "fixed" => Variability::Fixed,
            "tunable" => Variability::Tunable,
            "discrete" => Variability::Discrete,
            _ => Variability::Continuous,
        }
    }
}

/// What `cargo fmu container` writes to `resources/container.toml`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Spec {
    /// The container's modelName and modelIdentifier (the system's name).
    pub model_identifier: String,
    pub guid: String,
    /// The internal communication step of the components, s: a communication step of the
    /// importer is cut into n = ceil(H / step) equal steps (H / n = step when H is a multiple).
    pub step: f64,
    #[serde(rename = "variable")]
    pub variables: Vec<Exposed>,
}

fn type_of(t: Type) -> &'static str {
    t.name()
}

fn variability_name(v: Variability) -> &'static str {
    match v {
        Variability::Constant => "constant",
        Variability::Fixed => "fixed",
        Variability::Tunable => "tunable",
        Variability::Discrete => "discrete",
        Variability::Continuous => "continuous",
    }
}

/// A model identifier from a system name: letters, digits and '_' (a C identifier).
pub fn identifier(name: &str) -> String {
    let mut id: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if id.is_empty() || id.starts_with(|c: char| c.is_ascii_digit()) {
        id.insert(0, '_');
    }
    id
}

impl Spec {
    /// The container of `sim` (a system read by [`Simulation::from_ssp`]) at internal step `step`.
    pub fn new(sim: &Simulation, step: f64) -> Result<Spec, Error> {
        if !(step > 0.0 && step.is_finite()) {
            return Err(Error::usage(format!(
                "internal step = {step} s: must be a positive number"
            )));
        }
        let mut variables: Vec<Exposed> = Vec::new();
        let descriptions = sim.component_descriptions();
        let description_of = |c: &str| descriptions.iter().find(|(n, _)| *n == c).map(|(_, d)| *d);
        let connectors = sim.system_connectors();
        // The system's own connectors, when it has any.
        for sc in connectors {
            let Some((first, rest)) = sc.links.split_first() else {
                return Err(Error::unsupported(
                    None,
                    Some(&sc.name),
                    format!(
                        "the system's {} '{}' is connected to no component: a container cannot give it a value",
                        sc.kind, sc.name
                    ),
                ));
            };
            let d = description_of(&first.0).expect("resolved when the system was read");
            let v = d.variable(&first.1).expect("resolved when the system was read");
            let wanted = if sc.kind == "input" {
                Causality::Input
            } else {
                Causality::Output
            };
            for (c, name) in &sc.links {
                let other = description_of(c).and_then(|d| d.variable(name)).expect("resolved");
                if other.causality != wanted || other.ty != v.ty {
                    return Err(Error::unsupported(
                        Some(c),
                        Some(name),
                        format!(
                            "the system's {} '{}' is connected to '{c}.{name}', a {} {} (expected {} {})",
                            sc.kind,
                            sc.name,
                            other.causality.name(),
                            other.ty.name(),
                            wanted.name(),
                            v.ty.name()
                        ),
                    ));
                }
            }
            let start = match v.causality {
                Causality::Output => match v.initial() {
                    Some(Initial::Exact) => v.start.clone(),
                    _ => None,
                },
                _ => sim.start_value(&first.0, &v.name).or_else(|| v.start.clone()),
            };
            variables.push(Exposed {
                vr: variables.len() as u32,
                name: sc.name.clone(),
                component: first.0.clone(),
                variable: first.1.clone(),
                ty: type_of(v.ty).to_owned(),
                causality: v.causality.name().to_owned(),
                variability: variability_name(v.variability).to_owned(),
                start,
                also: rest.to_vec(),
            });
        }
        for (component, description) in &descriptions {
            let component = *component;
            for v in &description.variables {
                let connected = sim.is_connected_input(component, &v.name);
                let exposed = match v.causality {
                    Causality::Input => connectors.is_empty() && !connected,
                    Causality::Output => connectors.is_empty(),
                    Causality::Parameter => matches!(v.variability, Variability::Fixed | Variability::Tunable),
                    _ => false,
                };
                if !exposed {
                    continue;
                }
                let bound = sim.start_value(component, &v.name);
                let start = match v.causality {
                    Causality::Output => match v.initial() {
                        Some(Initial::Exact) => v.start.clone(),
                        _ => None,
                    },
                    _ => bound.or_else(|| v.start.clone()),
                };
                let name = format!("{component}.{}", v.name);
                if variables.iter().any(|e| e.name == name) {
                    return Err(Error::unsupported(
                        None,
                        Some(&name),
                        format!("the system's connector '{name}' has the name of a component's parameter"),
                    ));
                }
                variables.push(Exposed {
                    vr: variables.len() as u32,
                    name,
                    component: component.to_owned(),
                    variable: v.name.clone(),
                    ty: type_of(v.ty).to_owned(),
                    causality: v.causality.name().to_owned(),
                    variability: variability_name(v.variability).to_owned(),
                    start,
                    also: Vec::new(),
                });
            }
        }
        let mut spec = Spec {
            model_identifier: identifier(&sim.name),
            guid: String::new(),
            step,
            variables,
        };
        // The GUID: a digest of what the container is (its spec and its components' GUIDs).
        let mut seed = toml::to_string(&spec).map_err(|e| Error::io(format!("container spec: {e}")))?;
        for (c, d) in sim.component_descriptions() {
            let _ = write!(seed, "{c}={}", d.guid);
        }
        let h = const_sha1::sha1(seed.as_bytes()).as_bytes();
        let hex: String = h.iter().map(|b| format!("{b:02x}")).collect();
        spec.guid = format!(
            "{{{}-{}-{}-{}-{}}}",
            &hex[0..8],
            &hex[8..12],
            &hex[12..16],
            &hex[16..20],
            &hex[20..32]
        );
        Ok(spec)
    }

    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a spec serializes")
    }

    pub fn from_toml(text: &str) -> Result<Spec, String> {
        toml::from_str(text).map_err(|e| format!("{SPEC_FILE}: {e}"))
    }

    /// FMI 3.0's independent variable `time`: the value reference after the exposed variables'.
    pub fn time_vr(&self) -> u32 {
        self.variables.len() as u32
    }

    /// The indices (1-based, the container's variable order) of the container's inputs an
    /// output depends on directly: through its component's ModelStructure, and through every
    /// connection into an input it depends on, back to the exposed inputs.
    pub fn output_dependencies(&self, sim: &Simulation, output: &Exposed) -> Vec<u32> {
        let mut out = Vec::new();
        let mut seen: Vec<(String, String)> = Vec::new();
        let mut todo = vec![(output.component.clone(), output.variable.clone())];
        while let Some((c, v)) = todo.pop() {
            if seen.contains(&(c.clone(), v.clone())) {
                continue;
            }
            seen.push((c.clone(), v.clone()));
            for input in sim.direct_inputs(&c, &v) {
                let feeds = |e: &&Exposed| {
                    e.causality() == Causality::Input
                        && ((e.component == c && e.variable == input)
                            || e.also.iter().any(|(ac, av)| *ac == c && *av == input))
                };
                if let Some(e) = self.variables.iter().find(feeds) {
                    out.push(e.vr + 1);
                } else if let Some((sc, sv)) = sim.source_of(&c, &input) {
                    todo.push((sc, sv));
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The exposed variable of value reference `vr`.
    pub fn by_vr(&self, vr: u32) -> Option<&Exposed> {
        self.variables.get(vr as usize).filter(|e| e.vr == vr)
    }
}

/// The component's description, checked to be one the container can run.
pub fn check_component(component: &str, d: &Description) -> Result<(), Error> {
    if d.cs.is_none() {
        return Err(Error::unsupported(
            Some(component),
            None,
            format!("component '{component}': not a co-simulation FMU"),
        ));
    }
    Ok(())
}
