//! The container's modelDescription.xml (FMI 2.0 and 3.0), written from its [`Spec`]: the
//! exposed variables, the units and simple types the components define for them, the
//! capabilities every component shares.

use super::*;

impl Spec {
    /// The container's FMI 2.0 modelDescription.xml. `descriptions` are the components'
    /// (name, description, its modelDescription.xml text), in the system's order.
    /// `experiment`: the SSD's DefaultExperiment (start, stop), written with the step into the
    /// container's.
    pub fn model_description(
        &self,
        sim: &Simulation,
        system_name: &str,
        component_xml: &[(String, String)],
        experiment: (Option<f64>, Option<f64>),
    ) -> String {
        let esc = |s: &str| quick_xml::escape::escape(s).into_owned();
        let descriptions = sim.component_descriptions();
        let Header {
            name,
            description,
            state,
            serialize,
        } = self.header(sim, system_name);
        let mut x = String::new();
        let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
        let _ = writeln!(
            x,
            r#"<fmiModelDescription fmiVersion="2.0" modelName="{name}" guid="{}" description="{description}" generationTool="rustfmu-container {}" variableNamingConvention="structured" numberOfEventIndicators="0">"#,
            self.guid,
            env!("CARGO_PKG_VERSION")
        );
        let _ = writeln!(
            x,
            r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="{state}" canSerializeFMUstate="{serialize}" canNotUseMemoryManagementFunctions="true"/>"#,
            self.model_identifier
        );
        let (units, types) = self.definitions(sim, component_xml);
        write_units(&mut x, &units);
        if !types.is_empty() {
            let _ = writeln!(x, "  <TypeDefinitions>");
            for (_, b) in &types {
                let _ = writeln!(x, "    {}", b.trim());
            }
            let _ = writeln!(x, "  </TypeDefinitions>");
        }
        // The categories of the container's own messages (the components' go under logAll,
        // prefixed with the component's name), and the experiment.
        write_categories_and_experiment(&mut x, experiment, self.step);
        let _ = writeln!(x, "  <ModelVariables>");
        for e in &self.variables {
            let v = declaration(&descriptions, e);
            let description = v.and_then(|v| v.description.clone()).unwrap_or_default();
            let _ = write!(
                x,
                r#"    <ScalarVariable name="{}" valueReference="{}" causality="{}" variability="{}""#,
                esc(&e.name),
                e.vr,
                e.causality,
                e.variability
            );
            if !description.is_empty() {
                let _ = write!(x, r#" description="{}""#, esc(&description));
            }
            write_initial(&mut x, e);
            let _ = write!(x, ">\n      <{}", e.ty);
            write_type_attributes(&mut x, e, v);
            if let Some(s) = &e.start {
                let _ = write!(x, r#" start="{}""#, esc(s));
            }
            let _ = writeln!(x, "/>\n    </ScalarVariable>");
        }
        let _ = writeln!(x, "  </ModelVariables>");
        let _ = writeln!(x, "  <ModelStructure>");
        let outputs = self.outputs();
        if !outputs.is_empty() {
            let _ = writeln!(x, "    <Outputs>");
            for e in &outputs {
                let deps = self.output_dependencies(sim, e);
                let list: Vec<String> = deps.iter().map(|i| i.to_string()).collect();
                let _ = writeln!(
                    x,
                    r#"      <Unknown index="{}" dependencies="{}"/>"#,
                    e.vr + 1,
                    list.join(" ")
                );
            }
            let _ = writeln!(x, "    </Outputs>");
            let initial: Vec<&&Exposed> = outputs.iter().filter(|e| e.start.is_none()).collect();
            if !initial.is_empty() {
                let _ = writeln!(x, "    <InitialUnknowns>");
                for e in initial {
                    let _ = writeln!(x, r#"      <Unknown index="{}"/>"#, e.vr + 1);
                }
                let _ = writeln!(x, "    </InitialUnknowns>");
            }
        }
        let _ = writeln!(x, "  </ModelStructure>");
        let _ = writeln!(x, "</fmiModelDescription>");
        x
    }

    /// The container's FMI 3.0 modelDescription.xml (co-simulation): the variables of
    /// [`Spec::model_description`] in FMI 3.0's types (Real as Float64, Integer as Int32,
    /// Enumeration with its EnumerationType), the independent variable `time` after them (value
    /// reference: their count), the same units, output dependencies (as value references) and
    /// experiment; the GUID is the instantiation token.
    pub fn model_description3(
        &self,
        sim: &Simulation,
        system_name: &str,
        component_xml: &[(String, String)],
        experiment: (Option<f64>, Option<f64>),
    ) -> String {
        let esc = |s: &str| quick_xml::escape::escape(s).into_owned();
        let descriptions = sim.component_descriptions();
        let Header {
            name,
            description,
            state,
            serialize,
        } = self.header(sim, system_name);
        let mut x = String::new();
        let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
        let _ = writeln!(
            x,
            r#"<fmiModelDescription fmiVersion="3.0" modelName="{name}" instantiationToken="{}" description="{description}" generationTool="rustfmu-container {}" variableNamingConvention="structured">"#,
            self.guid,
            env!("CARGO_PKG_VERSION")
        );
        let _ = writeln!(
            x,
            r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="{state}" canSerializeFMUState="{serialize}" hasEventMode="false"/>"#,
            self.model_identifier
        );
        let (units, types) = self.definitions(sim, component_xml);
        write_units(&mut x, &units);
        let types: Vec<String> = types.iter().filter_map(|(_, b)| simple_type3(b)).collect();
        if !types.is_empty() {
            let _ = writeln!(x, "  <TypeDefinitions>");
            for b in &types {
                let _ = writeln!(x, "    {b}");
            }
            let _ = writeln!(x, "  </TypeDefinitions>");
        }
        write_categories_and_experiment(&mut x, experiment, self.step);
        let _ = writeln!(x, "  <ModelVariables>");
        let _ = writeln!(
            x,
            r#"    <Float64 name="time" valueReference="{}" causality="independent" variability="continuous" description="Simulation time"/>"#,
            self.time_vr()
        );
        for e in &self.variables {
            let v = declaration(&descriptions, e);
            let element = match e.ty() {
                Type::Real => "Float64",
                Type::Integer => "Int32",
                Type::Boolean => "Boolean",
                Type::String => "String",
                Type::Enumeration => "Enumeration",
            };
            let _ = write!(
                x,
                r#"    <{element} name="{}" valueReference="{}" causality="{}" variability="{}""#,
                esc(&e.name),
                e.vr,
                e.causality,
                e.variability
            );
            if let Some(description) = v.and_then(|v| v.description.as_deref())
                && !description.is_empty()
            {
                let _ = write!(x, r#" description="{}""#, esc(description));
            }
            write_initial(&mut x, e);
            write_type_attributes(&mut x, e, v);
            match (&e.start, e.ty()) {
                (Some(s), Type::String) => {
                    let _ = writeln!(x, ">\n      <Start value=\"{}\"/>\n    </String>", esc(s));
                }
                (Some(s), _) => {
                    let _ = writeln!(x, r#" start="{}"/>"#, esc(s));
                }
                (None, _) => {
                    let _ = writeln!(x, "/>");
                }
            }
        }
        let _ = writeln!(x, "  </ModelVariables>");
        let _ = writeln!(x, "  <ModelStructure>");
        let outputs = self.outputs();
        for e in &outputs {
            let deps: Vec<String> = self
                .output_dependencies(sim, e)
                .iter()
                .map(|i| (i - 1).to_string())
                .collect();
            let _ = writeln!(
                x,
                r#"    <Output valueReference="{}" dependencies="{}"/>"#,
                e.vr,
                deps.join(" ")
            );
        }
        for e in outputs.iter().filter(|e| e.start.is_none()) {
            let _ = writeln!(x, r#"    <InitialUnknown valueReference="{}"/>"#, e.vr);
        }
        let _ = writeln!(x, "  </ModelStructure>");
        let _ = writeln!(x, "</fmiModelDescription>");
        x
    }

    /// What both versions' headers say: the system's name and a description naming the
    /// components and the step (both escaped), and whether every component can get and set,
    /// and serialize, its FMU state.
    fn header(&self, sim: &Simulation, system_name: &str) -> Header {
        let esc = |s: &str| quick_xml::escape::escape(s).into_owned();
        let (state, serialize, names) = capabilities(sim);
        Header {
            name: esc(system_name),
            description: esc(&format!(
                "The system {system_name} as one FMU: {}, stepped by rustfmu-runner's master at {} s",
                names.join(", "),
                self.step
            )),
            state,
            serialize,
        }
    }

    /// The exposed outputs, in the container's order.
    fn outputs(&self) -> Vec<&Exposed> {
        self.variables
            .iter()
            .filter(|e| e.causality() == Causality::Output)
            .collect()
    }

    /// The units and simple types (their 2.0 XML blocks) the exposed variables use: the
    /// components' definitions, each once (a name two components define differently keeps the
    /// first).
    #[allow(clippy::type_complexity)]
    fn definitions(
        &self,
        sim: &Simulation,
        component_xml: &[(String, String)],
    ) -> (Vec<(String, String)>, Vec<(String, String)>) {
        let descriptions = sim.component_descriptions();
        let mut units: Vec<(String, String)> = Vec::new();
        let mut types: Vec<(String, String)> = Vec::new();
        for (component, xml) in component_xml {
            let d = descriptions.iter().find(|(c, _)| c == component).map(|(_, d)| *d);
            let Some(d) = d else { continue };
            for e in self.variables.iter().filter(|e| &e.component == component) {
                let Some(v) = d.variable(&e.variable) else { continue };
                if let Some(u) = &v.unit
                    && !units.iter().any(|(n, _)| n == u)
                    && let Some(block) = element_text(xml, "Unit", u)
                {
                    units.push((u.clone(), block));
                }
                if let Some(t) = &v.declared_type
                    && !types.iter().any(|(n, _)| n == t)
                    && let Some(block) = element_text(xml, "SimpleType", t).or_else(|| {
                        // An FMI 3.0 component's type, in FMI 2.0's form.
                        [
                            "Float64Type",
                            "Int32Type",
                            "BooleanType",
                            "StringType",
                            "EnumerationType",
                        ]
                        .iter()
                        .find_map(|tag| element_text(xml, tag, t))
                        .and_then(|b| simple_type2(&b))
                    })
                {
                    // A SimpleType's unit is a unit too.
                    if let Some(u) = attribute_in(
                        &block[block.find("unit=").map_or(0, |i| block[..i].rfind('<').unwrap_or(0))..],
                        "unit",
                    ) && !units.iter().any(|(n, _)| *n == u)
                        && let Some(ub) = element_text(xml, "Unit", &u)
                    {
                        units.push((u, ub));
                    }
                    types.push((t.clone(), block));
                }
            }
        }
        (units, types)
    }
}

/// The whole `<tag name="name" ...>...</tag>` (or `<tag name="name" .../>`) element of `xml`.
fn element_text(xml: &str, tag: &str, name: &str) -> Option<String> {
    let open = format!("<{tag} ");
    let mut from = 0;
    while let Some(i) = xml[from..].find(&open) {
        let start = from + i;
        let head_end = start + xml[start..].find('>')?;
        let head = &xml[start..=head_end];
        if attribute_in(head, "name").as_deref() == Some(name) {
            if head.ends_with("/>") {
                return Some(head.to_owned());
            }
            let close = format!("</{tag}>");
            let end = head_end + xml[head_end..].find(&close)? + close.len();
            return Some(xml[start..end].to_owned());
        }
        from = head_end;
    }
    None
}

/// The value of attribute `name` in the first tag of `text`.
fn attribute_in(text: &str, name: &str) -> Option<String> {
    let head = &text[..text.find('>').unwrap_or(text.len())];
    let key = format!(" {name}=\"");
    let i = head.find(&key)? + key.len();
    let j = head[i..].find('"')?;
    Some(head[i..i + j].to_owned())
}

/// Whether every component can get and set (and serialize) its FMU state, and each component
/// as "name (modelIdentifier)".
fn capabilities(sim: &Simulation) -> (bool, bool, Vec<String>) {
    let descriptions = sim.component_descriptions();
    let all =
        |f: fn(&md_reader::fmi2::CoSimulation) -> bool| descriptions.iter().all(|(_, d)| d.cs.as_ref().is_some_and(f));
    // A system that steps to its clocks' ticks keeps the importer's side of the components'
    // clocks (ticks planned, Event Mode, held values) in the runner, not in the components'
    // FMU states: the container offers no FMU state then (runner/container, `can_state`).
    let state = !sim.steps_to_clock_ticks() && all(|cs| cs.can_get_and_set_fmu_state);
    let serialize = state && all(|cs| cs.can_serialize_fmu_state);
    let names = descriptions
        .iter()
        .map(|(c, d)| format!("{c} ({})", d.model_identifier()))
        .collect();
    (state, serialize, names)
}

/// `<UnitDefinitions>` of the components' unit blocks (the same in FMI 2.0 and 3.0).
fn write_units(x: &mut String, units: &[(String, String)]) {
    if units.is_empty() {
        return;
    }
    let _ = writeln!(x, "  <UnitDefinitions>");
    for (_, b) in units {
        let _ = writeln!(x, "    {}", b.trim());
    }
    let _ = writeln!(x, "  </UnitDefinitions>");
}

/// `<LogCategories>` and `<DefaultExperiment>` (the same in FMI 2.0 and 3.0).
fn write_categories_and_experiment(x: &mut String, experiment: (Option<f64>, Option<f64>), step: f64) {
    let esc = |s: &str| quick_xml::escape::escape(s).into_owned();
    let _ = writeln!(x, "  <LogCategories>");
    for (name, what) in LOG_CATEGORIES {
        let _ = writeln!(x, r#"    <Category name="{name}" description="{}"/>"#, esc(what));
    }
    let _ = writeln!(x, "  </LogCategories>");
    let mut times = String::new();
    if let Some(t) = experiment.0 {
        let _ = write!(times, r#" startTime="{t:?}""#);
    }
    if let Some(t) = experiment.1 {
        let _ = write!(times, r#" stopTime="{t:?}""#);
    }
    let _ = writeln!(x, "  <DefaultExperiment{times} stepSize=\"{step}\"/>");
}

/// An FMI 3.0 type definition (`<Float64Type>`, ..., `<EnumerationType>` with its items) in FMI
/// 2.0's form, `<SimpleType>` around `<Real>`, ..., `<Enumeration>` (None if unreadable).
fn simple_type2(block: &str) -> Option<String> {
    use quick_xml::events::Event;
    let esc = |s: &str| quick_xml::escape::escape(s).into_owned();
    let mut reader = quick_xml::Reader::from_str(block);
    let mut outer: Option<(String, Vec<(String, String)>)> = None;
    let mut items: Vec<Vec<(String, String)>> = Vec::new();
    loop {
        match reader.read_event().ok()? {
            Event::Start(e) | Event::Empty(e) => {
                let name = String::from_utf8(e.name().as_ref().to_vec()).ok()?;
                let mut attrs = Vec::new();
                for a in e.attributes() {
                    let a = a.ok()?;
                    attrs.push((
                        String::from_utf8(a.key.as_ref().to_vec()).ok()?,
                        a.unescape_value().ok()?.into_owned(),
                    ));
                }
                if name == "Item" {
                    items.push(attrs);
                } else if outer.is_none() {
                    outer = Some((name, attrs));
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    let (kind, attrs) = outer?;
    let inner = match kind.as_str() {
        "Float64Type" => "Real",
        "Int32Type" => "Integer",
        "BooleanType" => "Boolean",
        "StringType" => "String",
        "EnumerationType" => "Enumeration",
        _ => return None,
    };
    let (own, rest): (Vec<_>, Vec<_>) = attrs.into_iter().partition(|(k, _)| k == "name" || k == "description");
    let mut out = String::from("<SimpleType");
    for (k, v) in &own {
        let _ = write!(out, r#" {k}="{}""#, esc(v));
    }
    let _ = write!(out, ">\n      <{inner}");
    for (k, v) in &rest {
        let _ = write!(out, r#" {k}="{}""#, esc(v));
    }
    if items.is_empty() {
        out.push_str("/>");
    } else {
        out.push('>');
        for item in &items {
            out.push_str("\n        <Item");
            for (k, v) in item {
                let _ = write!(out, r#" {k}="{}""#, esc(v));
            }
            out.push_str("/>");
        }
        let _ = write!(out, "\n      </{inner}>");
    }
    out.push_str("\n    </SimpleType>");
    Some(out)
}

/// An FMI 2.0 `<SimpleType>` block in FMI 3.0's form: `<Float64Type>`, `<Int32Type>`,
/// `<BooleanType>`, `<StringType>` or `<EnumerationType>` with its items (None if unreadable).
fn simple_type3(block: &str) -> Option<String> {
    use quick_xml::events::Event;
    let esc = |s: &str| quick_xml::escape::escape(s).into_owned();
    let attrs = |e: &quick_xml::events::BytesStart| -> Option<Vec<(String, String)>> {
        e.attributes()
            .map(|a| {
                let a = a.ok()?;
                let key = String::from_utf8(a.key.as_ref().to_vec()).ok()?;
                let value = a.unescape_value().ok()?.into_owned();
                Some((key, value))
            })
            .collect()
    };
    let mut reader = quick_xml::Reader::from_str(block);
    let mut outer = Vec::new();
    let mut kind: Option<(String, Vec<(String, String)>)> = None;
    let mut items = Vec::new();
    loop {
        match reader.read_event().ok()? {
            Event::Start(e) | Event::Empty(e) => {
                let name = String::from_utf8(e.name().as_ref().to_vec()).ok()?;
                let a = attrs(&e)?;
                match name.as_str() {
                    "SimpleType" => outer = a,
                    "Item" => items.push(a),
                    _ => kind = Some((name, a)),
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    let (kind, inner) = kind?;
    let element = match kind.as_str() {
        "Real" => "Float64Type",
        "Integer" => "Int32Type",
        "Boolean" => "BooleanType",
        "String" => "StringType",
        "Enumeration" => "EnumerationType",
        _ => return None,
    };
    let mut out = format!("<{element}");
    for (k, v) in outer.iter().chain(&inner) {
        let _ = write!(out, r#" {k}="{}""#, esc(v));
    }
    if items.is_empty() {
        out.push_str("/>");
        return Some(out);
    }
    out.push('>');
    for item in &items {
        out.push_str("\n      <Item");
        for (k, v) in item {
            let _ = write!(out, r#" {k}="{}""#, esc(v));
        }
        out.push_str("/>");
    }
    let _ = write!(out, "\n    </{element}>");
    Some(out)
}

/// [`Spec::header`]'s answer.
struct Header {
    name: String,
    description: String,
    state: bool,
    serialize: bool,
}

/// The declaration of the exposed variable `e` in its component's description.
fn declaration<'a>(descriptions: &[(&str, &'a Description)], e: &Exposed) -> Option<&'a md_reader::fmi2::Variable> {
    descriptions
        .iter()
        .find(|(c, _)| *c == e.component)
        .and_then(|(_, d)| d.variable(&e.variable))
}

/// An exposed output with a start value, and a parameter, are `initial="exact"`; the others
/// take the standard's default.
fn write_initial(x: &mut String, e: &Exposed) {
    let initial = match e.causality() {
        Causality::Output if e.start.is_some() => Some("exact"),
        Causality::Parameter => Some("exact"),
        _ => None,
    };
    if let Some(i) = initial {
        let _ = write!(x, r#" initial="{i}""#);
    }
}

/// The attributes an exposed variable takes from its component's declaration `v`: declared
/// type, unit, and (but for Boolean and String) min and max.
fn write_type_attributes(x: &mut String, e: &Exposed, v: Option<&md_reader::fmi2::Variable>) {
    let esc = |s: &str| quick_xml::escape::escape(s).into_owned();
    let Some(v) = v else { return };
    if let Some(t) = &v.declared_type {
        let _ = write!(x, r#" declaredType="{}""#, esc(t));
    }
    if let Some(u) = &v.unit {
        let _ = write!(x, r#" unit="{}""#, esc(u));
    }
    if e.ty() != Type::Boolean && e.ty() != Type::String {
        if let Some(m) = v.min {
            let _ = write!(x, r#" min="{m}""#);
        }
        if let Some(m) = v.max {
            let _ = write!(x, r#" max="{m}""#);
        }
    }
}
