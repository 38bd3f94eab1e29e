//! `modelDescription.xml` as an importer reads it: what the suite needs to drive any FMU without
//! knowing it (value references, types, causality, variability, initial, start, min/max, flags).

use quick_xml::Reader;
use quick_xml::events::Event;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Type {
    Real,
    Integer,
    Boolean,
    String,
    Enumeration,
}

#[derive(Debug, Clone)]
pub struct Variable {
    pub name: String,
    pub vr: u32,
    pub ty: Type,
    pub causality: String,
    pub variability: String,
    /// As written in the XML; see [`Variable::initial`] for the one in force.
    pub initial_attr: Option<String>,
    pub start: Option<String>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// `derivative` of a Real: the 1-based index (in `<ModelVariables>`) of the variable this
    /// one is the time derivative of.
    pub derivative: Option<usize>,
}

impl Variable {
    /// The `initial` in force: written, or the default of FMI 2.0 section 2.2.7 (table of
    /// causality × variability). `None` where `initial` is not defined (inputs, independent).
    pub fn initial(&self) -> Option<&str> {
        if let Some(i) = &self.initial_attr {
            return Some(i);
        }
        match (self.causality.as_str(), self.variability.as_str()) {
            ("input" | "independent", _) => None,
            (_, "constant") => Some("exact"),
            ("parameter", _) => Some("exact"),
            ("calculatedParameter" | "output" | "local", _) => Some("calculated"),
            _ => None,
        }
    }

    /// Whether FMI 2.0 (section 3.2.3, the conditions on fmi2SetXXX in the model-exchange state
    /// table) lets an importer set this variable in that model-exchange state. Instantiated and
    /// InitializationMode are as in co-simulation; EventMode as StepComplete; in
    /// ContinuousTimeMode only continuous Real inputs.
    pub fn settable_in_me(&self, state: &str) -> bool {
        match state {
            "EventMode" => self.settable_in("StepComplete"),
            "ContinuousTimeMode" => {
                self.ty == Type::Real && self.causality == "input" && self.variability == "continuous"
            }
            other => self.settable_in(other),
        }
    }

    pub fn start_real(&self) -> Option<f64> {
        self.start.as_deref().and_then(|s| s.parse().ok())
    }

    pub fn start_integer(&self) -> Option<i32> {
        self.start.as_deref().and_then(|s| s.parse().ok())
    }

    pub fn start_boolean(&self) -> Option<bool> {
        self.start.as_deref().map(|s| s == "true" || s == "1")
    }

    /// Whether FMI 2.0 (section 4.2.4, the conditions on fmi2SetXXX in the co-simulation state
    /// table) lets an importer set this variable in the state of that name. Written here from
    /// the standard, independently of the runtime's own rule.
    pub fn settable_in(&self, state: &str) -> bool {
        if self.variability == "constant" {
            return false;
        }
        let input = self.causality == "input";
        match state {
            // "variability != constant that have initial = exact or approx" (and inputs, whose
            // start values an importer sets before initialization)
            "Instantiated" => input || matches!(self.initial(), Some("exact" | "approx")),
            // "variability != constant that have initial = exact, or causality = input"
            "InitializationMode" => input || self.initial() == Some("exact"),
            // "causality = input, or causality = parameter and variability = tunable"
            "StepComplete" => input || (self.causality == "parameter" && self.variability == "tunable"),
            _ => false,
        }
    }
}

/// The `<ModelExchange>` element.
#[derive(Debug, Clone, Default)]
pub struct ModelExchange {
    pub model_identifier: String,
    pub can_get_and_set_fmu_state: bool,
    pub can_serialize_fmu_state: bool,
    pub provides_directional_derivative: bool,
    pub completed_integrator_step_not_needed: bool,
}

/// One `<Unknown>` of `<ModelStructure>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unknown {
    /// 1-based index of the variable in `<ModelVariables>`.
    pub index: usize,
    /// The 1-based indices it depends on; `None` when the attribute is missing (then it may
    /// depend on every known).
    pub dependencies: Option<Vec<usize>>,
}

/// `<ModelStructure>`. A list that does not parse (an index that is no number) is kept as
/// the error, for the checks to report.
#[derive(Debug, Clone, Default)]
pub struct ModelStructure {
    pub outputs: Vec<Unknown>,
    pub derivatives: Vec<Unknown>,
    pub initial_unknowns: Vec<Unknown>,
    pub errors: Vec<String>,
}

#[derive(Debug, Clone)]
pub struct Description {
    pub model_identifier: String,
    pub guid: String,
    pub fmi_version: String,
    pub can_get_and_set_fmu_state: bool,
    pub can_serialize_fmu_state: bool,
    pub provides_directional_derivative: bool,
    pub can_handle_variable_step: bool,
    pub can_interpolate_inputs: bool,
    pub max_output_derivative_order: u32,
    pub can_run_asynchronuously: bool,
    /// Whether the description has a `<ModelExchange>` element too (the FMU then accepts
    /// `fmi2ModelExchange` in fmi2Instantiate).
    pub model_exchange: bool,
    /// The `<ModelExchange>` element, if there is one.
    pub me: Option<ModelExchange>,
    /// `numberOfEventIndicators` of `<fmiModelDescription>` (0 when missing).
    pub number_of_event_indicators: usize,
    pub model_structure: ModelStructure,
    /// `generationTool` of `<fmiModelDescription>`, for the report.
    pub generation_tool: String,
    pub log_categories: Vec<String>,
    /// startTime, stopTime, stepSize of `<DefaultExperiment>`.
    pub default_experiment: (Option<f64>, Option<f64>, Option<f64>),
    pub variables: Vec<Variable>,
}

impl Description {
    pub fn parse(xml: &str) -> Result<Description, String> {
        let mut reader = Reader::from_str(xml);
        let mut d = Description {
            model_identifier: String::new(),
            guid: String::new(),
            fmi_version: String::new(),
            can_get_and_set_fmu_state: false,
            can_serialize_fmu_state: false,
            provides_directional_derivative: false,
            can_handle_variable_step: false,
            can_interpolate_inputs: false,
            max_output_derivative_order: 0,
            can_run_asynchronuously: false,
            model_exchange: false,
            me: None,
            number_of_event_indicators: 0,
            model_structure: ModelStructure::default(),
            generation_tool: String::new(),
            log_categories: vec![],
            default_experiment: (None, None, None),
            variables: vec![],
        };
        let mut current: Option<Variable> = None;
        // Which list of <ModelStructure> the <Unknown>s belong to.
        let mut section: Option<Vec<u8>> = None;
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
                    match e.name().as_ref() {
                        b"fmiModelDescription" => {
                            d.fmi_version = attr(b"fmiVersion").unwrap_or_default();
                            d.guid = attr(b"guid").unwrap_or_default();
                            d.generation_tool = attr(b"generationTool").unwrap_or_default();
                            d.number_of_event_indicators = attr(b"numberOfEventIndicators")
                                .and_then(|v| v.parse().ok())
                                .unwrap_or(0);
                        }
                        b"CoSimulation" => {
                            d.model_identifier = attr(b"modelIdentifier").unwrap_or_default();
                            d.can_get_and_set_fmu_state = flag(b"canGetAndSetFMUstate");
                            d.can_serialize_fmu_state = flag(b"canSerializeFMUstate");
                            d.provides_directional_derivative = flag(b"providesDirectionalDerivative");
                            d.can_handle_variable_step = flag(b"canHandleVariableCommunicationStepSize");
                            d.can_interpolate_inputs = flag(b"canInterpolateInputs");
                            d.max_output_derivative_order = attr(b"maxOutputDerivativeOrder")
                                .and_then(|v| v.parse().ok())
                                .unwrap_or(0);
                            d.can_run_asynchronuously = flag(b"canRunAsynchronuously");
                        }
                        b"ModelExchange" => {
                            d.model_exchange = true;
                            d.me = Some(ModelExchange {
                                model_identifier: attr(b"modelIdentifier").unwrap_or_default(),
                                can_get_and_set_fmu_state: flag(b"canGetAndSetFMUstate"),
                                can_serialize_fmu_state: flag(b"canSerializeFMUstate"),
                                provides_directional_derivative: flag(b"providesDirectionalDerivative"),
                                completed_integrator_step_not_needed: flag(b"completedIntegratorStepNotNeeded"),
                            });
                        }
                        tag @ (b"Outputs" | b"Derivatives" | b"InitialUnknowns") if is_start => {
                            section = Some(tag.to_vec());
                        }
                        b"Unknown" => {
                            let (line, col) = crate::archive::line_column(xml, reader.buffer_position() as usize);
                            let at = format!("modelDescription.xml:{line}:{col}");
                            let index = attr(b"index").and_then(|v| v.trim().parse::<usize>().ok());
                            let dependencies = attr(b"dependencies").map(|v| {
                                v.split_whitespace()
                                    .map(|x| x.parse::<usize>())
                                    .collect::<Result<Vec<_>, _>>()
                            });
                            let ms = &mut d.model_structure;
                            match (index, dependencies) {
                                (None, _) => ms.errors.push(format!("{at}: an <Unknown> without a valid index")),
                                (_, Some(Err(e))) => ms.errors.push(format!("{at}: dependencies: {e}")),
                                (Some(index), deps) => {
                                    let u = Unknown {
                                        index,
                                        dependencies: deps.map(|r| r.unwrap_or_default()),
                                    };
                                    match section.as_deref() {
                                        Some(b"Outputs") => ms.outputs.push(u),
                                        Some(b"Derivatives") => ms.derivatives.push(u),
                                        Some(b"InitialUnknowns") => ms.initial_unknowns.push(u),
                                        _ => ms.errors.push(format!(
                                            "{at}: an <Unknown> outside Outputs, Derivatives and InitialUnknowns"
                                        )),
                                    }
                                }
                            }
                        }
                        b"Category" => d.log_categories.push(attr(b"name").unwrap_or_default()),
                        b"DefaultExperiment" => {
                            d.default_experiment = (real(b"startTime"), real(b"stopTime"), real(b"stepSize"))
                        }
                        b"ScalarVariable" => current = Some(Variable {
                            name: attr(b"name").unwrap_or_default(),
                            vr: attr(b"valueReference").and_then(|v| v.parse().ok()).ok_or_else(|| {
                                let (line, col) = crate::archive::line_column(xml, reader.buffer_position() as usize);
                                format!(
                                    "modelDescription.xml:{line}:{col}: a ScalarVariable without a valid valueReference"
                                )
                            })?,
                            ty: Type::Real,
                            causality: attr(b"causality").unwrap_or_else(|| "local".into()),
                            variability: attr(b"variability").unwrap_or_else(|| "continuous".into()),
                            initial_attr: attr(b"initial"),
                            start: None,
                            min: None,
                            max: None,
                            derivative: None,
                        }),
                        tag @ (b"Real" | b"Integer" | b"Boolean" | b"String" | b"Enumeration") => {
                            if let Some(mut v) = current.take() {
                                v.ty = match tag {
                                    b"Real" => Type::Real,
                                    b"Integer" => Type::Integer,
                                    b"Boolean" => Type::Boolean,
                                    b"String" => Type::String,
                                    _ => Type::Enumeration,
                                };
                                v.start = attr(b"start");
                                v.min = real(b"min");
                                v.max = real(b"max");
                                v.derivative = attr(b"derivative").and_then(|x| x.parse().ok());
                                d.variables.push(v);
                            }
                        }
                        _ => {}
                    }
                }
                Event::End(e) => {
                    if matches!(e.name().as_ref(), b"Outputs" | b"Derivatives" | b"InitialUnknowns") {
                        section = None;
                    }
                }
                _ => {}
            }
        }
        if d.model_identifier.is_empty() {
            return Err("modelDescription.xml: no <CoSimulation modelIdentifier=...>: not a co-simulation FMU".into());
        }
        Ok(d)
    }

    pub fn of_type(&self, ty: Type) -> impl Iterator<Item = &Variable> {
        self.variables.iter().filter(move |v| v.ty == ty)
    }

    pub fn vrs_of_type(&self, ty: Type) -> Vec<u32> {
        self.of_type(ty).map(|v| v.vr).collect()
    }

    pub fn variable(&self, name: &str) -> &Variable {
        self.variables
            .iter()
            .find(|v| v.name == name)
            .unwrap_or_else(|| panic!("{} has no variable '{name}'", self.model_identifier))
    }

    /// The variable of a 1-based `<ModelVariables>` index (as `<ModelStructure>` and
    /// `derivative` give them).
    pub fn by_index(&self, index: usize) -> Option<&Variable> {
        index.checked_sub(1).and_then(|i| self.variables.get(i))
    }

    /// The continuous states, in the order of `<ModelStructure><Derivatives>` (the order of the
    /// state vector of fmi2GetContinuousStates), each as (state, its derivative): the variable
    /// each derivative's `derivative` attribute points to. An error says what is wrong with the
    /// declaration.
    pub fn continuous_states(&self) -> Result<Vec<(&Variable, &Variable)>, String> {
        let ms = &self.model_structure;
        if !ms.errors.is_empty() {
            return Err(ms.errors.join("; "));
        }
        ms.derivatives
            .iter()
            .map(|u| {
                let der = self
                    .by_index(u.index)
                    .ok_or_else(|| format!("<Derivatives> lists index {}, which is no variable", u.index))?;
                if der.ty != Type::Real {
                    return Err(format!("<Derivatives> lists '{}', which is no Real", der.name));
                }
                let Some(of) = der.derivative else {
                    return Err(format!(
                        "<Derivatives> lists '{}', which has no derivative attribute",
                        der.name
                    ));
                };
                let state = self
                    .by_index(of)
                    .ok_or_else(|| format!("'{}' has derivative=\"{of}\", which is no variable", der.name))?;
                if state.ty != Type::Real || state.variability != "continuous" {
                    return Err(format!(
                        "'{}' has derivative=\"{of}\": '{}' is no continuous Real ({:?}, {})",
                        der.name, state.name, state.ty, state.variability
                    ));
                }
                Ok((state, der))
            })
            .collect()
    }

    /// The number of continuous states: the number of `<Derivatives>` unknowns.
    pub fn number_of_continuous_states(&self) -> usize {
        self.model_structure.derivatives.len()
    }

    /// A value reference that names no variable of any type.
    pub fn unknown_vr(&self) -> u32 {
        self.variables.iter().map(|v| v.vr).max().unwrap_or(0) + 1000
    }
}
