//! Checks of a packaged description that its reader does not make: the lengths of FMI 3.0
//! arrays, and `terminalsAndIcons.xml` against the variables.

use md_reader::{Causality, ModelDescription, fmi3};
use std::collections::BTreeSet;

/// The length of an FMI 3.0 array's dimension at the start: a fixed one, or the start value of
/// the variable its `valueReference` names; `Err` says what is wrong with that variable.
fn dimension_length(d: &fmi3::ModelDescription, dim: &fmi3::Dimension) -> Result<u64, String> {
    let vr = match *dim {
        fmi3::Dimension::Fixed(n) => return Ok(n),
        fmi3::Dimension::Parameter(vr) => vr,
    };
    let p = d
        .by_vr(vr)
        .ok_or_else(|| format!("<Dimension valueReference=\"{vr}\"> names no variable"))?;
    if p.ty != fmi3::Type::UInt64
        || !(p.causality == Causality::StructuralParameter || p.variability == md_reader::Variability::Constant)
    {
        return Err(format!(
            "<Dimension valueReference=\"{vr}\"> names '{}', a {} {}; a length is set by a UInt64 structuralParameter \
             or constant (FMI 3.0, 2.4.7.6)",
            p.name,
            p.causality.name(),
            p.ty.name()
        ));
    }
    p.start
        .as_deref()
        .and_then(|s| s.trim().parse::<u64>().ok())
        .ok_or_else(|| format!("'{}', which sets a length (vr {vr}), has no UInt64 start value", p.name))
}

/// What is wrong with the arrays of an FMI 3.0 description: a `<Dimension valueReference>` that
/// names no UInt64 structural parameter (or constant), or a `start` list whose length is
/// neither 1 (every element's) nor the number of elements at the start lengths (those of the
/// structural parameters at their start values).
pub fn array_problems(d: &fmi3::ModelDescription) -> Vec<String> {
    let mut problems = Vec::new();
    for v in d.variables.iter().filter(|v| v.array) {
        let lengths: Result<Vec<u64>, String> = v.dimensions.iter().map(|dim| dimension_length(d, dim)).collect();
        let lengths = match lengths {
            Ok(l) => l,
            Err(e) => {
                problems.push(format!("variable '{}' (vr {}): {e}", v.name, v.vr));
                continue;
            }
        };
        // A String's or Binary's start values are <Start> children (the reader keeps the first).
        if matches!(v.ty, fmi3::Type::String | fmi3::Type::Binary) {
            continue;
        }
        let count = lengths.iter().try_fold(1u64, |n, &k| n.checked_mul(k));
        if let (Some(start), Some(count)) = (&v.start, count) {
            let given = start.split_whitespace().count() as u64;
            if given != 1 && given != count {
                let shape: Vec<String> = lengths.iter().map(u64::to_string).collect();
                problems.push(format!(
                    "variable '{}' (vr {}): {given} start values for {count} elements (the lengths at the start: {})",
                    v.name,
                    v.vr,
                    shape.join(" x ")
                ));
            }
        }
    }
    problems
}

/// What is wrong with `terminalsAndIcons.xml` against the model description (FMI 3.0, 2.4.9):
/// not well-formed, another root or `fmiVersion`, a terminal without `name` or
/// `matchingRule`, a member without `variableName` or `variableKind`, or naming no variable.
pub fn terminal_problems(terminals: &str, model_description: &str) -> Vec<String> {
    use quick_xml::events::Event;
    let names: BTreeSet<String> = match md_reader::parse(model_description) {
        Ok(ModelDescription::Fmi3(d)) => d.variables.iter().map(|v| v.name.clone()).collect(),
        _ => return vec!["terminalsAndIcons.xml beside a description that is not FMI 3.0".into()],
    };
    let mut problems = Vec::new();
    let mut reader = quick_xml::Reader::from_str(terminals);
    let mut root_seen = false;
    loop {
        let e = match reader.read_event() {
            Ok(Event::Eof) => break,
            Ok(Event::Start(e) | Event::Empty(e)) => e,
            Ok(_) => continue,
            Err(err) => {
                problems.push(format!(
                    "terminalsAndIcons.xml is not well-formed at byte {}: {err}",
                    reader.error_position()
                ));
                break;
            }
        };
        let attr = |name: &str| {
            e.try_get_attribute(name)
                .ok()
                .flatten()
                .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
        };
        match e.name().as_ref() {
            b"fmiTerminalsAndIcons" => {
                root_seen = true;
                if !attr("fmiVersion").is_some_and(|v| v.starts_with("3.")) {
                    problems.push("terminalsAndIcons.xml: fmiVersion is not 3.x".into());
                }
            }
            b"Terminal" if attr("name").is_none() || attr("matchingRule").is_none() => {
                problems.push("terminalsAndIcons.xml: a <Terminal> without name or matchingRule".into());
            }
            b"TerminalMemberVariable" => match (attr("variableName"), attr("variableKind")) {
                (Some(v), Some(_)) if names.contains(&v) => {}
                (Some(v), Some(_)) => problems.push(format!(
                    "terminalsAndIcons.xml: member variable '{v}' is no variable of modelDescription.xml"
                )),
                _ => problems.push(
                    "terminalsAndIcons.xml: a <TerminalMemberVariable> without variableName or variableKind".into(),
                ),
            },
            _ => {}
        }
    }
    if !root_seen && problems.is_empty() {
        problems.push("terminalsAndIcons.xml: the root is not <fmiTerminalsAndIcons>".into());
    }
    problems
}

#[cfg(test)]
mod terminal_tests {
    use super::terminal_problems;

    const MD: &str = r#"<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="{x}">
  <CoSimulation modelIdentifier="M"/>
  <ModelVariables><Float64 name="phi" valueReference="1" causality="output"/></ModelVariables>
  <ModelStructure><Output valueReference="1"/></ModelStructure>
</fmiModelDescription>"#;

    fn terminals(member: &str) -> String {
        format!(
            r#"<fmiTerminalsAndIcons fmiVersion="3.0"><Terminals><Terminal name="f" matchingRule="plug">{member}</Terminal></Terminals></fmiTerminalsAndIcons>"#
        )
    }

    #[test]
    fn members_must_name_variables_and_have_a_kind() {
        let good = terminals(r#"<TerminalMemberVariable variableName="phi" memberName="phi" variableKind="signal"/>"#);
        assert!(terminal_problems(&good, MD).is_empty());
        let unknown =
            terminals(r#"<TerminalMemberVariable variableName="tau" memberName="tau" variableKind="inflow"/>"#);
        assert_eq!(
            terminal_problems(&unknown, MD),
            ["terminalsAndIcons.xml: member variable 'tau' is no variable of modelDescription.xml"]
        );
        let kindless = terminals(r#"<TerminalMemberVariable variableName="phi"/>"#);
        assert_eq!(terminal_problems(&kindless, MD).len(), 1);
        assert_eq!(terminal_problems("<x", MD).len(), 1);
        assert_eq!(
            terminal_problems(&good.replace("3.0", "2.0"), MD),
            ["terminalsAndIcons.xml: fmiVersion is not 3.x"]
        );
    }
}

#[cfg(test)]
mod array_tests {
    use super::array_problems;
    use md_reader::fmi3::ModelDescription;

    /// A description with a structural parameter `n` (start 2), a Float64 parameter `k` and
    /// the array `a` (its attributes after `valueReference`, its `<Dimension>`s).
    fn problems(a: &str, dims: &str) -> Vec<String> {
        let xml = format!(
            r#"<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="{{x}}">
  <CoSimulation modelIdentifier="M"/>
  <ModelVariables>
    <UInt64 name="n" valueReference="1" causality="structuralParameter" variability="fixed" start="2"/>
    <Float64 name="k" valueReference="2" causality="parameter" variability="fixed" start="2"/>
    <Float64 name="a" valueReference="3" {a}>{dims}</Float64>
  </ModelVariables>
</fmiModelDescription>"#
        );
        array_problems(&ModelDescription::parse(&xml).unwrap())
    }

    #[test]
    fn a_length_is_set_by_a_uint64_structural_parameter_and_the_start_lists_the_start_size() {
        let p = r#"causality="parameter" variability="fixed""#;
        // n x 3 at the start: 2 x 3 = 6 values, or one for all.
        let sized = r#"<Dimension valueReference="1"/><Dimension start="3"/>"#;
        assert!(problems(&format!(r#"{p} start="1 2 3 4 5 6""#), sized).is_empty());
        assert!(problems(&format!(r#"{p} start="7""#), sized).is_empty());
        assert_eq!(
            problems(&format!(r#"{p} start="1 2 3""#), sized),
            ["variable 'a' (vr 3): 3 start values for 6 elements (the lengths at the start: 2 x 3)"]
        );
        // A fixed array counts the same way.
        assert!(!problems(&format!(r#"{p} start="1 2 3""#), r#"<Dimension start="2"/>"#).is_empty());
        // No start (an output): nothing to count.
        assert!(problems(r#"causality="output""#, sized).is_empty());
        // A length set by a Float64 parameter, or by no variable.
        let by_k = problems(&format!(r#"{p} start="1""#), r#"<Dimension valueReference="2"/>"#);
        assert_eq!(by_k.len(), 1);
        assert!(by_k[0].contains("names 'k', a parameter Float64"), "{by_k:?}");
        let by_none = problems(&format!(r#"{p} start="1""#), r#"<Dimension valueReference="9"/>"#);
        assert_eq!(
            by_none,
            ["variable 'a' (vr 3): <Dimension valueReference=\"9\"> names no variable"]
        );
    }
}
