//! `modelDescription.xml`, FMI 2.0 ([`fmi2`]) and FMI 3.0 ([`fmi3`]), written with quick-xml from
//! the typed description that the built library carries, each in the element order of its XSD.
//! Both come from the same decoded `ModelDescription`; only the encoding of the XML differs.

use fmi_standard::TypeKind;
use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use rustfmu::description::{
    Bound, Causality, FmiVersion, Initial, Interfaces, ModelDescription, NOT_SIZED, RUNTIME_LOG_CATEGORIES, Start,
    VarType, Variable,
};
use std::collections::BTreeSet;

/// Shortest text that reads back as the same f64 (Rust's `{:?}` is round-trip exact).
pub fn real_text(x: f64) -> String {
    format!("{x:?}")
}

/// Checks a decoded description against the rules of FMI 2.0 section 2.2.7 (FMI 3.0: 2.4.7)
/// once more (the derive macro enforces them at compile time; a description from elsewhere is
/// re-checked), with the same rules (`fmi-standard`) the derive uses. Structural parameters and
/// the arrays they size are FMI 3.0's only.
pub fn check_description(d: &ModelDescription, version: FmiVersion) -> Result<(), String> {
    let decls = d.variables;
    for name in d.event_indicators {
        match d.by_name(name) {
            Some(v)
                if v.var_type == VarType::Real && v.variability == rustfmu::description::Variability::Continuous => {}
            Some(v) => {
                return Err(format!(
                    "event indicator '{name}' (vr {}) is not a continuous Real variable",
                    v.value_reference
                ));
            }
            None => return Err(format!("event indicator '{name}' is no variable of the model")),
        }
    }
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
        let kind = if v.var_type.is_float() {
            TypeKind::Real
        } else {
            TypeKind::Other
        };
        if !fmi_standard::legal_variability_for_type(kind, v.variability) {
            return Err(format!("{at}: only Real variables may be continuous"));
        }
        if !v.unit.is_empty() && !d.units.iter().any(|u| u.name == v.unit) {
            return Err(format!("{at}: unit '{}' is not declared", v.unit));
        }
        if v.var_type == VarType::Enumeration && v.enumeration.is_none() {
            return Err(format!("{at}: an Enumeration variable without its type"));
        }
        if version == FmiVersion::V2 && !v.causality.in_fmi2() {
            // FMI 2.0 has no structural parameters (a model with some is FMI 3.0 only).
            return Err(format!("{at}: causality {:?} is FMI 3.0's only", v.causality));
        }
        if v.is_sized() {
            if version == FmiVersion::V2 {
                return Err(format!(
                    "{at}: an array sized by structural parameters is FMI 3.0's only"
                ));
            }
            array_sizes(d, v).map_err(|e| format!("{at}: {e}"))?;
        }
        if !fmi_standard::legal_variability(v.causality, v.variability) {
            return Err(format!(
                "{at}: causality {:?} with variability {:?} is not allowed",
                v.causality, v.variability
            ));
        }
        if let Some(i) = v.initial
            && !fmi_standard::legal_initial(v.causality, v.variability, i)
        {
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
        for dep in v.depends_on.unwrap_or(&[]) {
            if !decls
                .iter()
                .any(|o| o.name == *dep && (o.causality == Causality::Input || d.is_state(o)))
            {
                return Err(format!(
                    "{at}: depends on '{dep}', which is neither an input nor a continuous state"
                ));
            }
        }
        // The knowns of Initialization Mode: inputs, the independent variable and the variables
        // with initial = exact (parameters among them).
        for dep in v.initial_depends_on.unwrap_or(&[]) {
            if !decls.iter().any(|o| {
                o.name == *dep
                    && (matches!(o.causality, Causality::Input | Causality::Independent)
                        || o.effective_initial() == Some(Initial::Exact))
            }) {
                return Err(format!(
                    "{at}: initially depends on '{dep}', which is neither an input nor a variable with initial = exact"
                ));
            }
        }
        if v.initial_depends_on.is_some() && !d.is_initial_unknown(v) {
            return Err(format!(
                "{at}: declares initial dependencies but is no unknown of Initialization Mode"
            ));
        }
        if let Some(state) = v.derivative_of
            && !decls.iter().any(|o| o.name == state)
        {
            return Err(format!("{at}: derivative of '{state}', which is not declared"));
        }
    }
    check_display_units_and_aliases(d, version)
}

/// The display units and aliases once more: a unit's display units have distinct names, an
/// inverse one (FMI 3.0 only) has no offset; a variable and its aliases show their value in a
/// display unit of the variable's unit; alias names are unique among variables and aliases.
fn check_display_units_and_aliases(d: &ModelDescription, version: FmiVersion) -> Result<(), String> {
    for u in d.units {
        for (i, du) in u.display_units.iter().enumerate() {
            let at = format!("display unit '{}' of unit '{}'", du.name, u.name);
            if u.display_units[..i].iter().any(|o| o.name == du.name) {
                return Err(format!("{at}: declared twice"));
            }
            if du.inverse && version == FmiVersion::V2 {
                return Err(format!("{at}: inverse, which FMI 2.0 has not"));
            }
            if du.inverse && du.offset != 0.0 {
                return Err(format!("{at}: inverse with an offset (FMI 3.0, 2.4.3)"));
            }
            if !du.factor.is_finite() || du.factor == 0.0 || !du.offset.is_finite() {
                return Err(format!("{at}: factor and offset are finite numbers, the factor not 0"));
            }
        }
    }
    let mut names: BTreeSet<&str> = d.variables.iter().map(|v| v.name).collect();
    for v in d.variables {
        let shows = |du: &str, who: &str| -> Result<(), String> {
            if du.is_empty() {
                return Ok(());
            }
            match d.units.iter().find(|u| u.name == v.unit && !v.unit.is_empty()) {
                Some(u) if u.display_units.iter().any(|x| x.name == du) => Ok(()),
                _ => Err(format!(
                    "{who}: display unit '{du}' is no display unit of the variable's unit '{}'",
                    v.unit
                )),
            }
        };
        let at = format!("variable '{}' (vr {})", v.name, v.value_reference);
        shows(v.display_unit, &at)?;
        for a in v.aliases {
            let who = format!("alias '{}' of {at}", a.name);
            if !names.insert(a.name) {
                return Err(format!("{who}: the name of another variable or alias"));
            }
            shows(a.display_unit, &who)?;
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

/// `<UnitDefinitions>` (the same in FMI 2.0 and 3.0): the units the variables use, in name order.
fn unit_definitions(w: &mut Xml, d: &ModelDescription) -> Result<(), String> {
    let decls = d.variables;
    // Units in name order, as before (the derive lists them in order of first use).
    let mut units: Vec<_> = d
        .units
        .iter()
        .filter(|u| decls.iter().any(|v| v.unit == u.name))
        .collect();
    units.sort_by(|a, b| a.name.cmp(b.name));
    if !units.is_empty() {
        open(w, "UnitDefinitions", &[])?;
        for unit in &units {
            let b = unit.base;
            open(w, "Unit", &[("name", unit.name)])?;
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
            empty(w, "BaseUnit", &attrs)?;
            // display = factor · value + offset (FMI 3.0 also: inverse, factor / value).
            for du in unit.display_units {
                let (factor, offset) = (real_text(du.factor), real_text(du.offset));
                let mut attrs = vec![("name", du.name)];
                if du.factor != 1.0 {
                    attrs.push(("factor", &factor));
                }
                if du.offset != 0.0 {
                    attrs.push(("offset", &offset));
                }
                if du.inverse {
                    attrs.push(("inverse", "true"));
                }
                empty(w, "DisplayUnit", &attrs)?;
            }
            close(w, "Unit")?;
        }
        close(w, "UnitDefinitions")?;
    }

    Ok(())
}

/// `<LogCategories>`: the runtime's, then the model's. The runtime's say which status they come
/// with, in the names of the version the binary implements.
fn log_categories(w: &mut Xml, d: &ModelDescription, version: FmiVersion) -> Result<(), String> {
    open(w, "LogCategories", &[])?;
    for (i, c) in d.all_log_categories().enumerate() {
        let description = match version {
            FmiVersion::V3 if i < RUNTIME_LOG_CATEGORIES.len() => c.description.replace("fmi2", "fmi3"),
            _ => c.description.to_string(),
        };
        empty(w, "Category", &[("name", c.name), ("description", &description)])?;
    }
    close(w, "LogCategories")
}

/// `<DefaultExperiment>` (the same in FMI 2.0 and 3.0), if the model declares one.
fn default_experiment(w: &mut Xml, d: &ModelDescription) -> Result<(), String> {
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
        empty(w, "DefaultExperiment", &attrs)?;
    }
    Ok(())
}

/// An FMI 3.0 array's lengths at the start: per dimension, the capacity (its `<Dimension
/// start>`), or for one set by a structural parameter that parameter's start value. Checks what
/// the sizes rest on: one entry of `sized_by` per dimension, each naming a UInt64 structural
/// parameter (FMI 3.0, 2.4.7.6) whose start and `max` are within the capacity, and a start of
/// the whole capacity where the array has one.
pub fn array_sizes(d: &ModelDescription, v: &Variable) -> Result<Vec<usize>, String> {
    let capacities = v.fmi3.dimensions;
    if !v.is_sized() {
        return Ok(capacities.iter().map(|&n| n as usize).collect());
    }
    if v.fmi3.sized_by.len() != capacities.len() {
        return Err(format!(
            "{} dimension(s), {} structural parameter entries (one per dimension)",
            capacities.len(),
            v.fmi3.sized_by.len()
        ));
    }
    let mut sizes = Vec::with_capacity(capacities.len());
    for (&capacity, &vr) in capacities.iter().zip(v.fmi3.sized_by) {
        if vr == NOT_SIZED {
            sizes.push(capacity as usize);
            continue;
        }
        let p = d
            .variables
            .iter()
            .find(|p| p.value_reference == vr)
            .ok_or_else(|| format!("a length is set by value reference {vr}, which is no variable"))?;
        if p.var_type != VarType::UInt64 || p.causality != Causality::StructuralParameter {
            return Err(format!(
                "a length is set by '{}' (vr {vr}), which is not a UInt64 structural parameter (FMI 3.0, 2.4.7.6)",
                p.name
            ));
        }
        let Start::UInt64(start) = p.start else {
            return Err(format!("'{}', which sets a length, has no UInt64 start value", p.name));
        };
        match p.max {
            Some(max) if max.value <= capacity as f64 => {}
            Some(max) => {
                return Err(format!(
                    "'{}' sets a length of capacity {capacity} with max {}",
                    p.name,
                    real_text(max.value)
                ));
            }
            None => {
                return Err(format!("'{}' sets a length of capacity {capacity} without max", p.name));
            }
        }
        if start > u64::from(capacity) {
            return Err(format!(
                "'{}' starts at {start}, beyond the capacity {capacity} of the length it sets",
                p.name
            ));
        }
        sizes.push(start as usize);
    }
    if let Start::Array(items) = v.start
        && items.len() != v.element_count()
    {
        return Err(format!(
            "{} start values for a capacity of {} elements",
            items.len(),
            v.element_count()
        ));
    }
    Ok(sizes)
}

/// The start values an FMI 3.0 array lists: those of the elements within `sizes` (the lengths
/// at the start, [`array_sizes`]), in row-major order, taken from `items`, the start values of
/// the whole capacity (`capacities`) in row-major order. With every length at its capacity:
/// all of them.
fn active_items<'a>(items: &'a [Start], capacities: &[u32], sizes: &[usize]) -> Vec<&'a Start> {
    let count: usize = sizes.iter().product();
    let mut out = Vec::with_capacity(count);
    let mut index = vec![0usize; sizes.len()];
    for _ in 0..count {
        // The element's place in the capacity's row-major storage.
        let at = index
            .iter()
            .zip(capacities)
            .fold(0usize, |at, (&i, &c)| at * c as usize + i);
        out.extend(items.get(at));
        // The next index, the last dimension fastest.
        for k in (0..sizes.len()).rev() {
            index[k] += 1;
            if index[k] < sizes[k] {
                break;
            }
            index[k] = 0;
        }
    }
    out
}

/// `modelDescription.xml` (FMI 2.0) of a description, in the element order of the XSD.
pub fn fmi2(d: &ModelDescription, interfaces: Interfaces, guid: &str) -> Result<String, String> {
    if interfaces.version != FmiVersion::V2 {
        return Err(format!(
            "{}: the binary implements FMI {}, not 2.0 (its functions are not fmi2*)",
            d.model_identifier,
            interfaces.version.text()
        ));
    }
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
    let n_event_indicators = d.event_indicators.len().to_string();
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
                ("canBeInstantiatedOnlyOncePerProcess", "false"),
                ("canNotUseMemoryManagementFunctions", "true"),
                ("canGetAndSetFMUstate", "true"),
                ("canSerializeFMUstate", "true"),
                ("providesDirectionalDerivative", "true"),
            ],
        )?;
    }

    unit_definitions(&mut w, d)?;

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

    log_categories(&mut w, d, FmiVersion::V2)?;
    default_experiment(&mut w, d)?;

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
            // Not FMI 2.0 types (refused above).
            Start::Int64(_) | Start::UInt64(_) | Start::Binary(_) | Start::Array(_) | Start::None => String::new(),
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
        empty(&mut w, &format!("{:?}", v.var_type), &type_attrs)?;
        close(&mut w, "ScalarVariable")?;
    }
    fmi2_aliases(&mut w, decls)?;
    close(&mut w, "ModelVariables")?;

    let index_of = |name: &str| decls.iter().position(|d| d.name == name).map(|i| i + 1);
    // dependencies: indices of the knowns, "ordered according to size" (FMI 2.0, 3.3.1).
    let indices = |deps: &[&str]| {
        let set: BTreeSet<usize> = deps.iter().filter_map(|n| index_of(n)).collect();
        set.into_iter().map(|i| i.to_string()).collect::<Vec<_>>().join(" ")
    };
    let unknown = |w: &mut Xml, i: usize, v: &Variable| -> Result<(), String> {
        let index = (i + 1).to_string();
        let deps = v.depends_on.map(indices);
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
    let initial_unknowns: Vec<(usize, &Variable)> = decls
        .iter()
        .enumerate()
        .filter(|(_, v)| d.is_initial_unknown(v))
        .collect();
    if !initial_unknowns.is_empty() {
        open(&mut w, "InitialUnknowns", &[])?;
        for (i, v) in initial_unknowns {
            let index = (i + 1).to_string();
            let deps = v.initial_depends_on.map(indices);
            let mut attrs = vec![("index", index.as_str())];
            if let Some(deps) = &deps {
                attrs.push(("dependencies", deps));
            }
            empty(&mut w, "Unknown", &attrs)?;
        }
        close(&mut w, "InitialUnknowns")?;
    }
    close(&mut w, "ModelStructure")?;
    close(&mut w, "fmiModelDescription")?;
    let mut text = String::from_utf8(w.into_inner()).map_err(io)?;
    text.push('\n');
    Ok(text)
}

/// The aliases in FMI 2.0: after the declared variables (whose indices stay as they are), one
/// `<ScalarVariable>` per alias with the value reference, type, variability, unit and bounds of
/// its variable. FMI 2.0 (2.2.7) has an alias set share one value reference; at most one of the
/// set may be set by the importer and at most one carry a start value (a constant's aliases all
/// carry its value), and every output is listed in `<Outputs>`: so an alias is a `local` whose
/// `initial` is the default, calculated (a constant's: exact, with the constant's value).
fn fmi2_aliases(w: &mut Xml, decls: &[Variable]) -> Result<(), String> {
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
            let integer = matches!(v.var_type, VarType::Integer | VarType::Enumeration);
            let bound_text = |b: Bound, is_min: bool| {
                let x = bound_value(b, is_min);
                if integer {
                    (if is_min { x.ceil() } else { x.floor() } as i64).to_string()
                } else {
                    real_text(x)
                }
            };
            if let Some(b) = v.min {
                type_attrs.push(("min", bound_text(b, true)));
            }
            if let Some(b) = v.max {
                type_attrs.push(("max", bound_text(b, false)));
            }
            if let Some(n) = v.nominal {
                type_attrs.push(("nominal", real_text(n)));
            }
            if v.variability == rustfmu::description::Variability::Constant {
                let start = match v.start {
                    Start::Real(x) => real_text(x),
                    Start::Integer(x) => x.to_string(),
                    Start::Boolean(x) => x.to_string(),
                    Start::String(s) => s.to_string(),
                    _ => String::new(),
                };
                type_attrs.push(("start", start));
            }
            let type_attrs: Vec<(&str, &str)> = type_attrs.iter().map(|(k, v)| (*k, v.as_str())).collect();
            empty(w, &format!("{:?}", v.var_type), &type_attrs)?;
            close(w, "ScalarVariable")?;
        }
    }
    Ok(())
}

/// `modelDescription.xml` (FMI 3.0) of a description, in the element order of the FMI 3.0 XSD
/// (`fmi3ModelDescription.xsd`). `token` is the `instantiationToken`: the GUID of the FMI 3.0
/// binary's encoding. Variables are referred to by value reference throughout (`derivative`,
/// `ModelStructure`); the independent variable `time` is listed first unless the model declares
/// its own.
pub fn fmi3(d: &ModelDescription, interfaces: Interfaces, token: &str) -> Result<String, String> {
    if interfaces.version != FmiVersion::V3 {
        return Err(format!(
            "{}: the binary implements FMI {}, not 3.0 (its functions are not fmi3*)",
            d.model_identifier,
            interfaces.version.text()
        ));
    }
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
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .map_err(io)?;
    let mut root = vec![
        ("fmiVersion", "3.0"),
        ("modelName", d.model_identifier),
        ("instantiationToken", token),
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
    open(&mut w, "fmiModelDescription", &root)?;
    if interfaces.model_exchange {
        empty(
            &mut w,
            "ModelExchange",
            &[
                ("modelIdentifier", d.model_identifier),
                ("canGetAndSetFMUState", "true"),
                ("canSerializeFMUState", "true"),
                ("providesDirectionalDerivatives", "true"),
                ("providesAdjointDerivatives", "true"),
            ],
        )?;
    }
    if interfaces.co_simulation {
        empty(
            &mut w,
            "CoSimulation",
            &[
                ("modelIdentifier", d.model_identifier),
                ("canHandleVariableCommunicationStepSize", "true"),
                ("canGetAndSetFMUState", "true"),
                ("canSerializeFMUState", "true"),
                ("providesDirectionalDerivatives", "true"),
                ("providesAdjointDerivatives", "true"),
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
            ],
        )?;
    }
    if interfaces.scheduled_execution {
        // Partitions activated with fmi3ActivateModelPartition in Clock Activation Mode; FMU
        // states there (no directional derivatives: they are not offered between activations).
        empty(
            &mut w,
            "ScheduledExecution",
            &[
                ("modelIdentifier", d.model_identifier),
                ("canGetAndSetFMUState", "true"),
                ("canSerializeFMUState", "true"),
            ],
        )?;
    }
    unit_definitions(&mut w, d)?;

    let enums = d.enumerations();
    if !enums.is_empty() {
        open(&mut w, "TypeDefinitions", &[])?;
        for e in &enums {
            let mut attrs = vec![("name", e.name)];
            if !e.description.is_empty() {
                attrs.push(("description", e.description));
            }
            open(&mut w, "EnumerationType", &attrs)?;
            for item in e.items {
                let value = item.value.to_string();
                let mut attrs = vec![("name", item.name), ("value", value.as_str())];
                if !item.description.is_empty() {
                    attrs.push(("description", item.description));
                }
                empty(&mut w, "Item", &attrs)?;
            }
            close(&mut w, "EnumerationType")?;
        }
        close(&mut w, "TypeDefinitions")?;
    }

    log_categories(&mut w, d, FmiVersion::V3)?;
    default_experiment(&mut w, d)?;

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
    let vr_of = |name: &str| decls.iter().find(|o| o.name == name).map(|o| o.value_reference);
    for v in decls {
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
        // Integer and Enumeration bounds are integers (xs:int, xs:long); an exclusive one moves
        // to the next integer inside the range.
        let bound_text = |b: Bound, is_min: bool| match v.var_type {
            t if t.is_integer() || t == VarType::Enumeration => {
                let x = bound_value(b, is_min);
                (if is_min { x.ceil() } else { x.floor() } as i128).to_string()
            }
            // A Float32 bound is written as the f32 it is.
            VarType::Float32 => format!("{:?}", bound_value(b, is_min) as f32),
            _ => real_text(bound_value(b, is_min)),
        };
        let min = v.min.map(|b| bound_text(b, true));
        let max = v.max.map(|b| bound_text(b, false));
        let nominal = v.nominal.map(real_text);
        let scalar_text = |start: &Start| match *start {
            Start::Real(x) if v.var_type == VarType::Float32 => Some(format!("{:?}", x as f32)),
            Start::Real(x) => Some(real_text(x)),
            Start::Integer(x) => Some(x.to_string()),
            Start::Int64(x) => Some(x.to_string()),
            Start::UInt64(x) => Some(x.to_string()),
            Start::Boolean(x) => Some(x.to_string()),
            // A String's and a Binary's start is a child element.
            Start::String(_) | Start::Binary(_) | Start::Array(_) | Start::None => None,
        };
        // An array's start: its elements' in row-major order, separated by spaces; of an array
        // sized by structural parameters, those of the elements at the parameters' start values.
        let start = match v.start {
            Start::Array(items) => {
                let sizes = array_sizes(d, v).map_err(|e| format!("variable '{}': {e}", v.name))?;
                let items = active_items(items, v.fmi3.dimensions, &sizes);
                Some(items.into_iter().filter_map(scalar_text).collect::<Vec<_>>().join(" "))
            }
            ref one => scalar_text(one),
        };
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
            empty(&mut w, element, &attrs)?;
            continue;
        }
        open(&mut w, element, &attrs)?;
        // A fixed length, or the value reference of the structural parameter that sets it.
        for (k, n) in v.fmi3.dimensions.iter().enumerate() {
            match v.fmi3.sized_by.get(k) {
                Some(&vr) if vr != NOT_SIZED => empty(&mut w, "Dimension", &[("valueReference", &vr.to_string())])?,
                _ => empty(&mut w, "Dimension", &[("start", &n.to_string())])?,
            }
        }
        if let Some(value) = &start_child {
            empty(&mut w, "Start", &[("value", value)])?;
        }
        for a in v.aliases {
            let mut alias = vec![("name", a.name)];
            if !a.description.is_empty() {
                alias.push(("description", a.description));
            }
            if !a.display_unit.is_empty() {
                alias.push(("displayUnit", a.display_unit));
            }
            empty(&mut w, "Alias", &alias)?;
        }
        close(&mut w, element)?;
    }
    close(&mut w, "ModelVariables")?;

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
    open(&mut w, "ModelStructure", &[])?;
    for v in decls.iter().filter(|v| v.causality == Causality::Output) {
        unknown(&mut w, "Output", v, v.depends_on)?;
    }
    for v in decls.iter().filter(|v| v.derivative_of.is_some()) {
        unknown(&mut w, "ContinuousStateDerivative", v, v.depends_on)?;
    }
    for v in decls.iter().filter(|v| d.is_initial_unknown(v)) {
        unknown(&mut w, "InitialUnknown", v, v.initial_depends_on)?;
    }
    for name in d.event_indicators {
        let v = d
            .by_name(name)
            .ok_or_else(|| format!("{}: event indicator '{name}' is no variable", d.model_identifier))?;
        unknown(&mut w, "EventIndicator", v, v.depends_on)?;
    }
    close(&mut w, "ModelStructure")?;
    close(&mut w, "fmiModelDescription")?;
    let mut text = String::from_utf8(w.into_inner()).map_err(io)?;
    text.push('\n');
    Ok(text)
}

/// `terminalsAndIcons/terminalsAndIcons.xml` (FMI 3.0, 2.4.9) of a description with terminals,
/// in the order of `fmi3TerminalsAndIcons.xsd`; `None` without terminals. Every member names a
/// variable of the description (checked here, as the derive checked it).
pub fn terminals_and_icons(d: &ModelDescription) -> Result<Option<String>, String> {
    if d.terminals.is_empty() {
        return Ok(None);
    }
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .map_err(io)?;
    open(&mut w, "fmiTerminalsAndIcons", &[("fmiVersion", "3.0")])?;
    open(&mut w, "Terminals", &[])?;
    for t in d.terminals {
        let mut attrs = vec![("name", t.name), ("matchingRule", t.matching_rule)];
        if !t.kind.is_empty() {
            attrs.push(("terminalKind", t.kind));
        }
        if !t.description.is_empty() {
            attrs.push(("description", t.description));
        }
        open(&mut w, "Terminal", &attrs)?;
        for m in t.members {
            if d.by_name(m.variable).is_none() {
                return Err(format!(
                    "{}: terminal '{}': member '{}' names '{}', which is no variable",
                    d.model_identifier, t.name, m.member, m.variable
                ));
            }
            empty(
                &mut w,
                "TerminalMemberVariable",
                &[
                    ("variableName", m.variable),
                    ("memberName", m.member),
                    ("variableKind", m.kind),
                ],
            )?;
        }
        close(&mut w, "Terminal")?;
    }
    close(&mut w, "Terminals")?;
    close(&mut w, "fmiTerminalsAndIcons")?;
    let mut text = String::from_utf8(w.into_inner()).map_err(io)?;
    text.push('\n');
    Ok(Some(text))
}

/// A flat name has no structure (`der(x)`, `a.b`, `a[1]` ask for "structured").
fn is_flat_name(name: &str) -> bool {
    !name.contains(['.', '[', '('])
}

#[cfg(test)]
mod tests {
    use super::*;
    use rustfmu::description::{Start, Variability, Variable};

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
            display_unit: "",
            aliases: &[],
            description: "",
            min,
            max,
            nominal: None,
            depends_on: None,
            initial_depends_on: None,
            derivative_of: None,
            enumeration: None,
            fmi3: rustfmu::description::Fmi3Extras::NONE,
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
        event_indicators: &[],
        terminals: &[],
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

    // ---- FMI 3.0 ------------------------------------------------------------------------

    use rustfmu::description::{BaseUnit, DefaultExperiment, EnumItem, EnumType, Unit};

    const MODE: EnumType = EnumType {
        name: "Mode",
        description: "How it runs",
        items: &[
            EnumItem {
                name: "off",
                value: 0,
                description: "Off",
            },
            EnumItem {
                name: "on",
                value: 1,
                description: "",
            },
        ],
    };

    const fn v3(
        name: &'static str,
        vr: u32,
        var_type: VarType,
        causality: Causality,
        variability: Variability,
    ) -> Variable {
        Variable {
            name,
            value_reference: vr,
            var_type,
            causality,
            variability,
            initial: None,
            start: Start::None,
            unit: "",
            display_unit: "",
            aliases: &[],
            description: "",
            min: None,
            max: None,
            nominal: None,
            depends_on: None,
            initial_depends_on: None,
            derivative_of: None,
            enumeration: None,
            fmi3: rustfmu::description::Fmi3Extras::NONE,
        }
    }

    const LAG_VARS: &[Variable] = &[
        Variable {
            start: Start::Real(0.5),
            unit: "s",
            description: "Input u",
            ..v3("u", 0, VarType::Real, Causality::Input, Variability::Continuous)
        },
        Variable {
            initial: Some(Initial::Exact),
            start: Start::Real(1.0),
            nominal: Some(2.0),
            depends_on: Some(&["y"]),
            initial_depends_on: None,
            ..v3("y", 7, VarType::Real, Causality::Output, Variability::Continuous)
        },
        Variable {
            depends_on: Some(&["y", "u"]),
            initial_depends_on: None,
            derivative_of: Some("y"),
            ..v3("der(y)", 3, VarType::Real, Causality::Local, Variability::Continuous)
        },
        Variable {
            depends_on: Some(&[]),
            initial_depends_on: None,
            ..v3("z", 9, VarType::Real, Causality::Output, Variability::Continuous)
        },
        Variable {
            start: Start::String("a <b> & \"c\""),
            ..v3("label", 4, VarType::String, Causality::Parameter, Variability::Fixed)
        },
        Variable {
            start: Start::Boolean(true),
            ..v3("flag", 5, VarType::Boolean, Causality::Parameter, Variability::Tunable)
        },
        Variable {
            start: Start::Integer(1),
            enumeration: Some(&MODE),
            ..v3(
                "mode",
                6,
                VarType::Enumeration,
                Causality::Parameter,
                Variability::Fixed,
            )
        },
        Variable {
            start: Start::Integer(3),
            min: Some(Bound {
                value: 0.0,
                exclusive: true,
            }),
            max: Some(Bound {
                value: 10.0,
                exclusive: false,
            }),
            ..v3("n", 2, VarType::Integer, Causality::Parameter, Variability::Fixed)
        },
        v3(
            "k",
            8,
            VarType::Real,
            Causality::CalculatedParameter,
            Variability::Fixed,
        ),
    ];

    const LAG: ModelDescription = ModelDescription {
        model_identifier: "Lag",
        description: "A lag",
        author: "me",
        version: "1.0",
        copyright: "",
        license: "MIT",
        generation_tool: "test",
        default_experiment: Some(DefaultExperiment {
            start_time: Some(0.0),
            stop_time: Some(1.0),
            tolerance: None,
            step_size: Some(0.01),
        }),
        units: &[Unit {
            name: "s",
            base: BaseUnit {
                kg: 0,
                m: 0,
                s: 1,
                a: 0,
                k: 0,
                mol: 0,
                cd: 0,
                rad: 0,
                factor: 1.0,
                offset: 0.0,
            },
            display_units: &[],
        }],
        log_categories: &[],
        variables: LAG_VARS,
        internal_state: "",
        event_indicators: &[],
        terminals: &[],
    };

    fn lag3() -> String {
        fmi3(&LAG, Interfaces::BOTH_FMI3, "{token}").unwrap()
    }

    /// The text of the element that has `name="<name>"`.
    fn element<'a>(xml: &'a str, name: &str) -> &'a str {
        let at = xml
            .find(&format!("name=\"{name}\""))
            .unwrap_or_else(|| panic!("no {name} in {xml}"));
        let start = xml[..at].rfind('<').unwrap();
        let end = at + xml[at..].find("/>").unwrap() + 2;
        &xml[start..end]
    }

    #[test]
    fn fmi3_root_interfaces_and_the_order_of_the_schema() {
        let xml = lag3();
        assert!(xml.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"3.0\" modelName=\"Lag\" instantiationToken=\"{token}\" description=\"A lag\" author=\"me\" version=\"1.0\" license=\"MIT\" generationTool=\"test\" variableNamingConvention=\"structured\">"), "{xml}");
        assert!(
            !xml.contains("guid=") && !xml.contains("numberOfEventIndicators"),
            "{xml}"
        );
        assert!(xml.contains(r#"<ModelExchange modelIdentifier="Lag" canGetAndSetFMUState="true" canSerializeFMUState="true" providesDirectionalDerivatives="true" providesAdjointDerivatives="true"/>"#), "{xml}");
        assert!(xml.contains(r#"<CoSimulation modelIdentifier="Lag" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="true" canSerializeFMUState="true" providesDirectionalDerivatives="true" providesAdjointDerivatives="true" maxOutputDerivativeOrder="1" providesIntermediateUpdate="true" mightReturnEarlyFromDoStep="true" canReturnEarlyAfterIntermediateUpdate="true" hasEventMode="true"/>"#), "{xml}");
        let order = [
            "<ModelExchange ",
            "<CoSimulation ",
            "<UnitDefinitions>",
            "<TypeDefinitions>",
            "<LogCategories>",
            "<DefaultExperiment ",
            "<ModelVariables>",
            "<ModelStructure>",
        ];
        let at: Vec<usize> = order
            .iter()
            .map(|e| xml.find(e).unwrap_or_else(|| panic!("no {e}")))
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "{xml}");
        assert!(xml.contains("Messages that come with fmi3Error"), "{xml}");
        assert!(!xml.contains("fmi2"), "{xml}");
        assert!(
            xml.contains(r#"<DefaultExperiment startTime="0.0" stopTime="1.0" stepSize="0.01"/>"#),
            "{xml}"
        );
    }

    #[test]
    fn fmi3_variables_time_first_derivative_by_value_reference_string_start_child() {
        let xml = lag3();
        let vars = &xml[xml.find("<ModelVariables>").unwrap()..xml.find("</ModelVariables>").unwrap()];
        // time: one above the highest declared value reference (9), listed first.
        let first = vars.lines().nth(1).unwrap().trim();
        assert_eq!(
            first,
            r#"<Float64 name="time" valueReference="10" description="Simulation time" causality="independent" variability="continuous"/>"#
        );
        assert_eq!(
            element(vars, "u"),
            r#"<Float64 name="u" valueReference="0" description="Input u" causality="input" variability="continuous" unit="s" start="0.5"/>"#
        );
        assert_eq!(
            element(vars, "y"),
            r#"<Float64 name="y" valueReference="7" causality="output" variability="continuous" initial="exact" nominal="2.0" start="1.0"/>"#
        );
        // derivative names the state's value reference (7), not its index.
        assert_eq!(
            element(vars, "der(y)"),
            r#"<Float64 name="der(y)" valueReference="3" causality="local" variability="continuous" derivative="7"/>"#
        );
        assert!(
            vars.contains("<String name=\"label\" valueReference=\"4\" causality=\"parameter\" variability=\"fixed\">\n      <Start value=\"a &lt;b&gt; &amp; &quot;c&quot;\"/>\n    </String>"),
            "{vars}"
        );
        assert_eq!(
            element(vars, "flag"),
            r#"<Boolean name="flag" valueReference="5" causality="parameter" variability="tunable" start="true"/>"#
        );
        assert_eq!(
            element(vars, "mode"),
            r#"<Enumeration name="mode" valueReference="6" causality="parameter" variability="fixed" declaredType="Mode" start="1"/>"#
        );
        // > 0 and <= 10: 1 ..= 10, as integers.
        assert_eq!(
            element(vars, "n"),
            r#"<Int32 name="n" valueReference="2" causality="parameter" variability="fixed" min="1" max="10" start="3"/>"#
        );
        assert_eq!(
            element(vars, "k"),
            r#"<Float64 name="k" valueReference="8" causality="calculatedParameter" variability="fixed"/>"#
        );
        assert!(xml.contains("<TypeDefinitions>\n    <EnumerationType name=\"Mode\" description=\"How it runs\">\n      <Item name=\"off\" value=\"0\" description=\"Off\"/>\n      <Item name=\"on\" value=\"1\"/>\n    </EnumerationType>\n  </TypeDefinitions>"), "{xml}");
    }

    #[test]
    fn fmi3_model_structure_by_value_reference() {
        let xml = lag3();
        let ms = &xml[xml.find("<ModelStructure>").unwrap()..];
        let expected = r#"<ModelStructure>
    <Output valueReference="7" dependencies="7" dependenciesKind="dependent"/>
    <Output valueReference="9" dependencies="" dependenciesKind=""/>
    <ContinuousStateDerivative valueReference="3" dependencies="0 7" dependenciesKind="dependent dependent"/>
    <InitialUnknown valueReference="3"/>
    <InitialUnknown valueReference="9"/>
    <InitialUnknown valueReference="8"/>
  </ModelStructure>
</fmiModelDescription>
"#;
        assert_eq!(ms, expected);
    }

    #[test]
    fn a_declared_independent_variable_replaces_time() {
        const VARS: &[Variable] = &[
            v3("t", 0, VarType::Real, Causality::Independent, Variability::Continuous),
            Variable {
                start: Start::Real(1.0),
                ..v3("p", 1, VarType::Real, Causality::Parameter, Variability::Fixed)
            },
        ];
        let d = ModelDescription { variables: VARS, ..LAG };
        let xml = fmi3(&d, Interfaces::BOTH_FMI3, "{token}").unwrap();
        assert!(!xml.contains("name=\"time\""), "{xml}");
        assert!(
            xml.contains(r#"<Float64 name="t" valueReference="0" causality="independent" variability="continuous"/>"#),
            "{xml}"
        );
        assert!(xml.contains("variableNamingConvention=\"flat\""), "{xml}");
    }

    // ---- arrays sized by structural parameters (FMI 3.0) ---------------------------------

    /// A UInt64 structural parameter of start `start`, at most 3.
    const fn size(name: &'static str, vr: u32, start: u64) -> Variable {
        Variable {
            start: Start::UInt64(start),
            min: Some(Bound {
                value: 0.0,
                exclusive: false,
            }),
            max: Some(Bound {
                value: 3.0,
                exclusive: false,
            }),
            ..v3(
                name,
                vr,
                VarType::UInt64,
                Causality::StructuralParameter,
                Variability::Tunable,
            )
        }
    }

    /// 1 ..= 12, the start of a capacity of 3 x 4 (row-major: row i holds 4i+1 ..= 4i+4).
    const TWELVE: &[Start] = &[
        Start::Real(1.0),
        Start::Real(2.0),
        Start::Real(3.0),
        Start::Real(4.0),
        Start::Real(5.0),
        Start::Real(6.0),
        Start::Real(7.0),
        Start::Real(8.0),
        Start::Real(9.0),
        Start::Real(10.0),
        Start::Real(11.0),
        Start::Real(12.0),
    ];

    /// A parameter array of capacity `dims` sized by `sized_by`, start [`TWELVE`]'s first.
    const fn sized(name: &'static str, vr: u32, dims: &'static [u32], sized_by: &'static [u32]) -> Variable {
        Variable {
            start: Start::Array(TWELVE),
            fmi3: rustfmu::description::Fmi3Extras {
                only: true,
                dimensions: dims,
                sized_by,
                ..rustfmu::description::Fmi3Extras::NONE
            },
            ..v3(name, vr, VarType::Real, Causality::Parameter, Variability::Tunable)
        }
    }

    const SIZED_VARS: &[Variable] = &[
        size("m", 1, 2),
        size("n", 2, 3),
        // [m, n] of capacity [3, 4]: the first 2 rows, the first 3 columns of each.
        sized("A", 3, &[3, 4], &[1, 2]),
        // [n, 4] of capacity [3, 4]: the first 3 rows, all 4 columns.
        sized("B", 4, &[3, 4], &[2, NOT_SIZED]),
        // [m] of capacity 3 (the start: TWELVE's first 3).
        Variable {
            start: Start::Array(TWELVE.split_at(3).0),
            ..sized("u", 5, &[3], &[1])
        },
        // An output: no start.
        Variable {
            start: Start::None,
            causality: Causality::Output,
            variability: Variability::Continuous,
            ..sized("y", 6, &[3], &[2])
        },
    ];

    fn sized3(vars: &'static [Variable]) -> Result<String, String> {
        let d = ModelDescription { variables: vars, ..LAG };
        fmi3(&d, Interfaces::BOTH_FMI3, "{token}")
    }

    /// The text of the array element that has `name="<name>"`, up to its end tag.
    fn array_element<'a>(xml: &'a str, name: &str) -> &'a str {
        let at = xml
            .find(&format!("name=\"{name}\""))
            .unwrap_or_else(|| panic!("no {name} in {xml}"));
        let start = xml[..at].rfind('<').unwrap();
        let end = at + xml[at..].find("</Float64>").unwrap() + "</Float64>".len();
        &xml[start..end]
    }

    #[test]
    fn a_sized_array_names_its_structural_parameters_and_starts_at_their_start_sizes() {
        let xml = sized3(SIZED_VARS).unwrap();
        assert_eq!(
            element(&xml, "m"),
            r#"<UInt64 name="m" valueReference="1" causality="structuralParameter" variability="tunable" min="0" max="3" start="2"/>"#
        );
        // 2 x 3 of the 3 x 4 storage, row-major: (0,0..3), (1,0..3).
        assert_eq!(
            array_element(&xml, "A"),
            "<Float64 name=\"A\" valueReference=\"3\" causality=\"parameter\" variability=\"tunable\" start=\"1.0 2.0 3.0 5.0 6.0 7.0\">\n      \
             <Dimension valueReference=\"1\"/>\n      <Dimension valueReference=\"2\"/>\n    </Float64>"
        );
        // A fixed length beside a sized one: <Dimension start>.
        assert_eq!(
            array_element(&xml, "B"),
            "<Float64 name=\"B\" valueReference=\"4\" causality=\"parameter\" variability=\"tunable\" \
             start=\"1.0 2.0 3.0 4.0 5.0 6.0 7.0 8.0 9.0 10.0 11.0 12.0\">\n      \
             <Dimension valueReference=\"2\"/>\n      <Dimension start=\"4\"/>\n    </Float64>"
        );
        assert!(array_element(&xml, "u").contains(r#"start="1.0 2.0">"#), "{xml}");
        assert!(!array_element(&xml, "y").contains("start="), "{xml}");
        // What validation reads back: every length set by a UInt64 structural parameter, and as
        // many start values as elements at the start lengths.
        let d = fmi_description::fmi3::ModelDescription::parse(&xml).unwrap();
        assert_eq!(crate::validate::array_problems(&d), Vec::<String>::new());
    }

    #[test]
    fn a_sized_array_needs_a_uint64_structural_parameter_within_its_capacity() {
        // Sized by a parameter that is no structural parameter.
        const NOT_STRUCTURAL: &[Variable] = &[
            Variable {
                causality: Causality::Parameter,
                ..size("m", 1, 2)
            },
            sized("A", 3, &[3, 4], &[1, NOT_SIZED]),
        ];
        let e = sized3(NOT_STRUCTURAL).unwrap_err();
        assert!(
            e.contains("'m' (vr 1), which is not a UInt64 structural parameter"),
            "{e}"
        );
        // A max beyond the capacity (3 rows).
        const BEYOND: &[Variable] = &[
            Variable {
                max: Some(Bound {
                    value: 4.0,
                    exclusive: false,
                }),
                ..size("m", 1, 2)
            },
            sized("A", 3, &[3, 4], &[1, NOT_SIZED]),
        ];
        let e = sized3(BEYOND).unwrap_err();
        assert!(e.contains("capacity 3 with max 4"), "{e}");
        // Start values for other than the capacity.
        const SHORT: &[Variable] = &[
            size("m", 1, 2),
            Variable {
                start: Start::Array(TWELVE.split_at(6).0),
                ..sized("A", 3, &[3, 4], &[1, NOT_SIZED])
            },
        ];
        let e = sized3(SHORT).unwrap_err();
        assert!(e.contains("6 start values for a capacity of 12 elements"), "{e}");
        // FMI 2.0 has no structural parameters.
        let d = ModelDescription {
            variables: SIZED_VARS,
            ..LAG
        };
        let e = fmi2(&d, Interfaces::BOTH, "{guid}").unwrap_err();
        assert!(e.contains("FMI 3.0's only"), "{e}");
    }

    #[test]
    fn each_writer_takes_only_a_binary_of_its_version() {
        let e = fmi3(&LAG, Interfaces::BOTH, "{guid}").unwrap_err();
        assert!(e.contains("FMI 2.0, not 3.0"), "{e}");
        let e = fmi2(&LAG, Interfaces::BOTH_FMI3, "{guid}").unwrap_err();
        assert!(e.contains("FMI 3.0, not 2.0"), "{e}");
        // The same description in FMI 2.0: indices, no time.
        let xml2 = fmi2(&LAG, Interfaces::BOTH, "{guid}").unwrap();
        assert!(
            xml2.contains("derivative=\"2\"") && !xml2.contains("name=\"time\""),
            "{xml2}"
        );
        assert!(xml2.contains("Messages that come with fmi2Error"), "{xml2}");
    }
}

/// Display units and aliases through the encoding (as `cargo fmu` reads them from a library) into
/// both files.
#[cfg(test)]
mod alias_tests {
    use super::*;
    use rustfmu::description::{Alias, BaseUnit, DisplayUnit, Fmi3Extras, Unit, Variability, decode, encode_to_vec};

    const M: BaseUnit = BaseUnit {
        kg: 0,
        m: 1,
        s: 0,
        a: 0,
        k: 0,
        mol: 0,
        cd: 0,
        rad: 0,
        factor: 1.0,
        offset: 0.0,
    };

    const fn real(name: &'static str, vr: u32, causality: Causality, variability: Variability) -> Variable {
        Variable {
            name,
            value_reference: vr,
            var_type: VarType::Real,
            causality,
            variability,
            initial: None,
            start: Start::None,
            unit: "m",
            display_unit: "",
            aliases: &[],
            description: "",
            min: None,
            max: None,
            nominal: None,
            depends_on: None,
            initial_depends_on: None,
            derivative_of: None,
            enumeration: None,
            fmi3: Fmi3Extras::NONE,
        }
    }

    const VARS: &[Variable] = &[
        Variable {
            initial: Some(Initial::Exact),
            start: Start::Real(1.0),
            description: "Position of the ball",
            aliases: &[Alias {
                name: "h_ft",
                description: "Position in feet",
                display_unit: "ft",
            }],
            ..real("h", 1, Causality::Output, Variability::Continuous)
        },
        Variable {
            start: Start::Real(2.5),
            display_unit: "ft",
            description: "Length",
            aliases: &[Alias {
                name: "l2",
                description: "",
                display_unit: "",
            }],
            ..real("l", 2, Causality::Local, Variability::Constant)
        },
    ];

    const BALL: ModelDescription = ModelDescription {
        model_identifier: "Ball",
        description: "",
        author: "",
        version: "",
        copyright: "",
        license: "",
        generation_tool: "test",
        default_experiment: None,
        units: &[Unit {
            name: "m",
            base: M,
            display_units: &[DisplayUnit {
                name: "ft",
                factor: 3.280839895,
                offset: 0.0,
                inverse: false,
            }],
        }],
        log_categories: &[],
        variables: VARS,
        internal_state: "",
        event_indicators: &[],
        terminals: &[],
    };

    /// The description as `cargo fmu` gets it from a library of that version.
    fn decoded(interfaces: Interfaces) -> (ModelDescription, Interfaces) {
        decode(&encode_to_vec(&BALL, interfaces)).unwrap()
    }

    #[test]
    fn the_encoding_carries_display_units_and_aliases() {
        for interfaces in [Interfaces::BOTH, Interfaces::BOTH_FMI3] {
            let (d, back) = decoded(interfaces);
            assert_eq!(back, interfaces);
            assert_eq!(d.units, BALL.units);
            assert_eq!(d.variables, BALL.variables);
        }
        // Without display units and aliases, no trace of them: the encodings (and GUIDs) of the
        // models that declare none are those before they existed.
        const PLAIN_VARS: [Variable; 2] = [
            Variable {
                aliases: &[],
                ..VARS[0]
            },
            Variable {
                display_unit: "",
                aliases: &[],
                ..VARS[1]
            },
        ];
        const PLAIN_UNITS: [Unit; 1] = [Unit {
            display_units: &[],
            ..BALL.units[0]
        }];
        let plain = ModelDescription {
            units: &PLAIN_UNITS,
            variables: &PLAIN_VARS,
            ..BALL
        };
        let with = encode_to_vec(&BALL, Interfaces::BOTH);
        let without = encode_to_vec(&plain, Interfaces::BOTH);
        // The header (magic, format, payload length: 32 bytes) aside, the same bytes up to the
        // display units' block.
        assert!(with.len() > without.len());
        assert_eq!(
            &with[32..without.len()],
            &without[32..],
            "the encoding before the display units' block"
        );
    }

    #[test]
    fn fmi3_writes_the_display_unit_the_alias_and_the_variables_display_unit() {
        let (d, i) = decoded(Interfaces::BOTH_FMI3);
        let xml = fmi3(&d, i, "{token}").unwrap();
        assert!(
            xml.contains(
                "<Unit name=\"m\">\n      <BaseUnit m=\"1\"/>\n      <DisplayUnit name=\"ft\" factor=\"3.280839895\"/>\n    </Unit>"
            ),
            "{xml}"
        );
        assert!(
            xml.contains(
                "initial=\"exact\" unit=\"m\" start=\"1.0\">\n      <Alias name=\"h_ft\" description=\"Position in feet\" displayUnit=\"ft\"/>\n    </Float64>"
            ),
            "{xml}"
        );
        assert!(
            xml.contains("unit=\"m\" displayUnit=\"ft\" start=\"2.5\">\n      <Alias name=\"l2\"/>"),
            "{xml}"
        );
    }

    #[test]
    fn fmi2_writes_each_alias_as_a_local_of_the_same_value_reference_after_the_variables() {
        let (d, i) = decoded(Interfaces::BOTH);
        let xml = fmi2(&d, i, "{guid}").unwrap();
        assert!(
            xml.contains("<DisplayUnit name=\"ft\" factor=\"3.280839895\"/>"),
            "{xml}"
        );
        assert!(
            xml.contains("<Real unit=\"m\" displayUnit=\"ft\" start=\"2.5\"/>"),
            "{xml}"
        );
        // After the two variables: indices 3 and 4, h's and l's value references; the constant's
        // alias carries the constant's value, the other no start.
        assert!(
            xml.contains(
                "<!-- index 3 -->\n    <ScalarVariable name=\"h_ft\" valueReference=\"1\" description=\"Position in feet\" \
                 causality=\"local\" variability=\"continuous\">\n      <Real unit=\"m\" displayUnit=\"ft\"/>"
            ),
            "{xml}"
        );
        assert!(
            xml.contains(
                "<!-- index 4 -->\n    <ScalarVariable name=\"l2\" valueReference=\"2\" description=\"Length\" \
                 causality=\"local\" variability=\"constant\">\n      <Real unit=\"m\" start=\"2.5\"/>"
            ),
            "{xml}"
        );
        // The outputs are the declared ones only.
        assert!(
            xml.contains("<Outputs>\n      <Unknown index=\"1\"/>\n    </Outputs>"),
            "{xml}"
        );
    }

    #[test]
    fn wrong_display_units_and_aliases_are_refused_naming_them() {
        const CLASH: [Variable; 2] = [
            VARS[0],
            Variable {
                aliases: &[Alias {
                    name: "h",
                    description: "",
                    display_unit: "",
                }],
                ..VARS[1]
            },
        ];
        let e = fmi3(
            &ModelDescription {
                variables: &CLASH,
                ..BALL
            },
            Interfaces::BOTH_FMI3,
            "t",
        )
        .unwrap_err();
        assert!(
            e.contains("alias 'h' of variable 'l' (vr 2): the name of another variable or alias"),
            "{e}"
        );
        const UNKNOWN: [Variable; 1] = [Variable {
            display_unit: "yd",
            ..VARS[1]
        }];
        let e = fmi2(
            &ModelDescription {
                variables: &UNKNOWN,
                ..BALL
            },
            Interfaces::BOTH,
            "g",
        )
        .unwrap_err();
        assert!(
            e.contains("display unit 'yd' is no display unit of the variable's unit 'm'"),
            "{e}"
        );
        const INVERSE: [Unit; 1] = [Unit {
            display_units: &[DisplayUnit {
                inverse: true,
                ..BALL.units[0].display_units[0]
            }],
            ..BALL.units[0]
        }];
        let d = ModelDescription {
            units: &INVERSE,
            ..BALL
        };
        let e = fmi2(&d, Interfaces::BOTH, "g").unwrap_err();
        assert!(
            e.contains("display unit 'ft' of unit 'm': inverse, which FMI 2.0 has not"),
            "{e}"
        );
        assert!(
            fmi3(&d, Interfaces::BOTH_FMI3, "t")
                .unwrap()
                .contains("inverse=\"true\"")
        );
    }
}
