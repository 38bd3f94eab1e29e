//! `modelDescription.xml` (FMI 2.0), written with quick-xml from the typed description that
//! the built library carries, in the element order of the XSD.

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use rustfmu::description::{
    Bound, Causality, Initial, Interfaces, ModelDescription, Start, VarType, Variability, Variable,
};
use std::collections::BTreeSet;

/// Shortest text that reads back as the same f64 (Rust's `{:?}` is round-trip exact).
pub fn real_text(x: f64) -> String {
    format!("{x:?}")
}

/// Checks a decoded description against the rules of FMI 2.0 section 2.2.7 once more (the
/// derive macro enforces them at compile time; a description from elsewhere is re-checked).
pub fn check_description(d: &ModelDescription) -> Result<(), String> {
    let decls = d.variables;
    let mut seen_names = BTreeSet::new();
    let mut seen_vrs = BTreeSet::new();
    for v in decls {
        let at = format!("variable '{}' (vr {})", v.name, v.value_reference);
        if !seen_names.insert(v.name) {
            return Err(format!("{at}: the name is declared twice"));
        }
        if !seen_vrs.insert(v.value_reference) {
            return Err(format!("{at}: the value reference is used twice"));
        }
        rustfmu::description::check_values(v).map_err(|e| format!("{at}: {}", e.message()))?;
        if v.var_type != VarType::Real && v.variability == Variability::Continuous {
            return Err(format!("{at}: only Real variables may be continuous"));
        }
        if !v.unit.is_empty() && !d.units.iter().any(|u| u.name == v.unit) {
            return Err(format!("{at}: unit '{}' is not declared", v.unit));
        }
        if v.var_type == VarType::Enumeration && v.enumeration.is_none() {
            return Err(format!("{at}: an Enumeration variable without its type"));
        }
        use Causality as C;
        use Variability as V;
        let legal_variability = match v.causality {
            C::Parameter | C::CalculatedParameter => matches!(v.variability, V::Fixed | V::Tunable),
            C::Input => matches!(v.variability, V::Discrete | V::Continuous),
            C::Output => matches!(v.variability, V::Constant | V::Discrete | V::Continuous),
            C::Local => true,
            C::Independent => v.variability == V::Continuous,
        };
        if !legal_variability {
            return Err(format!(
                "{at}: causality {:?} with variability {:?} is not allowed",
                v.causality, v.variability
            ));
        }
        let legal_initial = match (v.causality, v.variability, v.initial) {
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
                v.initial, v.causality, v.variability
            ));
        }
        if v.has_start() == matches!(v.start, Start::None) {
            return Err(format!(
                "{at}: a start value must be given exactly where the standard asks for one"
            ));
        }
        // The knowns of ModelStructure: inputs and continuous states.
        let is_state = |name: &str| decls.iter().any(|d| d.derivative_of == Some(name));
        for dep in v.depends_on.unwrap_or(&[]) {
            if !decls
                .iter()
                .any(|o| o.name == *dep && (o.causality == C::Input || is_state(o.name)))
            {
                return Err(format!(
                    "{at}: depends on '{dep}', which is neither an input nor a continuous state"
                ));
            }
        }
        if let Some(state) = v.derivative_of
            && !decls.iter().any(|o| o.name == state)
        {
            return Err(format!("{at}: derivative of '{state}', which is not declared"));
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

/// `min`/`max` as FMI 2.0 writes them: inclusive, so an exclusive bound is written as the
/// nearest representable value inside the range (`> 0` becomes 5e-324).
fn bound_value(b: Bound, is_min: bool) -> f64 {
    match (b.exclusive, is_min) {
        (false, _) => b.value,
        (true, true) => b.value.next_up(),
        (true, false) => b.value.next_down(),
    }
}

/// `modelDescription.xml` (FMI 2.0) of a description, in the element order of the XSD.
pub fn fmi2(d: &ModelDescription, interfaces: Interfaces, guid: &str) -> Result<String, String> {
    check_description(d)?;
    let decls = d.variables;
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .map_err(io)?;
    let mut root = vec![
        ("fmiVersion", "2.0"),
        ("modelName", d.model_identifier),
        ("guid", guid),
        ("description", d.description),
        ("author", d.author),
        ("version", d.version),
    ];
    if !d.copyright.is_empty() {
        root.push(("copyright", d.copyright));
    }
    if !d.license.is_empty() {
        root.push(("license", d.license));
    }
    root.extend([
        ("generationTool", d.generation_tool),
        (
            "variableNamingConvention",
            if decls.iter().any(|v| !is_flat_name(v.name)) {
                "structured"
            } else {
                "flat"
            },
        ),
    ]);
    let n_event_indicators = "0".to_string();
    root.push(("numberOfEventIndicators", &n_event_indicators));
    open(&mut w, "fmiModelDescription", &root)?;
    if interfaces.model_exchange {
        empty(
            &mut w,
            "ModelExchange",
            &[
                ("modelIdentifier", d.model_identifier),
                ("needsExecutionTool", "false"),
                ("completedIntegratorStepNotNeeded", "true"),
                ("canBeInstantiatedOnlyOncePerProcess", "false"),
                ("canNotUseMemoryManagementFunctions", "true"),
                ("canGetAndSetFMUstate", "true"),
                ("canSerializeFMUstate", "true"),
                ("providesDirectionalDerivative", "true"),
            ],
        )?;
    }
    if interfaces.co_simulation {
        empty(
            &mut w,
            "CoSimulation",
            &[
                ("modelIdentifier", d.model_identifier),
                ("needsExecutionTool", "false"),
                ("canHandleVariableCommunicationStepSize", "true"),
                ("canInterpolateInputs", "false"),
                ("maxOutputDerivativeOrder", "0"),
                ("canRunAsynchronuously", "false"),
                ("canBeInstantiatedOnlyOncePerProcess", "false"),
                ("canNotUseMemoryManagementFunctions", "true"),
                ("canGetAndSetFMUstate", "true"),
                ("canSerializeFMUstate", "true"),
                ("providesDirectionalDerivative", "true"),
            ],
        )?;
    }

    // Units in name order, as before (the derive lists them in order of first use).
    let mut units: Vec<_> = d
        .units
        .iter()
        .filter(|u| decls.iter().any(|v| v.unit == u.name))
        .collect();
    units.sort_by(|a, b| a.name.cmp(b.name));
    if !units.is_empty() {
        open(&mut w, "UnitDefinitions", &[])?;
        for unit in &units {
            let b = unit.base;
            open(&mut w, "Unit", &[("name", unit.name)])?;
            let exps = [
                ("kg", b.kg),
                ("m", b.m),
                ("s", b.s),
                ("A", b.a),
                ("K", b.k),
                ("mol", b.mol),
                ("cd", b.cd),
                ("rad", b.rad),
            ];
            let mut texts: Vec<(&str, String)> = exps
                .iter()
                .filter(|(_, e)| *e != 0)
                .map(|(k, e)| (*k, e.to_string()))
                .collect();
            if b.factor != 1.0 {
                texts.push(("factor", real_text(b.factor)));
            }
            if b.offset != 0.0 {
                texts.push(("offset", real_text(b.offset)));
            }
            let attrs: Vec<(&str, &str)> = texts.iter().map(|(k, v)| (*k, v.as_str())).collect();
            empty(&mut w, "BaseUnit", &attrs)?;
            close(&mut w, "Unit")?;
        }
        close(&mut w, "UnitDefinitions")?;
    }

    let enums = d.enumerations();
    if !enums.is_empty() {
        open(&mut w, "TypeDefinitions", &[])?;
        for e in &enums {
            let mut attrs = vec![("name", e.name)];
            if !e.description.is_empty() {
                attrs.push(("description", e.description));
            }
            open(&mut w, "SimpleType", &attrs)?;
            open(&mut w, "Enumeration", &[])?;
            for item in e.items {
                let value = item.value.to_string();
                let mut attrs = vec![("name", item.name), ("value", value.as_str())];
                if !item.description.is_empty() {
                    attrs.push(("description", item.description));
                }
                empty(&mut w, "Item", &attrs)?;
            }
            close(&mut w, "Enumeration")?;
            close(&mut w, "SimpleType")?;
        }
        close(&mut w, "TypeDefinitions")?;
    }

    open(&mut w, "LogCategories", &[])?;
    for c in d.all_log_categories() {
        empty(&mut w, "Category", &[("name", c.name), ("description", c.description)])?;
    }
    close(&mut w, "LogCategories")?;

    if let Some(e) = d.default_experiment {
        let texts: Vec<(&str, String)> = [
            ("startTime", e.start_time),
            ("stopTime", e.stop_time),
            ("tolerance", e.tolerance),
            ("stepSize", e.step_size),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.map(|v| (k, real_text(v))))
        .collect();
        let attrs: Vec<(&str, &str)> = texts.iter().map(|(k, v)| (*k, v.as_str())).collect();
        empty(&mut w, "DefaultExperiment", &attrs)?;
    }

    open(&mut w, "ModelVariables", &[])?;
    for (i, v) in decls.iter().enumerate() {
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
        open(&mut w, "ScalarVariable", &attrs)?;
        let start = match v.start {
            Start::Real(x) => real_text(x),
            Start::Integer(x) => x.to_string(),
            Start::Boolean(x) => x.to_string(),
            Start::String(s) => s.to_string(),
            Start::None => String::new(),
        };
        // An Integer's bounds are written as integers ("1", not "1.0": the XSD type is xs:int).
        let bound_text = |b: Bound, is_min: bool| match v.var_type {
            // An exclusive integer bound moves to the next integer inside the range.
            VarType::Integer | VarType::Enumeration => {
                let x = bound_value(b, is_min);
                (if is_min { x.ceil() } else { x.floor() } as i64).to_string()
            }
            _ => real_text(bound_value(b, is_min)),
        };
        let min = v.min.map(|b| bound_text(b, true));
        let max = v.max.map(|b| bound_text(b, false));
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
        empty(&mut w, &format!("{:?}", v.var_type), &type_attrs)?;
        close(&mut w, "ScalarVariable")?;
    }
    close(&mut w, "ModelVariables")?;

    let index_of = |name: &str| decls.iter().position(|d| d.name == name).map(|i| (i + 1).to_string());
    let unknown = |w: &mut Xml, i: usize, v: &Variable| -> Result<(), String> {
        let index = (i + 1).to_string();
        let deps = v
            .depends_on
            .map(|deps| deps.iter().filter_map(|n| index_of(n)).collect::<Vec<_>>().join(" "));
        let mut attrs = vec![("index", index.as_str())];
        if let Some(deps) = &deps {
            attrs.push(("dependencies", deps));
        }
        empty(w, "Unknown", &attrs)
    };
    open(&mut w, "ModelStructure", &[])?;
    let outputs: Vec<(usize, &Variable)> = decls
        .iter()
        .enumerate()
        .filter(|(_, d)| d.causality == Causality::Output)
        .collect();
    if !outputs.is_empty() {
        open(&mut w, "Outputs", &[])?;
        for (i, v) in &outputs {
            unknown(&mut w, *i, v)?;
        }
        close(&mut w, "Outputs")?;
    }
    let derivatives: Vec<(usize, &Variable)> = decls
        .iter()
        .enumerate()
        .filter(|(_, d)| d.derivative_of.is_some())
        .collect();
    if !derivatives.is_empty() {
        open(&mut w, "Derivatives", &[])?;
        for (i, v) in &derivatives {
            unknown(&mut w, *i, v)?;
        }
        close(&mut w, "Derivatives")?;
    }
    let is_state = |v: &Variable| decls.iter().any(|d| d.derivative_of == Some(v.name));
    let initial_unknowns: Vec<usize> = decls
        .iter()
        .enumerate()
        .filter(|(_, d)| {
            ((d.causality == Causality::Output || d.derivative_of.is_some() || is_state(d))
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

/// A flat name has no structure (`der(x)`, `a.b`, `a[1]` ask for "structured").
fn is_flat_name(name: &str) -> bool {
    !name.contains(['.', '[', '('])
}

#[cfg(test)]
mod tests {
    use super::*;
    use rustfmu::description::{Start, Variable};

    const fn var(name: &'static str, vr: u32, min: Option<Bound>, max: Option<Bound>) -> Variable {
        Variable {
            name,
            value_reference: vr,
            var_type: VarType::Integer,
            causality: Causality::Parameter,
            variability: Variability::Fixed,
            initial: None,
            start: Start::Integer(5),
            unit: "",
            description: "",
            min,
            max,
            nominal: None,
            depends_on: None,
            derivative_of: None,
            enumeration: None,
        }
    }

    const VARS: &[Variable] = &[
        var(
            "inclusive",
            0,
            Some(Bound {
                value: 1.0,
                exclusive: false,
            }),
            Some(Bound {
                value: 9.0,
                exclusive: false,
            }),
        ),
        var(
            "exclusive",
            1,
            Some(Bound {
                value: 0.0,
                exclusive: true,
            }),
            Some(Bound {
                value: 10.0,
                exclusive: true,
            }),
        ),
    ];

    const D: ModelDescription = ModelDescription {
        model_identifier: "Bounds",
        description: "",
        author: "",
        version: "0",
        copyright: "",
        license: "",
        generation_tool: "test",
        default_experiment: None,
        units: &[],
        log_categories: &[],
        variables: VARS,
        internal_state: "",
    };

    #[test]
    fn integer_bounds_are_written_as_the_integers_inside_the_range() {
        let xml = fmi2(&D, Interfaces::CO_SIMULATION, "{guid}").unwrap();
        assert!(xml.contains(r#"<Integer min="1" max="9" start="5"/>"#), "{xml}");
        // > 0 and < 10: 1 ..= 9 (not 0 and 10, which the runtime refuses).
        let exclusive = xml.split("name=\"exclusive\"").nth(1).unwrap();
        assert!(
            exclusive.contains(r#"<Integer min="1" max="9" start="5"/>"#),
            "{exclusive}"
        );
    }

    #[test]
    fn an_exclusive_real_bound_is_written_as_the_nearest_legal_value() {
        assert_eq!(
            bound_value(
                Bound {
                    value: 0.0,
                    exclusive: true
                },
                true
            ),
            5e-324
        );
        assert_eq!(
            bound_value(
                Bound {
                    value: 1.0,
                    exclusive: true
                },
                false
            ),
            1.0f64.next_down()
        );
        assert_eq!(
            bound_value(
                Bound {
                    value: 1.0,
                    exclusive: false
                },
                false
            ),
            1.0
        );
    }
}
