//! `modelDescription.xml`, written from a model's declarations with quick-xml, in the element
//! order of the FMI 2.0 XSD, and the GUID derived from its content.

use super::logging::CATEGORIES;
use super::model::CoSimModel;
use super::units::base_unit;
use super::variables::{Causality, Initial, Value, VarDecl, VarType, Variability, VariableSet};
use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use std::collections::BTreeSet;

/// Placeholder the GUID is computed over, so the GUID hashes everything else in the file.
const GUID_PLACEHOLDER: &str = "{00000000-0000-0000-0000-000000000000}";

/// Namespace for the name-based (v5) UUIDs of model descriptions.
const GUID_NAMESPACE: uuid::Uuid = uuid::Uuid::from_bytes([
    0x6f, 0x3c, 0x2a, 0x51, 0x8e, 0x0d, 0x4b, 0x7a, 0x9c, 0x11, 0x52, 0xd4, 0x0e, 0x9b, 0x33, 0x70,
]);

/// The model description of `M`, or what is wrong with its declarations.
pub fn model_description<M: CoSimModel>() -> Result<String, String> {
    let body = write_description::<M>(GUID_PLACEHOLDER)?;
    Ok(body.replacen(GUID_PLACEHOLDER, &guid_of(&body), 1))
}

/// The GUID of `M`: a v5 UUID of its description with the GUID left out. It changes whenever
/// anything in the description changes (variables, units, start values, documentation).
pub fn guid<M: CoSimModel>() -> Result<String, String> {
    Ok(guid_of(&write_description::<M>(GUID_PLACEHOLDER)?))
}

fn guid_of(description: &str) -> String {
    format!("{{{}}}", uuid::Uuid::new_v5(&GUID_NAMESPACE, description.as_bytes()))
}

/// Shortest text that reads back as the same f64 (Rust's `{:?}` is round-trip exact).
pub fn real_text(x: f64) -> String {
    format!("{x:?}")
}

/// Checks the declarations against the rules of FMI 2.0 section 2.2.7.
pub fn check_declarations(decls: &[VarDecl]) -> Result<(), String> {
    let mut seen_names = BTreeSet::new();
    let mut seen_vrs = BTreeSet::new();
    for d in decls {
        let at = format!("variable '{}' (vr {})", d.name, d.value_reference);
        if !seen_names.insert(d.name) {
            return Err(format!("{at}: the name is declared twice"));
        }
        if !seen_vrs.insert((d.value_reference, d.var_type as u8)) {
            return Err(format!("{at}: the value reference is used twice for {:?}", d.var_type));
        }
        if d.start.var_type() != d.var_type {
            return Err(format!("{at}: start value {:?} is not a {:?}", d.start, d.var_type));
        }
        for bound in [d.min, d.max].into_iter().flatten() {
            let fits = match d.var_type {
                VarType::Real => bound.is_finite(),
                VarType::Integer => bound.fract() == 0.0 && bound.abs() <= i32::MAX as f64,
                VarType::Boolean => false,
            };
            if !fits {
                return Err(format!("{at}: bound {bound} does not fit a {:?} variable", d.var_type));
            }
        }
        let start = match d.start {
            Value::Real(x) => Some(x),
            Value::Integer(x) => Some(x as f64),
            Value::Boolean(_) => None,
        };
        if let Some(x) = start
            && (d.min.is_some_and(|m| x < m) || d.max.is_some_and(|m| x > m))
        {
            return Err(format!("{at}: start value {x} is outside [min, max]"));
        }
        if d.var_type != VarType::Real && d.variability == Variability::Continuous {
            return Err(format!("{at}: only Real variables may be continuous"));
        }
        if !d.unit.is_empty() && base_unit(d.unit).is_none() {
            return Err(format!("{at}: unit '{}' is not declared in fmi2::units::UNITS", d.unit));
        }
        if let Value::Real(x) = d.start
            && !x.is_finite()
        {
            return Err(format!("{at}: start value {x} is not finite"));
        }
        use Causality as C;
        use Variability as V;
        let legal_variability = match d.causality {
            C::Parameter | C::CalculatedParameter => matches!(d.variability, V::Fixed | V::Tunable),
            C::Input => matches!(d.variability, V::Discrete | V::Continuous),
            C::Output => matches!(d.variability, V::Constant | V::Discrete | V::Continuous),
            C::Local => true,
            C::Independent => d.variability == V::Continuous,
        };
        if !legal_variability {
            return Err(format!(
                "{at}: causality {:?} with variability {:?} is not allowed",
                d.causality, d.variability
            ));
        }
        let legal_initial = match (d.causality, d.variability, d.initial) {
            (_, _, None) => true,
            (C::Input | C::Independent, _, Some(_)) => false,
            (C::Parameter, _, Some(i)) | (_, V::Constant, Some(i)) => i == Initial::Exact,
            (C::CalculatedParameter, _, Some(i)) => i != Initial::Exact,
            (C::Local, V::Fixed | V::Tunable, Some(i)) => i != Initial::Exact,
            (C::Output | C::Local, _, Some(_)) => true,
        };
        if !legal_initial {
            return Err(format!(
                "{at}: initial {:?} is not allowed with causality {:?} and variability {:?}",
                d.initial, d.causality, d.variability
            ));
        }
        if d.depends_on.is_some() && d.causality != C::Output {
            return Err(format!("{at}: only outputs declare dependencies"));
        }
        for dep in d.depends_on.unwrap_or(&[]) {
            if !decls.iter().any(|o| o.name == *dep && o.causality == C::Input) {
                return Err(format!("{at}: depends on '{dep}', which is not an input"));
            }
        }
    }
    Ok(())
}

type Xml = Writer<Vec<u8>>;

fn io(e: impl std::fmt::Display) -> String {
    format!("writing modelDescription.xml: {e}")
}

fn empty(w: &mut Xml, name: &str, attrs: &[(&str, &str)]) -> Result<(), String> {
    let mut el = BytesStart::new(name);
    for (k, v) in attrs {
        el.push_attribute((*k, *v));
    }
    w.write_event(Event::Empty(el)).map_err(io)
}

fn open(w: &mut Xml, name: &str, attrs: &[(&str, &str)]) -> Result<(), String> {
    let mut el = BytesStart::new(name);
    for (k, v) in attrs {
        el.push_attribute((*k, *v));
    }
    w.write_event(Event::Start(el)).map_err(io)
}

fn close(w: &mut Xml, name: &str) -> Result<(), String> {
    w.write_event(Event::End(BytesEnd::new(name))).map_err(io)
}

fn lower_camel<T: std::fmt::Debug>(v: T) -> String {
    let s = format!("{v:?}");
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_lowercase().chain(c).collect(),
        None => s,
    }
}

fn write_description<M: CoSimModel>(guid: &str) -> Result<String, String> {
    let info = M::INFO;
    let decls = M::Vars::DECLS;
    check_declarations(decls)?;
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .map_err(io)?;
    open(
        &mut w,
        "fmiModelDescription",
        &[
            ("fmiVersion", "2.0"),
            ("modelName", info.identifier),
            ("guid", guid),
            ("description", info.description),
            ("author", info.author),
            ("version", info.version),
            ("generationTool", concat!("rustfmu ", env!("CARGO_PKG_VERSION"))),
            ("variableNamingConvention", "flat"),
            ("numberOfEventIndicators", "0"),
        ],
    )?;
    empty(
        &mut w,
        "CoSimulation",
        &[
            ("modelIdentifier", info.identifier),
            ("needsExecutionTool", "false"),
            ("canHandleVariableCommunicationStepSize", "true"),
            ("canInterpolateInputs", "false"),
            ("maxOutputDerivativeOrder", "0"),
            ("canRunAsynchronuously", "false"),
            ("canBeInstantiatedOnlyOncePerProcess", "false"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            ("providesDirectionalDerivative", "false"),
        ],
    )?;

    let units: BTreeSet<&str> = decls.iter().map(|d| d.unit).filter(|u| !u.is_empty()).collect();
    if !units.is_empty() {
        open(&mut w, "UnitDefinitions", &[])?;
        for unit in &units {
            let b = base_unit(unit).ok_or_else(|| format!("unit '{unit}' is not declared"))?;
            open(&mut w, "Unit", &[("name", unit)])?;
            let exps = [("kg", b.kg), ("m", b.m), ("s", b.s), ("A", b.a), ("rad", b.rad)];
            let texts: Vec<(&str, String)> = exps
                .iter()
                .filter(|(_, e)| *e != 0)
                .map(|(k, e)| (*k, e.to_string()))
                .collect();
            let attrs: Vec<(&str, &str)> = texts.iter().map(|(k, v)| (*k, v.as_str())).collect();
            empty(&mut w, "BaseUnit", &attrs)?;
            close(&mut w, "Unit")?;
        }
        close(&mut w, "UnitDefinitions")?;
    }

    open(&mut w, "LogCategories", &[])?;
    for (name, description) in CATEGORIES {
        empty(&mut w, "Category", &[("name", name), ("description", description)])?;
    }
    close(&mut w, "LogCategories")?;

    if let Some(e) = info.default_experiment {
        empty(
            &mut w,
            "DefaultExperiment",
            &[
                ("startTime", &real_text(e.start_time)),
                ("stopTime", &real_text(e.stop_time)),
                ("stepSize", &real_text(e.step_size)),
            ],
        )?;
    }

    open(&mut w, "ModelVariables", &[])?;
    for (i, d) in decls.iter().enumerate() {
        w.write_event(Event::Comment(quick_xml::events::BytesText::new(&format!(
            " index {} ",
            i + 1
        ))))
        .map_err(io)?;
        let vr = d.value_reference.to_string();
        let causality = lower_camel(d.causality);
        let variability = lower_camel(d.variability);
        let mut attrs = vec![
            ("name", d.name),
            ("valueReference", vr.as_str()),
            ("description", d.description.trim()),
            ("causality", causality.as_str()),
            ("variability", variability.as_str()),
        ];
        let initial = d.initial.map(lower_camel);
        if let Some(initial) = &initial {
            attrs.push(("initial", initial));
        }
        open(&mut w, "ScalarVariable", &attrs)?;
        let start = match d.start {
            Value::Real(x) => real_text(x),
            Value::Integer(x) => x.to_string(),
            Value::Boolean(x) => x.to_string(),
        };
        // An Integer's bounds are written as integers ("1", not "1.0": the XSD type is xs:int).
        let bound_text = |x: f64| match d.var_type {
            VarType::Integer => (x as i64).to_string(),
            _ => real_text(x),
        };
        let min = d.min.map(bound_text);
        let max = d.max.map(bound_text);
        let mut type_attrs: Vec<(&str, &str)> = Vec::new();
        if d.var_type == VarType::Real && !d.unit.is_empty() {
            type_attrs.push(("unit", d.unit));
        }
        if let Some(min) = &min {
            type_attrs.push(("min", min));
        }
        if let Some(max) = &max {
            type_attrs.push(("max", max));
        }
        if d.has_start() {
            type_attrs.push(("start", &start));
        }
        empty(&mut w, &format!("{:?}", d.var_type), &type_attrs)?;
        close(&mut w, "ScalarVariable")?;
    }
    close(&mut w, "ModelVariables")?;

    let index_of = |name: &str| decls.iter().position(|d| d.name == name).map(|i| (i + 1).to_string());
    open(&mut w, "ModelStructure", &[])?;
    let outputs: Vec<(usize, &VarDecl)> = decls
        .iter()
        .enumerate()
        .filter(|(_, d)| d.causality == Causality::Output)
        .collect();
    if !outputs.is_empty() {
        open(&mut w, "Outputs", &[])?;
        for (i, d) in &outputs {
            let index = (i + 1).to_string();
            let deps = d
                .depends_on
                .map(|deps| deps.iter().filter_map(|n| index_of(n)).collect::<Vec<_>>().join(" "));
            let mut attrs = vec![("index", index.as_str())];
            if let Some(deps) = &deps {
                attrs.push(("dependencies", deps));
            }
            empty(&mut w, "Unknown", &attrs)?;
        }
        close(&mut w, "Outputs")?;
    }
    let initial_unknowns: Vec<usize> = decls
        .iter()
        .enumerate()
        .filter(|(_, d)| {
            (d.causality == Causality::Output
                && matches!(d.effective_initial(), Some(Initial::Approx | Initial::Calculated)))
                || d.causality == Causality::CalculatedParameter
        })
        .map(|(i, _)| i + 1)
        .collect();
    if !initial_unknowns.is_empty() {
        open(&mut w, "InitialUnknowns", &[])?;
        for i in initial_unknowns {
            empty(&mut w, "Unknown", &[("index", &i.to_string())])?;
        }
        close(&mut w, "InitialUnknowns")?;
    }
    close(&mut w, "ModelStructure")?;
    close(&mut w, "fmiModelDescription")?;
    let mut text = String::from_utf8(w.into_inner()).map_err(io)?;
    text.push('\n');
    Ok(text)
}
