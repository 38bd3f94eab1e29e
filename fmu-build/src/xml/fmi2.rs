//! `modelDescription.xml` of FMI 2.0.

use super::sections::definitions;
use super::{
    Xml, bound_value, check_description, close, document, empty, finish, interface, io, lower_camel, of_version, open,
    real_text, root_attributes,
};
use quick_xml::events::Event;
use rustfmu::description::{Bound, Causality, FmiVersion, Interfaces, ModelDescription, Start, VarType, Variable};
use std::collections::BTreeSet;

/// `modelDescription.xml` (FMI 2.0) of a description, in the element order of the XSD.
pub fn fmi2(d: &ModelDescription, interfaces: Interfaces, guid: &str) -> Result<String, String> {
    of_version(d, interfaces, FmiVersion::V2)?;
    check_description(d, FmiVersion::V2)?;
    let decls = d.variables;
    if let Some(v) = decls.iter().find(|v| !v.var_type.in_fmi2()) {
        return Err(format!(
            "{}: variable '{}' is a {}, which FMI 2.0 does not have (the FMI 2.0 encoding leaves such variables out: is the binary from another rustfmu release?)",
            d.model_identifier,
            v.name,
            v.var_type.fmi3_name()
        ));
    }
    let mut w = document()?;
    let n_event_indicators = d.event_indicators.len().to_string();
    let mut root = root_attributes(d, "2.0", ("guid", guid));
    root.push(("numberOfEventIndicators", &n_event_indicators));
    open(&mut w, "fmiModelDescription", &root)?;
    interfaces_of(&mut w, d, interfaces)?;
    definitions(&mut w, d, FmiVersion::V2)?;
    open(&mut w, "ModelVariables", &[])?;
    for (i, v) in decls.iter().enumerate() {
        scalar_variable(&mut w, decls, i, v)?;
    }
    aliases_of(&mut w, decls)?;
    close(&mut w, "ModelVariables")?;
    model_structure(&mut w, d)?;
    close(&mut w, "fmiModelDescription")?;
    finish(w)
}

/// The capabilities both interfaces of FMI 2.0 declare alike, after their own.
const CAPABILITIES: &[(&str, &str)] = &[
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canNotUseMemoryManagementFunctions", "true"),
    ("canGetAndSetFMUstate", "true"),
    ("canSerializeFMUstate", "true"),
    ("providesDirectionalDerivative", "true"),
];

/// `<ModelExchange>` and `<CoSimulation>`, each where the binary offers it.
fn interfaces_of(w: &mut Xml, d: &ModelDescription, interfaces: Interfaces) -> Result<(), String> {
    if interfaces.model_exchange {
        let own = [
            ("needsExecutionTool", "false"),
            ("completedIntegratorStepNotNeeded", "true"),
        ];
        interface(w, "ModelExchange", d, &[&own, CAPABILITIES])?;
    }
    if interfaces.co_simulation {
        let own = [
            ("needsExecutionTool", "false"),
            ("canHandleVariableCommunicationStepSize", "true"),
            // The runtime's integrator follows input derivatives where the model says its
            // step is that integrator (CoSimulation::INTERPOLATES_INPUTS).
            (
                "canInterpolateInputs",
                if interfaces.can_interpolate_inputs {
                    "true"
                } else {
                    "false"
                },
            ),
            // First derivatives of the outputs, exact (dual numbers through the equations).
            ("maxOutputDerivativeOrder", "1"),
            ("canRunAsynchronuously", "false"),
        ];
        interface(w, "CoSimulation", d, &[&own, CAPABILITIES])?;
    }
    Ok(())
}

/// One `<ScalarVariable>` of the declared variables (`i`: its place, the index is `i + 1`).
fn scalar_variable(w: &mut Xml, decls: &[Variable], i: usize, v: &Variable) -> Result<(), String> {
    w.write_event(Event::Comment(quick_xml::events::BytesText::new(&format!(
        " index {} ",
        i + 1
    ))))
    .map_err(io)?;
    let vr = v.value_reference.to_string();
    let causality = lower_camel(v.causality);
    let variability = lower_camel(v.variability);
    let mut attrs = vec![
        ("name", v.name),
        ("valueReference", vr.as_str()),
        ("description", v.description.trim()),
        ("causality", causality.as_str()),
        ("variability", variability.as_str()),
    ];
    let initial = v.initial.map(lower_camel);
    if let Some(initial) = &initial {
        attrs.push(("initial", initial));
    }
    open(w, "ScalarVariable", &attrs)?;
    let start = start_text(v);
    let min = v.min.map(|b| bound_text(v, b, true));
    let max = v.max.map(|b| bound_text(v, b, false));
    let nominal = v.nominal.map(real_text);
    let derivative = v
        .derivative_of
        .and_then(|s| decls.iter().position(|o| o.name == s))
        .map(|i| (i + 1).to_string());
    let mut type_attrs: Vec<(&str, &str)> = Vec::new();
    if let Some(e) = v.enumeration {
        type_attrs.push(("declaredType", e.name));
    }
    if let Some(derivative) = &derivative {
        type_attrs.push(("derivative", derivative));
    }
    if v.var_type == VarType::Real && !v.unit.is_empty() {
        type_attrs.push(("unit", v.unit));
        if !v.display_unit.is_empty() {
            type_attrs.push(("displayUnit", v.display_unit));
        }
    }
    if let Some(min) = &min {
        type_attrs.push(("min", min));
    }
    if let Some(max) = &max {
        type_attrs.push(("max", max));
    }
    if let Some(nominal) = &nominal {
        type_attrs.push(("nominal", nominal));
    }
    if v.has_start() {
        type_attrs.push(("start", &start));
    }
    empty(w, &format!("{:?}", v.var_type), &type_attrs)?;
    close(w, "ScalarVariable")?;
    Ok(())
}

/// `<ModelStructure>`: the outputs, derivatives and initial unknowns by index, each with the
/// indices of the knowns it depends on.
fn model_structure(w: &mut Xml, d: &ModelDescription) -> Result<(), String> {
    let decls = d.variables;
    let index_of = |name: &str| decls.iter().position(|d| d.name == name).map(|i| i + 1);
    // dependencies: indices of the knowns, "ordered according to size" (FMI 2.0, 3.3.1).
    let indices = |deps: &[&str]| {
        let set: BTreeSet<usize> = deps.iter().filter_map(|n| index_of(n)).collect();
        set.into_iter().map(|i| i.to_string()).collect::<Vec<_>>().join(" ")
    };
    // One list of unknowns (`Outputs`, ...): the variables `listed` picks, by index, each with
    // the knowns it depends on (at initialization: `initial`).
    let unknowns = |w: &mut Xml, element: &str, listed: &dyn Fn(&Variable) -> bool, initial: bool| {
        let list: Vec<(usize, &Variable)> = decls.iter().enumerate().filter(|(_, v)| listed(v)).collect();
        if list.is_empty() {
            return Ok(());
        }
        open(w, element, &[])?;
        for (i, v) in list {
            let index = (i + 1).to_string();
            let deps = if initial { v.initial_depends_on } else { v.depends_on }.map(indices);
            let mut attrs = vec![("index", index.as_str())];
            if let Some(deps) = &deps {
                attrs.push(("dependencies", deps));
            }
            empty(w, "Unknown", &attrs)?;
        }
        close(w, element)
    };
    open(w, "ModelStructure", &[])?;
    unknowns(w, "Outputs", &|v| v.causality == Causality::Output, false)?;
    unknowns(w, "Derivatives", &|v| v.derivative_of.is_some(), false)?;
    unknowns(w, "InitialUnknowns", &|v| d.is_initial_unknown(v), true)?;
    close(w, "ModelStructure")
}

/// The aliases in FMI 2.0: after the declared variables (whose indices stay as they are), one
/// `<ScalarVariable>` per alias with the value reference, type, variability, unit and bounds of
/// its variable. FMI 2.0 (2.2.7) has an alias set share one value reference; at most one of the
/// set may be set by the importer and at most one carry a start value (a constant's aliases all
/// carry its value), and every output is listed in `<Outputs>`: so an alias is a `local` whose
/// `initial` is the default, calculated (a constant's: exact, with the constant's value).
fn aliases_of(w: &mut Xml, decls: &[Variable]) -> Result<(), String> {
    let mut index = decls.len();
    for v in decls {
        for a in v.aliases {
            index += 1;
            w.write_event(Event::Comment(quick_xml::events::BytesText::new(&format!(
                " index {index} "
            ))))
            .map_err(io)?;
            let vr = v.value_reference.to_string();
            let variability = lower_camel(v.variability);
            let description = if a.description.is_empty() {
                v.description.trim()
            } else {
                a.description
            };
            let attrs = [
                ("name", a.name),
                ("valueReference", vr.as_str()),
                ("description", description),
                ("causality", "local"),
                ("variability", variability.as_str()),
            ];
            open(w, "ScalarVariable", &attrs)?;
            let mut type_attrs: Vec<(&str, String)> = Vec::new();
            if let Some(e) = v.enumeration {
                type_attrs.push(("declaredType", e.name.to_string()));
            }
            if v.var_type == VarType::Real && !v.unit.is_empty() {
                type_attrs.push(("unit", v.unit.to_string()));
                if !a.display_unit.is_empty() {
                    type_attrs.push(("displayUnit", a.display_unit.to_string()));
                }
            }
            if let Some(b) = v.min {
                type_attrs.push(("min", bound_text(v, b, true)));
            }
            if let Some(b) = v.max {
                type_attrs.push(("max", bound_text(v, b, false)));
            }
            if let Some(n) = v.nominal {
                type_attrs.push(("nominal", real_text(n)));
            }
            if v.variability == rustfmu::description::Variability::Constant {
                type_attrs.push(("start", start_text(v)));
            }
            let type_attrs: Vec<(&str, &str)> = type_attrs.iter().map(|(k, v)| (*k, v.as_str())).collect();
            empty(w, &format!("{:?}", v.var_type), &type_attrs)?;
            close(w, "ScalarVariable")?;
        }
    }
    Ok(())
}

/// A start value as FMI 2.0 writes it (empty for none).
fn start_text(v: &Variable) -> String {
    match v.start {
        Start::Real(x) => real_text(x),
        Start::Integer(x) => x.to_string(),
        Start::Boolean(x) => x.to_string(),
        Start::String(s) => s.to_string(),
        // Not FMI 2.0 types (refused by `fmi2`).
        Start::Int64(_) | Start::UInt64(_) | Start::Binary(_) | Start::Array(_) | Start::None => String::new(),
    }
}

/// A bound as FMI 2.0 writes it: an Integer's (and Enumeration's) as an integer ("1", not "1.0":
/// the XSD type is xs:int), an exclusive one moved to the next integer inside the range.
fn bound_text(v: &Variable, b: Bound, is_min: bool) -> String {
    let x = bound_value(b, is_min);
    match v.var_type {
        VarType::Integer | VarType::Enumeration => (if is_min { x.ceil() } else { x.floor() } as i64).to_string(),
        _ => real_text(x),
    }
}
