//! An FMI 2.0 `modelDescription.xml` (FMI 2.0 chapter 2.2): the interfaces and their flags, the
//! enumeration types, the variables (`<ScalarVariable>` with one type element), the model
//! structure (by 1-based variable index), the log categories and the default experiment.

use crate::common::{DefaultExperiment, kind};
use crate::read::{Events, Node};
use crate::{Causality, Initial, Variability, Version};
use std::fmt;

/// The type element of a `<ScalarVariable>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Type {
    Real,
    Integer,
    Boolean,
    String,
    Enumeration,
}

impl Type {
    /// Its element name, in modelDescription.xml as in SSP (`ssc:Real`, `ssv:Real`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Type::Real => "Real",
            Type::Integer => "Integer",
            Type::Boolean => "Boolean",
            Type::String => "String",
            Type::Enumeration => "Enumeration",
        }
    }

    fn from_element(name: &[u8]) -> Option<Type> {
        Some(match name {
            b"Real" => Type::Real,
            b"Integer" => Type::Integer,
            b"Boolean" => Type::Boolean,
            b"String" => Type::String,
            b"Enumeration" => Type::Enumeration,
            _ => return None,
        })
    }
}

impl fmt::Display for Type {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A `<ScalarVariable>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    pub name: String,
    pub vr: u32,
    pub ty: Type,
    pub causality: Causality,
    pub variability: Variability,
    /// `initial` as written; [`Variable::initial`] is the one in force.
    pub declared_initial: Option<Initial>,
    /// The `start` attribute, as written.
    pub start: Option<String>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// `derivative` of a Real: the 1-based index (in `<ModelVariables>`) of the variable this
    /// one is the time derivative of.
    pub derivative: Option<usize>,
    /// `declaredType`: the name of its type in `<TypeDefinitions>` (an Enumeration's items).
    pub declared_type: Option<String>,
    pub unit: Option<String>,
    pub description: Option<String>,
}

impl Variable {
    /// The `initial` in force: written, or the default of FMI 2.0 section 2.2.7 (table of
    /// causality × variability). `None` where `initial` is not defined (inputs, independent).
    pub fn initial(&self) -> Option<Initial> {
        self.declared_initial
            .or_else(|| fmi_standard::default_initial(self.causality, self.variability))
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

    /// Whether an importer may give it a start or parameter value: it declares a start value,
    /// is not an input (whose value comes from its connection) and not a constant.
    pub fn takes_start_value(&self) -> bool {
        self.start.is_some() && self.causality != Causality::Input && self.variability != Variability::Constant
    }
}

/// An enumeration type of `<TypeDefinitions>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Enumeration {
    pub name: String,
    /// (item name, value), in order.
    pub items: Vec<(String, i32)>,
}

/// The `<CoSimulation>` element.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct CoSimulation {
    pub model_identifier: String,
    pub can_get_and_set_fmu_state: bool,
    pub can_serialize_fmu_state: bool,
    pub provides_directional_derivative: bool,
    pub can_handle_variable_step: bool,
    pub can_interpolate_inputs: bool,
    pub max_output_derivative_order: u32,
    pub can_run_asynchronuously: bool,
}

/// The `<ModelExchange>` element.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
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
/// the error, for the caller to report.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ModelStructure {
    pub outputs: Vec<Unknown>,
    pub derivatives: Vec<Unknown>,
    pub initial_unknowns: Vec<Unknown>,
    pub errors: Vec<String>,
}

/// An FMI 2.0 model description.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelDescription {
    pub fmi_version: String,
    pub model_name: String,
    pub guid: String,
    pub description: String,
    /// `version` of the model.
    pub version: String,
    pub generation_tool: String,
    /// `numberOfEventIndicators` (0 when missing).
    pub number_of_event_indicators: usize,
    /// `<CoSimulation>`, if the FMU offers co-simulation.
    pub cs: Option<CoSimulation>,
    /// `<ModelExchange>`, if the FMU offers model exchange (it then accepts `fmi2ModelExchange`
    /// in fmi2Instantiate).
    pub me: Option<ModelExchange>,
    pub enumerations: Vec<Enumeration>,
    pub log_categories: Vec<String>,
    pub default_experiment: DefaultExperiment,
    pub variables: Vec<Variable>,
    pub model_structure: ModelStructure,
}

impl ModelDescription {
    /// Reads an FMI 2.0 description; `fmi_version` is read, not checked (a caller that takes
    /// only 2.0 says so in its own words, or reads with [`crate::parse`]).
    pub fn parse(xml: &str) -> Result<ModelDescription, String> {
        let mut events = Events::new(xml);
        let mut d = ModelDescription::default();
        // The ScalarVariable being read: its attributes, until its type element comes.
        let mut current: Option<Variable> = None;
        // Which list of <ModelStructure> the <Unknown>s belong to.
        let mut section: Option<Vec<u8>> = None;
        // Inside <SimpleType>: its name, and the enumeration being read, if it is one.
        let mut simple_type: Option<String> = None;
        let mut enumeration: Option<Enumeration> = None;
        loop {
            let (e, empty) = match events.next()? {
                Node::Eof => break,
                Node::Start(e, empty) => (e, empty),
                Node::End(name) => {
                    match name.as_slice() {
                        b"ScalarVariable" => {
                            if let Some(v) = current.take() {
                                return Err(format!("variable '{}' has no type element", v.name));
                            }
                        }
                        b"SimpleType" => {
                            simple_type = None;
                            d.enumerations.extend(enumeration.take());
                        }
                        b"Outputs" | b"Derivatives" | b"InitialUnknowns" => section = None,
                        _ => {}
                    }
                    continue;
                }
            };
            match e.name.as_slice() {
                b"fmiModelDescription" => {
                    d.fmi_version = e.string("fmiVersion").unwrap_or_default();
                    d.model_name = e.string("modelName").unwrap_or_default();
                    d.guid = e.string("guid").unwrap_or_default();
                    d.description = e.string("description").unwrap_or_default();
                    d.version = e.string("version").unwrap_or_default();
                    d.generation_tool = e.string("generationTool").unwrap_or_default();
                    d.number_of_event_indicators = e.number("numberOfEventIndicators").unwrap_or(0);
                }
                b"CoSimulation" => {
                    d.cs = Some(CoSimulation {
                        model_identifier: e.string("modelIdentifier").unwrap_or_default(),
                        can_get_and_set_fmu_state: e.flag("canGetAndSetFMUstate"),
                        can_serialize_fmu_state: e.flag("canSerializeFMUstate"),
                        provides_directional_derivative: e.flag("providesDirectionalDerivative"),
                        can_handle_variable_step: e.flag("canHandleVariableCommunicationStepSize"),
                        can_interpolate_inputs: e.flag("canInterpolateInputs"),
                        max_output_derivative_order: e.number("maxOutputDerivativeOrder").unwrap_or(0),
                        can_run_asynchronuously: e.flag("canRunAsynchronuously"),
                    })
                }
                b"ModelExchange" => {
                    d.me = Some(ModelExchange {
                        model_identifier: e.string("modelIdentifier").unwrap_or_default(),
                        can_get_and_set_fmu_state: e.flag("canGetAndSetFMUstate"),
                        can_serialize_fmu_state: e.flag("canSerializeFMUstate"),
                        provides_directional_derivative: e.flag("providesDirectionalDerivative"),
                        completed_integrator_step_not_needed: e.flag("completedIntegratorStepNotNeeded"),
                    })
                }
                b"SimpleType" if !empty => simple_type = e.string("name"),
                b"Enumeration" if simple_type.is_some() && current.is_none() => {
                    enumeration = Some(Enumeration {
                        name: simple_type.clone().unwrap_or_default(),
                        items: vec![],
                    })
                }
                b"Item" => {
                    if let Some(en) = &mut enumeration {
                        let name = e.string("name").unwrap_or_default();
                        let value = e
                            .number("value")
                            .ok_or_else(|| format!("enumeration {}: item '{name}' has no integer value", en.name))?;
                        en.items.push((name, value));
                    }
                }
                tag @ (b"Outputs" | b"Derivatives" | b"InitialUnknowns") if !empty => section = Some(tag.to_vec()),
                b"Unknown" => {
                    let at = events.here();
                    let ms = &mut d.model_structure;
                    match (e.number::<usize>("index"), e.list::<usize>("dependencies")) {
                        (None, _) => ms.errors.push(format!("{at}: an <Unknown> without a valid index")),
                        (_, Some(Err(err))) => ms.errors.push(format!("{at}: dependencies: {err}")),
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
                b"Category" => d.log_categories.push(e.string("name").unwrap_or_default()),
                b"DefaultExperiment" => d.default_experiment = DefaultExperiment::read(&e),
                b"ScalarVariable" => {
                    let name = e.string("name").ok_or("a ScalarVariable has no name")?;
                    let vr = e
                        .number("valueReference")
                        .ok_or_else(|| format!("{}: a ScalarVariable without a valid valueReference", events.here()))?;
                    let (causality, variability, declared_initial) =
                        kind(&e, &name, Version::Fmi2, Variability::Continuous)?;
                    if empty {
                        return Err(format!("variable '{name}' has no type element"));
                    }
                    current = Some(Variable {
                        name,
                        vr,
                        ty: Type::Real,
                        causality,
                        variability,
                        declared_initial,
                        start: None,
                        min: None,
                        max: None,
                        derivative: None,
                        declared_type: None,
                        unit: None,
                        description: e.string("description"),
                    });
                }
                tag => {
                    if let Some(ty) = Type::from_element(tag)
                        && let Some(mut v) = current.take()
                    {
                        v.ty = ty;
                        v.start = e.string("start");
                        v.min = e.number("min");
                        v.max = e.number("max");
                        v.derivative = e.number("derivative");
                        v.declared_type = e.string("declaredType");
                        v.unit = e.string("unit");
                        d.variables.push(v);
                    }
                }
            }
        }
        for v in &d.variables {
            if v.ty == Type::Enumeration && d.enumeration_of(v).is_none() {
                return Err(format!(
                    "Enumeration variable '{}' has no declaredType of TypeDefinitions",
                    v.name
                ));
            }
        }
        Ok(d)
    }

    /// modelIdentifier of `<CoSimulation>`, else of `<ModelExchange>` (empty with neither).
    pub fn model_identifier(&self) -> &str {
        match (&self.cs, &self.me) {
            (Some(cs), _) => &cs.model_identifier,
            (None, Some(me)) => &me.model_identifier,
            (None, None) => "",
        }
    }

    pub fn of_type(&self, ty: Type) -> impl Iterator<Item = &Variable> {
        self.variables.iter().filter(move |v| v.ty == ty)
    }

    pub fn vrs_of_type(&self, ty: Type) -> Vec<u32> {
        self.of_type(ty).map(|v| v.vr).collect()
    }

    /// The variable of that name.
    pub fn variable(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// The enumeration type of an Enumeration variable.
    pub fn enumeration_of(&self, v: &Variable) -> Option<&Enumeration> {
        let t = v.declared_type.as_deref()?;
        self.enumerations.iter().find(|e| e.name == t)
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
                if state.ty != Type::Real || state.variability != Variability::Continuous {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A co-simulation and model-exchange description: an enumeration type, a state and its
    /// derivative, an input, an output that depends on it, a tunable parameter.
    const XML: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Lag" guid="{1}" description="a lag" version="0.1.0" generationTool="hand" numberOfEventIndicators="0">
  <ModelExchange modelIdentifier="Lag" providesDirectionalDerivative="true" completedIntegratorStepNotNeeded="true"/>
  <CoSimulation modelIdentifier="Lag" canGetAndSetFMUstate="true" canHandleVariableCommunicationStepSize="true" maxOutputDerivativeOrder="0"/>
  <TypeDefinitions>
    <SimpleType name="Angle"><Real unit="rad"/></SimpleType>
    <SimpleType name="Mode">
      <Enumeration><Item name="LQR" value="1"/><Item name="PID" value=" 2 "/></Enumeration>
    </SimpleType>
  </TypeDefinitions>
  <LogCategories><Category name="logAll"/><Category name="logError"/></LogCategories>
  <DefaultExperiment startTime="0.0" stopTime="2.0" stepSize="1e-3"/>
  <ModelVariables>
    <!-- index 1 -->
    <ScalarVariable name="y" valueReference="1" causality="output" initial="exact"><Real start="0.5" unit="m"/></ScalarVariable>
    <ScalarVariable name="der(y)" valueReference="3"><Real derivative="1"/></ScalarVariable>
    <ScalarVariable name="u" valueReference="0" causality="input" description="the input"><Real start="0" min="-1" max="1"/></ScalarVariable>
    <ScalarVariable name="T" valueReference="2" causality="parameter" variability="tunable"><Real start="0.1"/></ScalarVariable>
    <ScalarVariable name="mode" valueReference="20" causality="parameter" variability="fixed"><Enumeration declaredType="Mode" start="1"/></ScalarVariable>
    <ScalarVariable name="n" valueReference="21" causality="local" variability="discrete"><Integer/></ScalarVariable>
  </ModelVariables>
  <ModelStructure>
    <Outputs><Unknown index="1" dependencies=""/></Outputs>
    <Derivatives><Unknown index="2" dependencies="1 3"/></Derivatives>
    <InitialUnknowns><Unknown index="2"/></InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>"#;

    fn lag() -> ModelDescription {
        ModelDescription::parse(XML).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn the_root_and_the_interfaces_are_read() {
        let d = lag();
        assert_eq!(
            (
                d.fmi_version.as_str(),
                d.model_name.as_str(),
                d.guid.as_str(),
                d.version.as_str()
            ),
            ("2.0", "Lag", "{1}", "0.1.0")
        );
        assert_eq!((d.description.as_str(), d.generation_tool.as_str()), ("a lag", "hand"));
        let cs = d.cs.as_ref().unwrap();
        assert!(cs.can_get_and_set_fmu_state && cs.can_handle_variable_step && !cs.can_serialize_fmu_state);
        let me = d.me.as_ref().unwrap();
        assert!(me.provides_directional_derivative && me.completed_integrator_step_not_needed);
        assert_eq!(d.model_identifier(), "Lag");
        assert_eq!(d.log_categories, ["logAll", "logError"]);
        assert_eq!(d.default_experiment.step_size.as_deref(), Some("1e-3"));
        assert_eq!(d.default_experiment.step_size(), Some(1e-3));
        assert_eq!(d.default_experiment.tolerance(), None);
    }

    #[test]
    fn variables_are_read_with_the_defaults_of_the_standard() {
        let d = lag();
        let names: Vec<&str> = d.variables.iter().map(|v| v.name.as_str()).collect();
        assert_eq!(names, ["y", "der(y)", "u", "T", "mode", "n"]);
        let y = d.variable("y").unwrap();
        assert_eq!((y.vr, y.ty, y.causality), (1, Type::Real, Causality::Output));
        assert_eq!(
            (y.start_real(), y.unit.as_deref(), y.initial()),
            (Some(0.5), Some("m"), Some(Initial::Exact))
        );
        // causality local, variability continuous, initial calculated: the defaults
        let der = d.variable("der(y)").unwrap();
        assert_eq!(
            (der.causality, der.variability, der.initial(), der.derivative),
            (
                Causality::Local,
                Variability::Continuous,
                Some(Initial::Calculated),
                Some(1)
            )
        );
        let u = d.variable("u").unwrap();
        assert_eq!((u.min, u.max, u.initial()), (Some(-1.0), Some(1.0), None));
        assert_eq!(u.description.as_deref(), Some("the input"));
        assert!(d.variable("T").unwrap().takes_start_value() && !u.takes_start_value());
        assert_eq!(d.variable("T").unwrap().initial(), Some(Initial::Exact));
        assert_eq!(d.vrs_of_type(Type::Real), [1, 3, 0, 2]);
        assert_eq!(d.unknown_vr(), 1021);
        assert!(d.variable("nope").is_none());
    }

    #[test]
    fn an_enumeration_variable_has_the_items_of_its_type() {
        let d = lag();
        let mode = d.variable("mode").unwrap();
        assert_eq!(
            (mode.ty, mode.causality, mode.vr, mode.start.as_deref()),
            (Type::Enumeration, Causality::Parameter, 20, Some("1"))
        );
        assert_eq!(
            d.enumeration_of(mode).unwrap().items,
            [("LQR".into(), 1), ("PID".into(), 2)]
        );
        // The Real of the SimpleType "Angle" is no variable; the Integer after mode is one.
        assert_eq!(d.variable("n").unwrap().ty, Type::Integer);
        assert_eq!(d.enumerations.len(), 1);
    }

    #[test]
    fn the_model_structure_gives_the_states_in_order() {
        let d = lag();
        let ms = &d.model_structure;
        assert_eq!(
            ms.outputs,
            [Unknown {
                index: 1,
                dependencies: Some(vec![])
            }]
        );
        assert_eq!(ms.derivatives[0].dependencies, Some(vec![1, 3]));
        assert_eq!(ms.initial_unknowns[0].dependencies, None);
        let states = d.continuous_states().unwrap();
        assert_eq!((states[0].0.name.as_str(), states[0].1.name.as_str()), ("y", "der(y)"));
        assert_eq!(d.number_of_continuous_states(), 1);
        assert_eq!(d.by_index(3).unwrap().name, "u");
        assert!(d.by_index(0).is_none());
    }

    #[test]
    fn an_unknown_that_does_not_parse_is_kept_as_an_error() {
        let xml = XML.replace(r#"dependencies="1 3""#, r#"dependencies="1 x""#);
        let d = ModelDescription::parse(&xml).unwrap();
        assert!(
            d.model_structure.errors[0].contains("dependencies: invalid digit"),
            "{:?}",
            d.model_structure.errors
        );
        assert!(
            d.model_structure.errors[0].starts_with("modelDescription.xml:24:57:"),
            "{:?}",
            d.model_structure.errors
        );
        assert!(d.continuous_states().is_err());
    }

    #[test]
    fn what_no_importer_could_use_is_refused_with_its_reason() {
        let bad = |from: &str, to: &str| {
            assert!(XML.contains(from), "{from}");
            ModelDescription::parse(&XML.replacen(from, to, 1)).unwrap_err()
        };
        assert_eq!(
            bad(r#"causality="input""#, r#"causality="sideways""#),
            "variable 'u': unknown causality 'sideways'"
        );
        assert_eq!(
            bad(r#"causality="input""#, r#"causality="structuralParameter""#),
            "variable 'u': unknown causality 'structuralParameter'"
        );
        assert_eq!(
            bad(r#"variability="tunable""#, r#"variability="often""#),
            "variable 'T': unknown variability 'often'"
        );
        assert_eq!(
            bad(r#"initial="exact""#, r#"initial="maybe""#),
            "variable 'y': unknown initial 'maybe'"
        );
        assert_eq!(bad(r#"<Real start="0.1"/>"#, ""), "variable 'T' has no type element");
        assert_eq!(
            bad(r#"valueReference="2""#, r#"valueReference="two""#),
            "modelDescription.xml:18:95: a ScalarVariable without a valid valueReference"
        );
        assert_eq!(
            bad(r#"name="LQR" value="1""#, r#"name="LQR""#),
            "enumeration Mode: item 'LQR' has no integer value"
        );
        assert_eq!(
            bad(r#"declaredType="Mode""#, r#"declaredType="Nope""#),
            "Enumeration variable 'mode' has no declaredType of TypeDefinitions"
        );
        assert!(bad("</ModelVariables>", "</ModelVariable>").starts_with("modelDescription.xml:21:"));
    }

    #[test]
    fn a_model_exchange_fmu_is_named_by_its_model_exchange_element() {
        let xml = XML.replace(
            r#"<CoSimulation modelIdentifier="Lag""#,
            r#"<Other modelIdentifier="X""#,
        );
        let d = ModelDescription::parse(&xml).unwrap();
        assert!(d.cs.is_none());
        assert_eq!(d.model_identifier(), "Lag");
    }
}
