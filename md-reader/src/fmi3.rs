//! An FMI 3.0 `modelDescription.xml` (FMI 3.0 section 2.4): the interfaces and their flags, the
//! variables (one element per type: `<Float64>`, `<Int32>`, ...), the model structure (by value
//! reference), the log categories and the default experiment.

use crate::common::{DefaultExperiment, kind};
use crate::read::{Events, Node};
use crate::{Causality, Initial, Variability, Version};
use std::fmt;

/// The element of a variable: its type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Type {
    Float32,
    Float64,
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    Boolean,
    String,
    Binary,
    Enumeration,
    Clock,
}

impl Type {
    pub const ALL: [Type; 15] = [
        Type::Float32,
        Type::Float64,
        Type::Int8,
        Type::UInt8,
        Type::Int16,
        Type::UInt16,
        Type::Int32,
        Type::UInt32,
        Type::Int64,
        Type::UInt64,
        Type::Boolean,
        Type::String,
        Type::Binary,
        Type::Enumeration,
        Type::Clock,
    ];

    /// Its element name.
    pub fn name(self) -> &'static str {
        match self {
            Type::Float32 => "Float32",
            Type::Float64 => "Float64",
            Type::Int8 => "Int8",
            Type::UInt8 => "UInt8",
            Type::Int16 => "Int16",
            Type::UInt16 => "UInt16",
            Type::Int32 => "Int32",
            Type::UInt32 => "UInt32",
            Type::Int64 => "Int64",
            Type::UInt64 => "UInt64",
            Type::Boolean => "Boolean",
            Type::String => "String",
            Type::Binary => "Binary",
            Type::Enumeration => "Enumeration",
            Type::Clock => "Clock",
        }
    }

    pub fn from_element(name: &[u8]) -> Option<Type> {
        Type::ALL.into_iter().find(|t| t.name().as_bytes() == name)
    }

    /// Float32 or Float64: the types that may be continuous.
    pub fn is_float(self) -> bool {
        matches!(self, Type::Float32 | Type::Float64)
    }
}

impl fmt::Display for Type {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    pub name: String,
    pub vr: u32,
    pub ty: Type,
    pub causality: Causality,
    pub variability: Variability,
    /// `initial` as written; [`Variable::initial`] is the one in force.
    pub declared_initial: Option<Initial>,
    /// The `start` attribute as written (of a String or Binary: the first `<Start value>`).
    pub start: Option<String>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// `derivative`: the value reference of the variable this one is the derivative of.
    pub derivative: Option<u32>,
    /// `<Dimension>` children: an array variable.
    pub array: bool,
    /// A Binary's `maxSize` (bytes).
    pub max_size: Option<u64>,
    /// A Binary's `mimeType` as written (`application/octet-stream` when absent).
    pub mime_type: Option<String>,
    /// The `<Dimension>`s of an array, outermost first: the fixed size (`start`), or the value
    /// reference of the structural parameter that sets it.
    pub dimensions: Vec<Dimension>,
    pub declared_type: Option<String>,
    pub unit: Option<String>,
    /// `displayUnit`: one of the `<DisplayUnit>`s of its unit.
    pub display_unit: Option<String>,
    pub description: Option<String>,
    /// The `<Alias>` children: other names of the variable (FMI 3.0, 2.4.7.3).
    pub aliases: Vec<Alias>,
    /// `clocks`: the value references of the clocks of a clocked variable (empty: not clocked).
    pub clocks: Vec<u32>,
    /// A Clock's `intervalVariability`, `intervalDecimal`, `shiftDecimal`, `canBeDeactivated`.
    pub clock: Option<ClockAttrs>,
    /// `intermediateUpdate`: the variable may be got or set in Intermediate Update Mode.
    pub intermediate_update: bool,
}

/// An `<Alias>` of a variable.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Alias {
    pub name: String,
    pub description: Option<String>,
    pub display_unit: Option<String>,
}

/// A `<Unit>` of `<UnitDefinitions>`: its name and its `<DisplayUnit>`s (the base units are not
/// read).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Unit {
    pub name: String,
    pub display_units: Vec<DisplayUnit>,
}

/// A `<DisplayUnit>`: a value `v` of its unit is shown as `factor · v + offset`, or, `inverse`,
/// as `factor / v`.
#[derive(Debug, Clone, PartialEq)]
pub struct DisplayUnit {
    pub name: String,
    pub factor: f64,
    pub offset: f64,
    pub inverse: bool,
}

/// The attributes of a `<Clock>` (FMI 3.0, 2.4.7.6).
#[derive(Debug, Clone, PartialEq)]
pub struct ClockAttrs {
    pub interval_variability: String,
    pub interval_decimal: Option<f64>,
    pub shift_decimal: Option<f64>,
    pub can_be_deactivated: bool,
    /// `priority` (Scheduled Execution: 0 the highest; required there for input clocks).
    pub priority: Option<u32>,
}

impl Variable {
    /// The `initial` in force: written, or the default of the FMI 3.0 table (causality ×
    /// variability, section 2.4.7.4). `None` where it is not defined.
    pub fn initial(&self) -> Option<Initial> {
        self.declared_initial
            .or_else(|| fmi_standard::default_initial(self.causality, self.variability))
    }
}

/// An `<EnumerationType>` of `<TypeDefinitions>` (FMI 3.0, 2.4.6.4): what an Enumeration
/// variable's `declaredType` names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Enumeration {
    pub name: String,
    /// (item name, value), in order; an FMI 3.0 item's value is an Int64.
    pub items: Vec<(String, i64)>,
}

/// One `<Dimension>` of an array variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    Fixed(u64),
    /// `valueReference` of a structural parameter.
    Parameter(u32),
}

impl Variable {
    /// The number of values of the variable where its size is fixed: 1 for a scalar, the
    /// product of the fixed dimensions for an array (`None` when a structural parameter sets one).
    pub fn fixed_count(&self) -> Option<u64> {
        self.dimensions.iter().try_fold(1u64, |n, d| match d {
            Dimension::Fixed(k) => n.checked_mul(*k),
            Dimension::Parameter(_) => None,
        })
    }
}

/// `<CoSimulation>` or `<ModelExchange>` (the flags one of them lacks stay false).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
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
    /// `mightReturnEarlyFromDoStep` (Co-Simulation): with earlyReturnAllowed, fmi3DoStep may end
    /// a step early of its own accord.
    pub might_return_early: bool,
    /// `providesPerElementDependencies`: fmi3GetNumberOfVariableDependencies and
    /// fmi3GetVariableDependencies are offered.
    pub provides_per_element_dependencies: bool,
    /// `providesEvaluateDiscreteStates` (Model Exchange): fmi3EvaluateDiscreteStates is offered.
    pub provides_evaluate_discrete_states: bool,
}

/// One element of `<ModelStructure>` (`<Output>`, `<ContinuousStateDerivative>`,
/// `<InitialUnknown>`, `<EventIndicator>`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unknown {
    pub vr: u32,
    /// Value references it depends on; `None` when the attribute is missing.
    pub dependencies: Option<Vec<u32>>,
}

/// An FMI 3.0 model description.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelDescription {
    pub fmi_version: String,
    pub model_name: String,
    /// `instantiationToken`.
    pub token: String,
    pub description: String,
    /// `version` of the model.
    pub version: String,
    pub generation_tool: String,
    pub cs: Option<Interface>,
    pub me: Option<Interface>,
    /// Whether it has `<ScheduledExecution>`.
    pub se: bool,
    /// The `<ScheduledExecution>` element's attributes (modelIdentifier, canGetAndSetFMUState,
    /// canSerializeFMUState), where it has one.
    pub se_interface: Option<Interface>,
    pub log_categories: Vec<String>,
    pub default_experiment: DefaultExperiment,
    /// `<UnitDefinitions>`.
    pub units: Vec<Unit>,
    /// The `<EnumerationType>`s of `<TypeDefinitions>`.
    pub enumerations: Vec<Enumeration>,
    pub variables: Vec<Variable>,
    pub outputs: Vec<Unknown>,
    pub derivatives: Vec<Unknown>,
    pub initial_unknowns: Vec<Unknown>,
    pub event_indicators: Vec<Unknown>,
    /// The elements of `<ModelStructure>` that do not parse, for the caller to report.
    pub errors: Vec<String>,
}

impl ModelDescription {
    /// Reads an FMI 3.0 description. A description with none of `<CoSimulation>`,
    /// `<ModelExchange>` and `<ScheduledExecution>` is refused (it offers no interface to run;
    /// each is optional in fmi3ModelDescription.xsd). One of Scheduled Execution only is read (`cs` and `me`
    /// None, `se` true): a tool that runs co-simulation or model exchange refuses it itself.
    pub fn parse(xml: &str) -> Result<ModelDescription, String> {
        let mut events = Events::new(xml);
        let mut d = ModelDescription::default();
        // The variable being read (its <Start>/<Dimension> children follow).
        let mut open: Option<usize> = None;
        let mut in_variables = false;
        // Inside an <EnumerationType>: its <Item>s follow.
        let mut in_enumeration = false;
        loop {
            let (e, empty) = match events.next()? {
                Node::Eof => break,
                Node::Start(e, empty) => (e, empty),
                Node::End(name) => {
                    if Type::from_element(&name).is_some() {
                        open = None;
                    }
                    if name == b"ModelVariables" {
                        in_variables = false;
                    }
                    if name == b"EnumerationType" {
                        in_enumeration = false;
                    }
                    continue;
                }
            };
            let interface = || Interface {
                model_identifier: e.string("modelIdentifier").unwrap_or_default(),
                can_get_and_set_fmu_state: e.flag("canGetAndSetFMUState"),
                can_serialize_fmu_state: e.flag("canSerializeFMUState"),
                provides_directional_derivatives: e.flag("providesDirectionalDerivatives"),
                provides_adjoint_derivatives: e.flag("providesAdjointDerivatives"),
                has_event_mode: e.flag("hasEventMode"),
                can_handle_variable_step: e.flag("canHandleVariableCommunicationStepSize"),
                max_output_derivative_order: e.number("maxOutputDerivativeOrder").unwrap_or(0),
                provides_intermediate_update: e.flag("providesIntermediateUpdate"),
                can_return_early: e.flag("canReturnEarlyAfterIntermediateUpdate"),
                might_return_early: e.flag("mightReturnEarlyFromDoStep"),
                provides_per_element_dependencies: e.flag("providesPerElementDependencies"),
                provides_evaluate_discrete_states: e.flag("providesEvaluateDiscreteStates"),
            };
            if in_variables && let Some(ty) = Type::from_element(&e.name) {
                let vr = e
                    .number("valueReference")
                    .ok_or_else(|| format!("{}: a <{ty}> without a valid valueReference", events.here()))?;
                let name = e.string("name").unwrap_or_default();
                // A variable of a type other than Float is discrete by default.
                let default_variability = if ty.is_float() {
                    Variability::Continuous
                } else {
                    Variability::Discrete
                };
                let (causality, variability, declared_initial) = kind(&e, &name, Version::Fmi3, default_variability)?;
                d.variables.push(Variable {
                    name,
                    vr,
                    ty,
                    causality,
                    variability,
                    declared_initial,
                    // A String's or Binary's start values are <Start> children.
                    start: if matches!(ty, Type::String | Type::Binary) {
                        None
                    } else {
                        e.string("start")
                    },
                    min: e.number("min"),
                    max: e.number("max"),
                    derivative: e.number("derivative"),
                    array: false,
                    max_size: e.number("maxSize"),
                    mime_type: e.string("mimeType"),
                    dimensions: Vec::new(),
                    declared_type: e.string("declaredType"),
                    unit: e.string("unit"),
                    display_unit: e.string("displayUnit"),
                    description: e.string("description"),
                    aliases: Vec::new(),
                    clock: (ty == Type::Clock).then(|| ClockAttrs {
                        interval_variability: e.string("intervalVariability").unwrap_or_default(),
                        interval_decimal: e.number("intervalDecimal"),
                        shift_decimal: e.number("shiftDecimal"),
                        can_be_deactivated: e.string("canBeDeactivated").as_deref() == Some("true"),
                        priority: e.number("priority"),
                    }),
                    clocks: e
                        .string("clocks")
                        .map(|s| s.split_whitespace().filter_map(|x| x.parse().ok()).collect())
                        .unwrap_or_default(),
                    intermediate_update: e.flag("intermediateUpdate"),
                });
                open = (!empty).then_some(d.variables.len() - 1);
                continue;
            }
            match e.name.as_slice() {
                b"fmiModelDescription" => {
                    d.fmi_version = e.string("fmiVersion").unwrap_or_default();
                    d.model_name = e.string("modelName").unwrap_or_default();
                    d.token = e.string("instantiationToken").unwrap_or_default();
                    d.description = e.string("description").unwrap_or_default();
                    d.version = e.string("version").unwrap_or_default();
                    d.generation_tool = e.string("generationTool").unwrap_or_default();
                }
                b"CoSimulation" => d.cs = Some(interface()),
                b"ModelExchange" => d.me = Some(interface()),
                b"ScheduledExecution" => {
                    d.se = true;
                    d.se_interface = Some(interface());
                }
                b"ModelVariables" => in_variables = !empty,
                b"EnumerationType" => {
                    d.enumerations.push(Enumeration {
                        name: e.string("name").unwrap_or_default(),
                        items: Vec::new(),
                    });
                    in_enumeration = !empty;
                }
                b"Item" if in_enumeration => {
                    let en = d.enumerations.last_mut().expect("in an EnumerationType");
                    let name = e.string("name").unwrap_or_default();
                    let value = e.number("value").ok_or_else(|| {
                        format!(
                            "{}: EnumerationType {}: item '{name}' has no Int64 value",
                            events.here(),
                            en.name
                        )
                    })?;
                    en.items.push((name, value));
                }
                b"Category" => d.log_categories.push(e.string("name").unwrap_or_default()),
                b"DefaultExperiment" => d.default_experiment = DefaultExperiment::read(&e),
                b"Start" => {
                    if let Some(i) = open {
                        d.variables[i].start = e.string("value");
                    }
                }
                b"Alias" => {
                    if let Some(i) = open {
                        d.variables[i].aliases.push(Alias {
                            name: e.string("name").unwrap_or_default(),
                            description: e.string("description"),
                            display_unit: e.string("displayUnit"),
                        });
                    }
                }
                b"Unit" if !in_variables => d.units.push(Unit {
                    name: e.string("name").unwrap_or_default(),
                    display_units: Vec::new(),
                }),
                b"DisplayUnit" => {
                    if let Some(u) = d.units.last_mut() {
                        u.display_units.push(DisplayUnit {
                            name: e.string("name").unwrap_or_default(),
                            factor: e.number("factor").unwrap_or(1.0),
                            offset: e.number("offset").unwrap_or(0.0),
                            inverse: e.string("inverse").as_deref() == Some("true"),
                        });
                    }
                }
                b"Dimension" => {
                    if let Some(i) = open {
                        d.variables[i].array = true;
                        let dim = match (e.number("start"), e.number("valueReference")) {
                            (Some(n), _) => Dimension::Fixed(n),
                            (None, Some(vr)) => Dimension::Parameter(vr),
                            (None, None) => Dimension::Fixed(0),
                        };
                        d.variables[i].dimensions.push(dim);
                    }
                }
                tag @ (b"Output" | b"ContinuousStateDerivative" | b"InitialUnknown" | b"EventIndicator") => {
                    let at = events.here();
                    match (e.number::<u32>("valueReference"), e.list::<u32>("dependencies")) {
                        (None, _) => d.errors.push(format!(
                            "{at}: <{}> without a valid valueReference",
                            String::from_utf8_lossy(tag)
                        )),
                        (_, Some(Err(err))) => d.errors.push(format!("{at}: dependencies: {err}")),
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
                _ => {}
            }
        }
        if d.cs.is_none() && d.me.is_none() && !d.se {
            return Err(
                "modelDescription.xml: none of <CoSimulation>, <ModelExchange> and <ScheduledExecution>".into(),
            );
        }
        Ok(d)
    }

    /// The model identifier (of CoSimulation, else of ModelExchange, else of
    /// ScheduledExecution).
    pub fn model_identifier(&self) -> &str {
        self.cs
            .as_ref()
            .or(self.me.as_ref())
            .or(self.se_interface.as_ref())
            .map(|i| i.model_identifier.as_str())
            .unwrap_or("")
    }

    /// Whether the FMU declares Scheduled Execution and neither co-simulation nor model exchange.
    pub fn scheduled_execution_only(&self) -> bool {
        self.se && self.cs.is_none() && self.me.is_none()
    }

    /// The scalar (not array) variables of that type that are not clocked (a clocked variable
    /// is read and set while one of its clocks ticks only: `clocks`).
    pub fn of_type(&self, ty: Type) -> impl Iterator<Item = &Variable> {
        self.variables
            .iter()
            .filter(move |v| v.ty == ty && !v.array && v.clocks.is_empty())
    }

    pub fn vrs_of_type(&self, ty: Type) -> Vec<u32> {
        self.of_type(ty).map(|v| v.vr).collect()
    }

    /// The `<EnumerationType>` an Enumeration variable's `declaredType` names.
    pub fn enumeration_of(&self, v: &Variable) -> Option<&Enumeration> {
        let t = v.declared_type.as_deref()?;
        self.enumerations.iter().find(|e| e.name == t)
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
                if !state.ty.is_float() || state.variability != Variability::Continuous {
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
        self.variables.iter().find(|v| v.causality == Causality::Independent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const XML: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="Lag" instantiationToken="{t}" generationTool="hand">
  <ModelExchange modelIdentifier="LagME" providesDirectionalDerivatives="true"/>
  <CoSimulation modelIdentifier="Lag" canGetAndSetFMUState="true" providesAdjointDerivatives="true" hasEventMode="true"/>
  <LogCategories><Category name="logEvents"/></LogCategories>
  <DefaultExperiment stopTime="1.0"/>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent"/>
    <Float64 name="y" valueReference="1" causality="output" start="0.5" unit="m"/>
    <Float64 name="der(y)" valueReference="3" derivative="1"/>
    <Float64 name="u" valueReference="2" causality="input" start="0" min="-1" max="1"/>
    <Int32 name="n" valueReference="4" causality="parameter" variability="tunable" start="3"/>
    <Boolean name="on" valueReference="5" causality="output"/>
    <String name="label" valueReference="6" causality="parameter" variability="fixed"><Start value="hi"/></String>
    <Float64 name="v" valueReference="7" causality="parameter" variability="fixed" start="1 2"><Dimension start="2"/></Float64>
    <Float32 name="k" valueReference="8" causality="structuralParameter" variability="fixed" start="1"/>
  </ModelVariables>
  <ModelStructure>
    <Output valueReference="1" dependencies=""/>
    <Output valueReference="5"/>
    <ContinuousStateDerivative valueReference="3" dependencies="1 2"/>
    <InitialUnknown valueReference="3"/>
  </ModelStructure>
</fmiModelDescription>"#;

    fn lag() -> ModelDescription {
        ModelDescription::parse(XML).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn the_root_and_the_interfaces_are_read() {
        let d = lag();
        assert_eq!(
            (d.fmi_version.as_str(), d.token.as_str(), d.model_name.as_str()),
            ("3.0", "{t}", "Lag")
        );
        let cs = d.cs.as_ref().unwrap();
        assert!(cs.can_get_and_set_fmu_state && cs.provides_adjoint_derivatives && cs.has_event_mode);
        assert!(d.me.as_ref().unwrap().provides_directional_derivatives && !d.se);
        assert_eq!(d.model_identifier(), "Lag");
        assert_eq!(d.log_categories, ["logEvents"]);
        assert_eq!(d.default_experiment.stop_time(), Some(1.0));
        assert_eq!(d.independent().unwrap().name, "time");
    }

    #[test]
    fn variables_are_read_with_the_defaults_of_their_type() {
        let d = lag();
        assert_eq!(d.variables.len(), 9);
        let der = d.by_vr(3).unwrap();
        assert_eq!(
            (der.ty, der.causality, der.variability, der.initial(), der.derivative),
            (
                Type::Float64,
                Causality::Local,
                Variability::Continuous,
                Some(Initial::Calculated),
                Some(1)
            )
        );
        // A type other than Float is discrete by default.
        assert_eq!(d.by_vr(5).unwrap().variability, Variability::Discrete);
        let n = d.by_vr(4).unwrap();
        assert_eq!(
            (n.ty, n.start.as_deref(), n.initial()),
            (Type::Int32, Some("3"), Some(Initial::Exact))
        );
        assert_eq!(d.by_vr(6).unwrap().start.as_deref(), Some("hi"));
        assert_eq!(d.by_vr(8).unwrap().causality, Causality::StructuralParameter);
        // The array is no scalar of its type.
        assert!(d.by_vr(7).unwrap().array);
        assert_eq!(d.vrs_of_type(Type::Float64), [0, 1, 3, 2]);
        assert_eq!(d.by_vr(1).unwrap().unit.as_deref(), Some("m"));
        assert_eq!(d.unknown_vr(), 1008);
    }

    #[test]
    fn the_model_structure_is_read_by_value_reference() {
        let d = lag();
        assert_eq!(
            d.outputs[0],
            Unknown {
                vr: 1,
                dependencies: Some(vec![])
            }
        );
        assert_eq!(d.outputs[1].dependencies, None);
        assert_eq!(d.continuous_states().unwrap(), [(1, 3)]);
        assert_eq!(d.initial_unknowns.len(), 1);
        let bad = ModelDescription::parse(&XML.replace(r#"<Output valueReference="5"/>"#, r#"<Output/>"#)).unwrap();
        assert!(
            bad.errors[0].ends_with("<Output> without a valid valueReference"),
            "{:?}",
            bad.errors
        );
        assert!(bad.continuous_states().is_err());
    }

    #[test]
    fn what_no_importer_could_use_is_refused() {
        let bad = |from: &str, to: &str| {
            assert!(XML.contains(from), "{from}");
            ModelDescription::parse(&XML.replacen(from, to, 1)).unwrap_err()
        };
        assert_eq!(
            bad(r#"valueReference="4""#, ""),
            "modelDescription.xml:12:77: a <Int32> without a valid valueReference"
        );
        assert_eq!(
            bad(r#"causality="output" start"#, r#"causality="out" start"#),
            "variable 'y': unknown causality 'out'"
        );
        let none = XML
            .replace(r#"<ModelExchange modelIdentifier="LagME""#, "<X")
            .replace(r#"<CoSimulation modelIdentifier="Lag""#, "<Y");
        assert_eq!(
            ModelDescription::parse(&none).unwrap_err(),
            "modelDescription.xml: none of <CoSimulation>, <ModelExchange> and <ScheduledExecution>"
        );
        // Scheduled Execution alone (as the Reference-FMUs' Clocks, v0.0.41) is read, its
        // identifier the element's.
        let se = none.replacen("<Y", r#"<ScheduledExecution modelIdentifier="LagSE""#, 1);
        let d = ModelDescription::parse(&se).unwrap();
        assert!(d.cs.is_none() && d.me.is_none() && d.se && d.scheduled_execution_only());
        assert_eq!(d.model_identifier(), "LagSE");
    }

    #[test]
    fn aliases_and_display_units_are_read() {
        // The Reference-FMUs' BouncingBall's h (v0.0.41), its unit and its alias in feet.
        let xml = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="B" instantiationToken="{t}">
  <CoSimulation modelIdentifier="B"/>
  <UnitDefinitions>
    <Unit name="m"><BaseUnit m="1"/><DisplayUnit name="ft" factor="3.280839895"/></Unit>
    <Unit name="S"><BaseUnit kg="-1" m="-2" s="3" A="2"/><DisplayUnit name="Ohm" inverse="true"/></Unit>
  </UnitDefinitions>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent"/>
    <Float64 name="h" valueReference="1" causality="output" unit="m" displayUnit="ft">
      <Alias name="h_ft" description="Position in feet" displayUnit="ft"/>
      <Alias name="height"/>
    </Float64>
    <Float64 name="v" valueReference="3" causality="output"/>
  </ModelVariables>
  <ModelStructure><Output valueReference="1"/><Output valueReference="3"/></ModelStructure>
</fmiModelDescription>"#;
        let d = ModelDescription::parse(xml).unwrap();
        let h = d.by_vr(1).unwrap();
        assert_eq!(h.display_unit.as_deref(), Some("ft"));
        assert_eq!(
            h.aliases,
            [
                Alias {
                    name: "h_ft".into(),
                    description: Some("Position in feet".into()),
                    display_unit: Some("ft".into()),
                },
                Alias {
                    name: "height".into(),
                    description: None,
                    display_unit: None,
                },
            ]
        );
        assert!(d.by_vr(3).unwrap().aliases.is_empty(), "the next variable has none");
        let units: Vec<_> = d
            .units
            .iter()
            .map(|u| (u.name.as_str(), u.display_units.clone()))
            .collect();
        let shown = |name: &str, factor, inverse| DisplayUnit {
            name: name.into(),
            factor,
            offset: 0.0,
            inverse,
        };
        assert_eq!(
            units,
            [
                ("m", vec![shown("ft", 3.280839895, false)]),
                ("S", vec![shown("Ohm", 1.0, true)])
            ]
        );
    }

    #[test]
    fn enumeration_types_and_dimensions_are_read() {
        // The Reference-FMUs' Feedthrough (Option) and StateSpace (y of r outputs), v0.0.41.
        let xml = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="E" instantiationToken="{t}">
  <CoSimulation modelIdentifier="E"/>
  <TypeDefinitions>
    <Float64Type name="Angle" unit="rad"/>
    <EnumerationType name="Option">
      <Item name="Option 1" value="1" description="First option"/>
      <Item name="Option 2" value=" 2 "/>
    </EnumerationType>
    <EnumerationType name="Empty"/>
  </TypeDefinitions>
  <ModelVariables>
    <UInt64 name="r" valueReference="3" causality="structuralParameter" variability="tunable" start="3"/>
    <Enumeration name="e" valueReference="1" causality="output" declaredType="Option"/>
    <Float64 name="y" valueReference="10" causality="output"><Dimension valueReference="3"/><Dimension start="2"/></Float64>
  </ModelVariables>
</fmiModelDescription>"#;
        let d = ModelDescription::parse(xml).unwrap();
        let item = |n: &str, v| (n.to_string(), v);
        assert_eq!(
            d.enumerations,
            [
                Enumeration {
                    name: "Option".into(),
                    items: vec![item("Option 1", 1), item("Option 2", 2)]
                },
                Enumeration {
                    name: "Empty".into(),
                    items: vec![]
                }
            ]
        );
        assert_eq!(
            d.enumeration_of(d.by_vr(1).unwrap()).map(|e| e.name.as_str()),
            Some("Option")
        );
        let y = d.by_vr(10).unwrap();
        assert!(y.array);
        assert_eq!(y.dimensions, [Dimension::Parameter(3), Dimension::Fixed(2)]);
        let e = ModelDescription::parse(&xml.replace(r#"value=" 2 ""#, r#"value="two""#)).unwrap_err();
        assert!(
            e.contains("EnumerationType Option: item 'Option 2' has no Int64 value"),
            "{e}"
        );
    }
}
