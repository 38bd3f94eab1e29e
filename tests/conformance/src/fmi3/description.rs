//! An FMI 3.0 `modelDescription.xml` as an importer reads it (FMI 3.0 section 2.4): the
//! interfaces and their flags, the variables (one element per type: `<Float64>`, `<Int32>`,
//! ...), the model structure (by value reference) and the log categories.

use quick_xml::Reader;
use quick_xml::events::Event;

#[derive(Debug, Clone)]
pub struct Variable {
    pub name: String,
    pub vr: u32,
    /// The element name: Float64, Int32, Boolean, String, Enumeration, Float32, Binary, Clock...
    pub ty: String,
    pub causality: String,
    pub variability: String,
    pub initial_attr: Option<String>,
    pub start: Option<String>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// `derivative`: the value reference of the variable this one is the derivative of.
    pub derivative: Option<u32>,
    /// `<Dimension>` children: an array variable.
    pub array: bool,
}

impl Variable {
    /// The `initial` in force: written, or the default of the FMI 3.0 table (causality ×
    /// variability, section 2.4.7.4). `None` where it is not defined.
    pub fn initial(&self) -> Option<&str> {
        if let Some(i) = &self.initial_attr {
            return Some(i);
        }
        match (self.causality.as_str(), self.variability.as_str()) {
            ("input" | "independent", _) => None,
            (_, "constant") => Some("exact"),
            ("parameter" | "structuralParameter", _) => Some("exact"),
            ("calculatedParameter" | "output" | "local", _) => Some("calculated"),
            _ => None,
        }
    }

    /// Whether FMI 3.0 lets an importer set this variable in that state (the conditions on
    /// fmi3Set{VariableType} in the state machine: Instantiated: variability != constant with
    /// initial exact or approx, and inputs; InitializationMode: initial exact, and inputs;
    /// EventMode and StepMode: inputs and tunable parameters; ContinuousTimeMode: continuous
    /// inputs).
    pub fn settable_in(&self, state: State) -> bool {
        if self.variability == "constant" || self.causality == "independent" {
            return false;
        }
        let input = self.causality == "input";
        let tunable = self.causality == "parameter" && self.variability == "tunable";
        match state {
            State::Instantiated => input || matches!(self.initial(), Some("exact" | "approx")),
            State::InitializationMode => input || self.initial() == Some("exact"),
            State::EventMode | State::StepMode => input || tunable,
            State::ContinuousTimeMode => input && self.variability == "continuous" && self.ty.starts_with("Float"),
            _ => false,
        }
    }
}

/// The states of the FMI 3.0 state machine an importer can bring an instance into (without
/// event mode, clocks or structural parameters), for ME and CS.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum State {
    Instantiated,
    InitializationMode,
    EventMode,
    ContinuousTimeMode,
    StepMode,
    Terminated,
}

impl State {
    pub const ME: [State; 5] = [
        State::Instantiated,
        State::InitializationMode,
        State::EventMode,
        State::ContinuousTimeMode,
        State::Terminated,
    ];
    pub const CS: [State; 4] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepMode,
        State::Terminated,
    ];
}

#[derive(Debug, Clone, Default)]
pub struct Interface {
    pub model_identifier: String,
    pub can_get_and_set_fmu_state: bool,
    pub can_serialize_fmu_state: bool,
    pub provides_directional_derivatives: bool,
    pub provides_adjoint_derivatives: bool,
    pub has_event_mode: bool,
    pub can_handle_variable_step: bool,
    pub max_output_derivative_order: u32,
    pub provides_intermediate_update: bool,
    pub can_return_early: bool,
}

/// One element of `<ModelStructure>` (`<Output>`, `<ContinuousStateDerivative>`,
/// `<InitialUnknown>`, `<EventIndicator>`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unknown {
    pub vr: u32,
    /// Value references it depends on; `None` when the attribute is missing.
    pub dependencies: Option<Vec<u32>>,
}

#[derive(Debug, Clone, Default)]
pub struct Description {
    pub fmi_version: String,
    pub model_name: String,
    pub token: String,
    pub generation_tool: String,
    pub cs: Option<Interface>,
    pub me: Option<Interface>,
    pub se: bool,
    pub log_categories: Vec<String>,
    pub default_experiment: (Option<f64>, Option<f64>, Option<f64>),
    pub variables: Vec<Variable>,
    pub outputs: Vec<Unknown>,
    pub derivatives: Vec<Unknown>,
    pub initial_unknowns: Vec<Unknown>,
    pub event_indicators: Vec<Unknown>,
    pub errors: Vec<String>,
}

const TYPES: [&str; 15] = [
    "Float32",
    "Float64",
    "Int8",
    "UInt8",
    "Int16",
    "UInt16",
    "Int32",
    "UInt32",
    "Int64",
    "UInt64",
    "Boolean",
    "String",
    "Binary",
    "Enumeration",
    "Clock",
];

impl Description {
    pub fn parse(xml: &str) -> Result<Description, String> {
        let mut reader = Reader::from_str(xml);
        let mut d = Description::default();
        // The variable being read (its <Start>/<Dimension> children follow).
        let mut open: Option<usize> = None;
        let mut in_variables = false;
        loop {
            let event = reader.read_event().map_err(|e| {
                let (line, col) = crate::archive::line_column(xml, reader.error_position() as usize);
                format!("modelDescription.xml:{line}:{col}: {e}")
            })?;
            let is_start = matches!(event, Event::Start(_));
            match event {
                Event::Eof => break,
                Event::Start(e) | Event::Empty(e) => {
                    let attr = |name: &[u8]| -> Option<String> {
                        e.attributes()
                            .flatten()
                            .find(|a| a.key.as_ref() == name)
                            .and_then(|a| a.unescape_value().ok())
                            .map(|v| v.into_owned())
                    };
                    let flag = |name: &[u8]| attr(name).as_deref() == Some("true");
                    let real = |name: &[u8]| attr(name).and_then(|v| v.parse::<f64>().ok());
                    let name = e.name().as_ref().to_vec();
                    let interface = || Interface {
                        model_identifier: attr(b"modelIdentifier").unwrap_or_default(),
                        can_get_and_set_fmu_state: flag(b"canGetAndSetFMUState"),
                        can_serialize_fmu_state: flag(b"canSerializeFMUState"),
                        provides_directional_derivatives: flag(b"providesDirectionalDerivatives"),
                        provides_adjoint_derivatives: flag(b"providesAdjointDerivatives"),
                        has_event_mode: flag(b"hasEventMode"),
                        can_handle_variable_step: flag(b"canHandleVariableCommunicationStepSize"),
                        max_output_derivative_order: attr(b"maxOutputDerivativeOrder")
                            .and_then(|v| v.parse().ok())
                            .unwrap_or(0),
                        provides_intermediate_update: flag(b"providesIntermediateUpdate"),
                        can_return_early: flag(b"canReturnEarlyAfterIntermediateUpdate"),
                    };
                    match name.as_slice() {
                        b"fmiModelDescription" => {
                            d.fmi_version = attr(b"fmiVersion").unwrap_or_default();
                            d.model_name = attr(b"modelName").unwrap_or_default();
                            d.token = attr(b"instantiationToken").unwrap_or_default();
                            d.generation_tool = attr(b"generationTool").unwrap_or_default();
                        }
                        b"CoSimulation" => d.cs = Some(interface()),
                        b"ModelExchange" => d.me = Some(interface()),
                        b"ScheduledExecution" => d.se = true,
                        b"ModelVariables" => in_variables = is_start,
                        b"Category" => d.log_categories.push(attr(b"name").unwrap_or_default()),
                        b"DefaultExperiment" => {
                            d.default_experiment = (real(b"startTime"), real(b"stopTime"), real(b"stepSize"))
                        }
                        b"Start" if open.is_some() => {
                            let i = open.unwrap_or_default();
                            d.variables[i].start = attr(b"value");
                        }
                        b"Dimension" if open.is_some() => {
                            let i = open.unwrap_or_default();
                            d.variables[i].array = true;
                        }
                        tag @ (b"Output" | b"ContinuousStateDerivative" | b"InitialUnknown" | b"EventIndicator") => {
                            let (line, col) = crate::archive::line_column(xml, reader.buffer_position() as usize);
                            let at = format!("modelDescription.xml:{line}:{col}");
                            let vr = attr(b"valueReference").and_then(|v| v.trim().parse::<u32>().ok());
                            let deps = attr(b"dependencies").map(|v| {
                                v.split_whitespace()
                                    .map(|x| x.parse::<u32>())
                                    .collect::<Result<Vec<_>, _>>()
                            });
                            match (vr, deps) {
                                (None, _) => d.errors.push(format!(
                                    "{at}: <{}> without a valid valueReference",
                                    String::from_utf8_lossy(tag)
                                )),
                                (_, Some(Err(e))) => d.errors.push(format!("{at}: dependencies: {e}")),
                                (Some(vr), deps) => {
                                    let u = Unknown {
                                        vr,
                                        dependencies: deps.map(|r| r.unwrap_or_default()),
                                    };
                                    match tag {
                                        b"Output" => d.outputs.push(u),
                                        b"ContinuousStateDerivative" => d.derivatives.push(u),
                                        b"InitialUnknown" => d.initial_unknowns.push(u),
                                        _ => d.event_indicators.push(u),
                                    }
                                }
                            }
                        }
                        tag if in_variables && TYPES.iter().any(|t| t.as_bytes() == tag) => {
                            let ty = String::from_utf8_lossy(tag).into_owned();
                            let vr = attr(b"valueReference").and_then(|v| v.parse().ok()).ok_or_else(|| {
                                let (line, col) = crate::archive::line_column(xml, reader.buffer_position() as usize);
                                format!("modelDescription.xml:{line}:{col}: a <{ty}> without a valid valueReference")
                            })?;
                            d.variables.push(Variable {
                                name: attr(b"name").unwrap_or_default(),
                                vr,
                                start: if ty == "String" || ty == "Binary" {
                                    None
                                } else {
                                    attr(b"start")
                                },
                                ty,
                                causality: attr(b"causality").unwrap_or_else(|| "local".into()),
                                variability: attr(b"variability").unwrap_or_else(|| "continuous".into()),
                                initial_attr: attr(b"initial"),
                                min: real(b"min"),
                                max: real(b"max"),
                                derivative: attr(b"derivative").and_then(|x| x.parse().ok()),
                                array: false,
                            });
                            open = is_start.then_some(d.variables.len() - 1);
                            // A variable of a type other than Float is discrete by default.
                            let v = d.variables.last_mut().unwrap();
                            if !v.ty.starts_with("Float") && attr(b"variability").is_none() {
                                v.variability = "discrete".into();
                            }
                        }
                        _ => {}
                    }
                }
                Event::End(e) => {
                    let n = e.name();
                    if TYPES.iter().any(|t| t.as_bytes() == n.as_ref()) {
                        open = None;
                    }
                    if n.as_ref() == b"ModelVariables" {
                        in_variables = false;
                    }
                }
                _ => {}
            }
        }
        if d.cs.is_none() && d.me.is_none() {
            return Err("modelDescription.xml: neither <CoSimulation> nor <ModelExchange>".into());
        }
        Ok(d)
    }

    /// The model identifier (of CoSimulation, else of ModelExchange).
    pub fn model_identifier(&self) -> &str {
        self.cs
            .as_ref()
            .or(self.me.as_ref())
            .map(|i| i.model_identifier.as_str())
            .unwrap_or("")
    }

    pub fn of_type<'a>(&'a self, ty: &'a str) -> impl Iterator<Item = &'a Variable> + 'a {
        self.variables.iter().filter(move |v| v.ty == ty && !v.array)
    }

    pub fn vrs_of_type(&self, ty: &str) -> Vec<u32> {
        self.of_type(ty).map(|v| v.vr).collect()
    }

    pub fn by_vr(&self, vr: u32) -> Option<&Variable> {
        self.variables.iter().find(|v| v.vr == vr)
    }

    /// A value reference that names no variable.
    pub fn unknown_vr(&self) -> u32 {
        self.variables.iter().map(|v| v.vr).max().unwrap_or(0) + 1000
    }

    /// The continuous states in the order of `<ContinuousStateDerivative>` (the order of the
    /// state vector), as (state vr, derivative vr).
    pub fn continuous_states(&self) -> Result<Vec<(u32, u32)>, String> {
        if !self.errors.is_empty() {
            return Err(self.errors.join("; "));
        }
        self.derivatives
            .iter()
            .map(|u| {
                let der = self.by_vr(u.vr).ok_or(format!(
                    "<ContinuousStateDerivative valueReference=\"{}\"> names no variable",
                    u.vr
                ))?;
                let of = der.derivative.ok_or(format!(
                    "'{}' is listed as a derivative but has no derivative attribute",
                    der.name
                ))?;
                let state = self.by_vr(of).ok_or(format!(
                    "'{}' has derivative=\"{of}\", which names no variable",
                    der.name
                ))?;
                if !state.ty.starts_with("Float") || state.variability != "continuous" {
                    return Err(format!(
                        "'{}' is the state of '{}' but no continuous Float",
                        state.name, der.name
                    ));
                }
                Ok((state.vr, der.vr))
            })
            .collect()
    }

    /// The independent variable (`causality="independent"`).
    pub fn independent(&self) -> Option<&Variable> {
        self.variables.iter().find(|v| v.causality == "independent")
    }
}
