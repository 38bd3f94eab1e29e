//! `modelDescription.xml` of FMI 3.0.

use super::arrays::{active_items, array_sizes};
use super::sections::definitions;
use super::{
    Xml, bound_value, check_description, close, document, empty, finish, interface, lower_camel, of_version, open,
    real_text, root_attributes,
};
use rustfmu::description::{
    Bound, Causality, FmiVersion, Interfaces, ModelDescription, NOT_SIZED, Start, VarType, Variable,
};
use std::collections::BTreeSet;

/// `modelDescription.xml` (FMI 3.0) of a description, in the element order of the FMI 3.0 XSD
/// (`fmi3ModelDescription.xsd`). `token` is the `instantiationToken`: the GUID of the FMI 3.0
/// binary's encoding. Variables are referred to by value reference throughout (`derivative`,
/// `ModelStructure`); the independent variable `time` is listed first unless the model declares
/// its own.
pub fn fmi3(d: &ModelDescription, interfaces: Interfaces, token: &str) -> Result<String, String> {
    of_version(d, interfaces, FmiVersion::V3)?;
    check_description(d, FmiVersion::V3)?;
    let decls = d.variables;
    let time_vr = d.time_value_reference();
    if !d.declares_independent() && decls.iter().any(|v| v.value_reference == time_vr) {
        return Err(format!(
            "{}: value reference {time_vr} of the independent variable 'time' is taken",
            d.model_identifier
        ));
    }
    if !d.declares_independent() && decls.iter().any(|v| v.name == "time") {
        return Err(format!(
            "{}: a variable named 'time' that is not the independent variable",
            d.model_identifier
        ));
    }
    let mut w = document()?;
    open(
        &mut w,
        "fmiModelDescription",
        &root_attributes(d, "3.0", ("instantiationToken", token)),
    )?;
    interfaces_of(&mut w, d, interfaces)?;
    definitions(&mut w, d, FmiVersion::V3)?;
    open(&mut w, "ModelVariables", &[])?;
    if !d.declares_independent() {
        let vr = time_vr.to_string();
        empty(
            &mut w,
            "Float64",
            &[
                ("name", "time"),
                ("valueReference", &vr),
                ("description", "Simulation time"),
                ("causality", "independent"),
                ("variability", "continuous"),
            ],
        )?;
    }
    for v in decls {
        variable(&mut w, d, v)?;
    }
    close(&mut w, "ModelVariables")?;
    model_structure(&mut w, d)?;
    close(&mut w, "fmiModelDescription")?;
    finish(w)
}

/// FMU states: every interface of FMI 3.0 declares them.
const STATES: &[(&str, &str)] = &[("canGetAndSetFMUState", "true"), ("canSerializeFMUState", "true")];

/// Directional and adjoint derivatives: model exchange and co-simulation declare them (not
/// Scheduled Execution: they are not offered between activations).
const DERIVATIVES: &[(&str, &str)] = &[
    ("providesDirectionalDerivatives", "true"),
    ("providesAdjointDerivatives", "true"),
];

/// `<ModelExchange>`, `<CoSimulation>` and `<ScheduledExecution>`, each where the binary offers it.
fn interfaces_of(w: &mut Xml, d: &ModelDescription, interfaces: Interfaces) -> Result<(), String> {
    if interfaces.model_exchange {
        interface(w, "ModelExchange", d, &[STATES, DERIVATIVES])?;
    }
    if interfaces.co_simulation {
        let after = [
            // First derivatives of the outputs, exact (dual numbers through the equations).
            ("maxOutputDerivativeOrder", "1"),
            // The runtime's integrator calls the importer's intermediate-update callback at
            // the end of each accepted internal step (time only: no variable is
            // intermediateUpdate="true"); with earlyReturnAllowed the importer may ask it
            // to return early there.
            ("providesIntermediateUpdate", "true"),
            // Events are handled inside fmi3DoStep, or with eventModeUsed by the importer
            // (with earlyReturnAllowed, the step returns at each event).
            ("mightReturnEarlyFromDoStep", "true"),
            ("canReturnEarlyAfterIntermediateUpdate", "true"),
            ("hasEventMode", "true"),
        ];
        let before = [("canHandleVariableCommunicationStepSize", "true")];
        interface(w, "CoSimulation", d, &[&before, STATES, DERIVATIVES, &after])?;
    }
    if interfaces.scheduled_execution {
        // Partitions activated with fmi3ActivateModelPartition in Clock Activation Mode; FMU
        // states there.
        interface(w, "ScheduledExecution", d, &[STATES])?;
    }
    Ok(())
}

/// One variable's element (`<Float64>`, ...) with its attributes, and its children: the
/// `<Dimension>`s of an array, the `<Start>` of a String or Binary, the `<Alias>`es.
fn variable(w: &mut Xml, d: &ModelDescription, v: &Variable) -> Result<(), String> {
    let vr_of = |name: &str| vr_of(d, name);
    let vr = v.value_reference.to_string();
    let causality = lower_camel(v.causality);
    let variability = lower_camel(v.variability);
    let mut attrs = vec![("name", v.name), ("valueReference", vr.as_str())];
    if !v.description.trim().is_empty() {
        attrs.push(("description", v.description.trim()));
    }
    attrs.extend([("causality", causality.as_str()), ("variability", variability.as_str())]);
    if let Some(e) = v.enumeration {
        attrs.push(("declaredType", e.name));
    }
    let initial = v.initial.map(lower_camel);
    if let Some(initial) = &initial {
        attrs.push(("initial", initial));
    }
    let min = v.min.map(|b| bound_text(v, b, true));
    let max = v.max.map(|b| bound_text(v, b, false));
    let nominal = v.nominal.map(real_text);
    let start = start_text(d, v)?;
    // In FMI 3.0 `derivative` is the value reference of the state, not an index.
    let derivative = match v.derivative_of {
        Some(state) => Some(
            vr_of(state)
                .ok_or_else(|| format!("variable '{}': derivative of '{state}', which is not declared", v.name))?
                .to_string(),
        ),
        None => None,
    };
    if v.var_type.is_float() && !v.unit.is_empty() {
        attrs.push(("unit", v.unit));
        if !v.display_unit.is_empty() {
            attrs.push(("displayUnit", v.display_unit));
        }
    }
    let max_size = v.fmi3.max_size.map(|m| m.to_string());
    if v.var_type == VarType::Binary {
        if !v.fmi3.mime_type.is_empty() {
            attrs.push(("mimeType", v.fmi3.mime_type));
        }
        if let Some(m) = &max_size {
            attrs.push(("maxSize", m));
        }
    }
    if !matches!(v.var_type, VarType::Boolean | VarType::String | VarType::Binary) {
        if let Some(min) = &min {
            attrs.push(("min", min));
        }
        if let Some(max) = &max {
            attrs.push(("max", max));
        }
    }
    if v.var_type.is_float()
        && let Some(nominal) = &nominal
    {
        attrs.push(("nominal", nominal));
    }
    if v.has_start()
        && let Some(start) = &start
    {
        attrs.push(("start", start));
    }
    if let Some(derivative) = &derivative {
        attrs.push(("derivative", derivative));
    }
    // A clocked variable's clocks, by value reference (FMI 3.0 `clocks`).
    let clocks = v
        .fmi3
        .clocks
        .iter()
        .map(|c| {
            vr_of(c)
                .map(|vr| vr.to_string())
                .ok_or_else(|| format!("variable '{}': clocked by '{c}', which is not declared", v.name))
        })
        .collect::<Result<Vec<_>, String>>()?
        .join(" ");
    if !clocks.is_empty() {
        attrs.push(("clocks", &clocks));
    }
    let (interval, shift) = match v.fmi3.clock {
        Some(c) => (c.interval.map(real_text), (c.shift != 0.0).then(|| real_text(c.shift))),
        None => (None, None),
    };
    let priority = v.fmi3.clock.and_then(|c| c.priority).map(|p| p.to_string());
    if let Some(c) = v.fmi3.clock {
        attrs.push(("intervalVariability", c.interval_variability.text()));
        if let Some(i) = &interval {
            attrs.push(("intervalDecimal", i));
        }
        if let Some(s) = &shift {
            attrs.push(("shiftDecimal", s));
        }
        if c.can_be_deactivated {
            attrs.push(("canBeDeactivated", "true"));
        }
        if let Some(p) = &priority {
            attrs.push(("priority", p));
        }
    }
    let element = v.var_type.fmi3_name();
    // The children, in the schema's order: <Dimension>s, <Start>s, <Alias>es.
    let start_child = match v.start {
        Start::String(s) if v.has_start() => Some(s.to_string()),
        // xs:hexBinary
        Start::Binary(b) if v.has_start() => Some(b.iter().map(|x| format!("{x:02x}")).collect()),
        _ => None,
    };
    if start_child.is_none() && !v.is_array() && v.aliases.is_empty() {
        return empty(w, element, &attrs);
    }
    open(w, element, &attrs)?;
    children(w, v, start_child.as_deref())?;
    close(w, element)
}

/// A bound as FMI 3.0 writes it: an Integer's and Enumeration's as an integer (xs:int, xs:long),
/// an exclusive one moved to the next integer inside the range; a Float32's as the f32 it is.
fn bound_text(v: &Variable, b: Bound, is_min: bool) -> String {
    match v.var_type {
        t if t.is_integer() || t == VarType::Enumeration => {
            let x = bound_value(b, is_min);
            (if is_min { x.ceil() } else { x.floor() } as i128).to_string()
        }
        VarType::Float32 => format!("{:?}", bound_value(b, is_min) as f32),
        _ => real_text(bound_value(b, is_min)),
    }
}

/// The `start` attribute's text (`None` for a String's and a Binary's: a child element). An
/// array's start: its elements' in row-major order, separated by spaces; of an array sized by
/// structural parameters, those of the elements at the parameters' start values.
fn start_text(d: &ModelDescription, v: &Variable) -> Result<Option<String>, String> {
    let scalar_text = |start: &Start| match *start {
        Start::Real(x) if v.var_type == VarType::Float32 => Some(format!("{:?}", x as f32)),
        Start::Real(x) => Some(real_text(x)),
        Start::Integer(x) => Some(x.to_string()),
        Start::Int64(x) => Some(x.to_string()),
        Start::UInt64(x) => Some(x.to_string()),
        Start::Boolean(x) => Some(x.to_string()),
        Start::String(_) | Start::Binary(_) | Start::Array(_) | Start::None => None,
    };
    Ok(match v.start {
        Start::Array(items) => {
            let sizes = array_sizes(d, v).map_err(|e| format!("variable '{}': {e}", v.name))?;
            let items = active_items(items, v.fmi3.dimensions, &sizes);
            Some(items.into_iter().filter_map(scalar_text).collect::<Vec<_>>().join(" "))
        }
        ref one => scalar_text(one),
    })
}

/// A variable's children, in the schema's order: `<Dimension>`s (a fixed length, or the value
/// reference of the structural parameter that sets it), `<Start>`, `<Alias>`es.
fn children(w: &mut Xml, v: &Variable, start_child: Option<&str>) -> Result<(), String> {
    for (k, n) in v.fmi3.dimensions.iter().enumerate() {
        match v.fmi3.sized_by.get(k) {
            Some(&vr) if vr != NOT_SIZED => empty(w, "Dimension", &[("valueReference", &vr.to_string())])?,
            _ => empty(w, "Dimension", &[("start", &n.to_string())])?,
        }
    }
    if let Some(value) = start_child {
        empty(w, "Start", &[("value", value)])?;
    }
    for a in v.aliases {
        let mut alias = vec![("name", a.name)];
        if !a.description.is_empty() {
            alias.push(("description", a.description));
        }
        if !a.display_unit.is_empty() {
            alias.push(("displayUnit", a.display_unit));
        }
        empty(w, "Alias", &alias)?;
    }
    Ok(())
}

/// `<ModelStructure>`: outputs, state derivatives, initial unknowns and event indicators by
/// value reference, each with the knowns it depends on.
fn model_structure(w: &mut Xml, d: &ModelDescription) -> Result<(), String> {
    let decls = d.variables;
    let vr_of = |name: &str| vr_of(d, name);
    // dependencies: value references of the knowns (inputs and continuous states), in
    // ascending order; dependenciesKind "dependent" for each (no particular structure claimed).
    let unknown = |w: &mut Xml, element: &str, v: &Variable, deps: Option<&[&str]>| -> Result<(), String> {
        let vr = v.value_reference.to_string();
        let deps = deps.map(|deps| {
            let set: BTreeSet<u32> = deps.iter().filter_map(|n| vr_of(n)).collect();
            set.into_iter().map(|vr| vr.to_string()).collect::<Vec<_>>()
        });
        let dep_text = deps.as_ref().map(|d| d.join(" "));
        let kind_text = deps.as_ref().map(|d| vec!["dependent"; d.len()].join(" "));
        let mut attrs = vec![("valueReference", vr.as_str())];
        if let (Some(deps), Some(kinds)) = (&dep_text, &kind_text) {
            attrs.push(("dependencies", deps));
            attrs.push(("dependenciesKind", kinds));
        }
        empty(w, element, &attrs)
    };
    open(w, "ModelStructure", &[])?;
    for v in decls.iter().filter(|v| v.causality == Causality::Output) {
        unknown(w, "Output", v, v.depends_on)?;
    }
    for v in decls.iter().filter(|v| v.derivative_of.is_some()) {
        unknown(w, "ContinuousStateDerivative", v, v.depends_on)?;
    }
    for v in decls.iter().filter(|v| d.is_initial_unknown(v)) {
        unknown(w, "InitialUnknown", v, v.initial_depends_on)?;
    }
    for name in d.event_indicators {
        let v = d
            .by_name(name)
            .ok_or_else(|| format!("{}: event indicator '{name}' is no variable", d.model_identifier))?;
        unknown(w, "EventIndicator", v, v.depends_on)?;
    }
    close(w, "ModelStructure")
}

/// The value reference of the declared variable `name`.
fn vr_of(d: &ModelDescription, name: &str) -> Option<u32> {
    d.variables.iter().find(|o| o.name == name).map(|o| o.value_reference)
}
