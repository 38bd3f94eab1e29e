//! FMI-LS-BUS 1.0.0 in a packaged FMU: the manifest (`extra/org.fmi-standard.fmi-ls-bus/`,
//! against `fmi3LayeredStandardBusManifest.xsd`'s required and fixed attributes), each network
//! terminal of `terminalsAndIcons.xml` ("Terminal Definitions") and the variables it names
//! ("Variables", "Rx Clocks", "Tx Clocks", "MIME Types"). Each problem quotes the rule.

use crate::xml::{LS_BUS_DESCRIPTION, NETWORK_TERMINAL_KIND};
use md_reader::fmi3::{Type, Variable};
use md_reader::{Causality, ModelDescription};
use quick_xml::events::Event;
use std::collections::BTreeMap;

/// A `<Terminal>` as read: its attributes, members (memberName → (variableName, variableKind))
/// and nested terminals.
#[derive(Default, Debug)]
struct Term {
    name: String,
    kind: String,
    rule: String,
    members: Vec<(String, String, String)>,
    nested: Vec<Term>,
}

/// The terminals of `terminalsAndIcons.xml`, nested as written (the file is checked well-formed by
/// `terminal_problems`; a malformed one gives no terminals here).
fn terminals(text: &str) -> Vec<Term> {
    let mut stack: Vec<Term> = Vec::new();
    let mut top = Vec::new();
    walk_terminals(text, |element| match element {
        TerminalXml::EndOfTerminal => {
            if let Some(t) = stack.pop() {
                match stack.last_mut() {
                    Some(parent) => parent.nested.push(t),
                    None => top.push(t),
                }
            }
        }
        TerminalXml::Open { name, attr, empty } => match name {
            b"Terminal" => {
                let t = Term {
                    name: attr("name"),
                    kind: attr("terminalKind"),
                    rule: attr("matchingRule"),
                    ..Term::default()
                };
                if empty {
                    match stack.last_mut() {
                        Some(parent) => parent.nested.push(t),
                        None => top.push(t),
                    }
                } else {
                    stack.push(t);
                }
            }
            b"TerminalMemberVariable" => {
                if let Some(t) = stack.last_mut() {
                    t.members
                        .push((attr("memberName"), attr("variableName"), attr("variableKind")));
                }
            }
            _ => {}
        },
    });
    top
}

/// What [`walk_terminals`] meets in terminalsAndIcons.xml.
pub(super) enum TerminalXml<'a> {
    /// An element opens (`empty`: and closes, `<X/>`); `attr` gives an attribute's value ("" if
    /// it has none).
    Open {
        name: &'a [u8],
        attr: &'a dyn Fn(&str) -> String,
        empty: bool,
    },
    /// `</Terminal>`.
    EndOfTerminal,
}

/// Reads terminalsAndIcons.xml element by element, to its end or its first error.
pub(super) fn walk_terminals(text: &str, mut each: impl FnMut(TerminalXml)) {
    let mut reader = quick_xml::Reader::from_str(text);
    loop {
        let (e, empty) = match reader.read_event() {
            Ok(Event::Start(e)) => (e, false),
            Ok(Event::Empty(e)) => (e, true),
            Ok(Event::End(e)) if e.name().as_ref() == b"Terminal" => {
                each(TerminalXml::EndOfTerminal);
                continue;
            }
            Ok(Event::Eof) | Err(_) => break,
            Ok(_) => continue,
        };
        let attr = |name: &str| {
            e.try_get_attribute(name)
                .ok()
                .flatten()
                .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
                .unwrap_or_default()
        };
        each(TerminalXml::Open {
            name: e.name().as_ref(),
            attr: &attr,
            empty,
        });
    }
}

/// The layered standard's rules on one FMU: `terminals_xml` is its `terminalsAndIcons.xml` (if
/// any), `manifest` its FMI-LS-BUS manifest (if any).
pub fn ls_bus_problems(terminals_xml: Option<&str>, model_description: &str, manifest: Option<&str>) -> Vec<String> {
    let mut problems = Vec::new();
    let networks: Vec<Term> = terminals_xml
        .map(terminals)
        .unwrap_or_default()
        .into_iter()
        .filter(|t| t.kind == NETWORK_TERMINAL_KIND)
        .collect();
    match (networks.is_empty(), manifest) {
        (true, None) => return problems,
        (true, Some(_)) => problems.push(
            "extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml without a network terminal (terminalKind \
             org.fmi-ls-bus.network-terminal) in terminalsAndIcons.xml: \"Each network connected to the FMU must be \
             described ... as a <Terminal>\" (FMI-LS-BUS 1.0.0, Bus Terminal)"
                .into(),
        ),
        (false, None) => problems.push(
            "a network terminal without extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml: \"This layered \
             standard ... requires the use of a layered standard manifest file\" (FMI-LS-BUS 1.0.0, Layered Standard \
             Manifest File)"
                .into(),
        ),
        (false, Some(m)) => problems.extend(manifest_problems(m)),
    }
    let vars: BTreeMap<String, Variable> = match md_reader::parse(model_description) {
        Ok(ModelDescription::Fmi3(d)) => d.variables.into_iter().map(|v| (v.name.clone(), v)).collect(),
        _ => {
            if !networks.is_empty() {
                problems.push("an FMI-LS-BUS network terminal in an FMU that is not FMI 3.0".into());
            }
            return problems;
        }
    };
    let by_vr = |vr: u32| vars.values().find(|v| v.vr == vr && v.ty == Type::Clock);
    let mut used: BTreeMap<String, String> = BTreeMap::new();
    for n in &networks {
        let at = format!("network terminal '{}'", n.name);
        if n.rule != "org.fmi-ls-bus.transceiver" {
            problems.push(format!(
                "{at}: matchingRule is '{}'; it \"must be org.fmi-ls-bus.transceiver\" (FMI-LS-BUS 1.0.0, Bus Terminal)",
                n.rule
            ));
        }
        let mut role = BTreeMap::new();
        for (member, variable, kind) in &n.members {
            if kind != "signal" {
                problems.push(format!(
                    "{at}: member '{member}' has variableKind '{kind}'; \"The variableKind of these four members must \
                     be signal\" (FMI-LS-BUS 1.0.0, Bus Terminal)"
                ));
            }
            if role.insert(member.as_str(), variable.as_str()).is_some() {
                problems.push(format!("{at}: member '{member}' appears twice"));
            }
            if let Some(other) = used.insert(variable.clone(), n.name.clone()) {
                problems.push(format!(
                    "{at}: variable '{variable}' is a member of network terminal '{other}' too: \"The use of the same \
                     variable within different Bus Terminals is not allowed\" (FMI-LS-BUS 1.0.0, Bus Terminal)"
                ));
            }
        }
        let mut var = |member: &str| -> Option<&Variable> {
            match role.get(member) {
                None => {
                    problems.push(format!(
                        "{at}: no member '{member}': \"A Bus Terminal shall contain four <TerminalMemberVariable> \
                         elements with the following memberName attributes: Tx_Data, Tx_Clock, Rx_Data and Rx_Clock\" \
                         (FMI-LS-BUS 1.0.0, Bus Terminal)"
                    ));
                    None
                }
                Some(name) => {
                    let v = vars.get(*name);
                    if v.is_none() {
                        problems.push(format!("{at}: member '{member}' names '{name}', which is no variable"));
                    }
                    v
                }
            }
        };
        let (rx_clock, rx_data, tx_clock, tx_data) = (var("Rx_Clock"), var("Rx_Data"), var("Tx_Clock"), var("Tx_Data"));
        if let Some(c) = rx_clock {
            let triggered = c.clock.as_ref().is_some_and(|k| k.interval_variability == "triggered");
            if c.ty != Type::Clock || c.causality != Causality::Input || !triggered {
                problems.push(format!(
                    "{at}: Rx_Clock '{}' is not an input triggered Clock: \"The input Clocks (Rx_Clock) shall be \
                     triggered Clocks\" (FMI-LS-BUS 1.0.0, Rx Clocks)",
                    c.name
                ));
            }
        }
        if let Some(c) = tx_clock {
            let iv = c.clock.as_ref().map(|k| k.interval_variability.as_str()).unwrap_or("");
            let ok = c.ty == Type::Clock
                && match c.causality {
                    Causality::Input => matches!(iv, "constant" | "fixed" | "tunable" | "changing" | "countdown"),
                    Causality::Output => iv == "triggered",
                    _ => false,
                };
            if !ok {
                problems.push(format!(
                    "{at}: Tx_Clock '{}' is neither an input time-based Clock nor an output triggered Clock \
                     (FMI-LS-BUS 1.0.0, Tx Clocks)",
                    c.name
                ));
            }
        }
        for (member, data, clock, causality) in [
            ("Rx_Data", rx_data, rx_clock, Causality::Input),
            ("Tx_Data", tx_data, tx_clock, Causality::Output),
        ] {
            let Some(v) = data else { continue };
            if v.ty != Type::Binary {
                problems.push(format!(
                    "{at}: {member} '{}' is no Binary: \"The Tx_Data/Rx_Data variables are of type fmi3Binary\" \
                     (FMI-LS-BUS 1.0.0, Tx/Rx Data Variables)",
                    v.name
                ));
                continue;
            }
            if v.causality != causality {
                problems.push(format!(
                    "{at}: {member} '{}' has causality {:?}; FMI-LS-BUS 1.0.0 (Variables) makes Rx_Data an input and \
                     Tx_Data an output",
                    v.name, v.causality
                ));
            }
            if let Some(c) = clock
                && !v.clocks.iter().any(|vr| by_vr(*vr).is_some_and(|k| k.name == c.name))
            {
                problems.push(format!(
                    "{at}: {member} '{}' is not clocked by '{}' (FMI-LS-BUS 1.0.0, Variables)",
                    v.name, c.name
                ));
            }
            let mime = v.mime_type.as_deref().unwrap_or("application/octet-stream");
            if !mime.starts_with("application/org.fmi-standard.fmi-ls-bus.") {
                problems.push(format!(
                    "{at}: {member} '{}' has mimeType '{mime}', none of FMI-LS-BUS 1.0.0's (MIME Types: \
                     application/org.fmi-standard.fmi-ls-bus.can; version=\"1.0.0\" for CAN)",
                    v.name
                ));
            }
        }
        if let (Some(rx), Some(tx)) = (rx_data, tx_data)
            && rx.mime_type != tx.mime_type
        {
            problems.push(format!(
                "{at}: Rx_Data and Tx_Data have different mimeTypes ({:?}, {:?}): one network, one bus type",
                rx.mime_type, tx.mime_type
            ));
        }
        for c in &n.nested {
            if c.kind == "org.fmi-ls-bus.network-terminal.configuration"
                && (c.name != "Configuration" || c.rule != "bus")
            {
                problems.push(format!(
                    "{at}: its Configuration Terminal is named '{}' with matchingRule '{}': \"name must be \
                     Configuration\", \"matchingRule must be bus\" (FMI-LS-BUS 1.0.0, Configuration Terminal)",
                    c.name, c.rule
                ));
            }
        }
    }
    problems
}

/// The manifest against `fmi3LayeredStandardBusManifest.xsd`: root, the required attributes with
/// their fixed values, `isBusSimulationFMU` a boolean.
fn manifest_problems(text: &str) -> Vec<String> {
    let at = "extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml";
    let mut reader = quick_xml::Reader::from_str(text);
    loop {
        match reader.read_event() {
            Ok(Event::Start(e) | Event::Empty(e)) => {
                if e.name().as_ref() != b"fmiLayeredStandardManifest" {
                    return vec![format!(
                        "{at}: the root is <{}>, not <fmiLayeredStandardManifest>",
                        String::from_utf8_lossy(e.name().as_ref())
                    )];
                }
                let attr = |name: &str| {
                    e.try_get_attribute(name)
                        .ok()
                        .flatten()
                        .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
                };
                let mut problems = Vec::new();
                if e.try_get_attribute("xmlns:fmi-ls")
                    .ok()
                    .flatten()
                    .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
                    != Some("http://fmi-standard.org/fmi-ls-manifest".into())
                {
                    problems.push(format!(
                        "{at}: the prefix fmi-ls is not bound to http://fmi-standard.org/fmi-ls-manifest"
                    ));
                }
                for (name, want) in [
                    ("fmi-ls:fmi-ls-name", Some("org.fmi-standard.fmi-ls-bus")),
                    ("fmi-ls:fmi-ls-version", None),
                    ("fmi-ls:fmi-ls-description", Some(LS_BUS_DESCRIPTION)),
                ] {
                    match (attr(name), want) {
                        (None, _) => problems.push(format!("{at}: the required attribute {name} is missing")),
                        (Some(v), Some(want)) if v != want => {
                            problems.push(format!("{at}: {name} is '{v}'; the schema fixes it to '{want}'"))
                        }
                        _ => {}
                    }
                }
                if let Some(b) = attr("isBusSimulationFMU")
                    && !matches!(b.as_str(), "true" | "false" | "1" | "0")
                {
                    problems.push(format!("{at}: isBusSimulationFMU is '{b}', not an xs:boolean"));
                }
                return problems;
            }
            Ok(Event::Eof) => return vec![format!("{at}: no root element")],
            Err(e) => {
                return vec![format!(
                    "{at} is not well-formed at byte {}: {e}",
                    reader.error_position()
                )];
            }
            Ok(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ls_bus_problems;

    const MIME: &str = "application/org.fmi-standard.fmi-ls-bus.can; version=&quot;1.0.0&quot;";

    fn md(rx_clock: &str, tx_mime: &str) -> String {
        format!(
            r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="N" instantiationToken="N">
  <CoSimulation modelIdentifier="N"/>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Clock name="P.Rx_Clock" valueReference="1002" causality="input" variability="discrete" intervalVariability="{rx_clock}"/>
    <Binary name="P.Rx_Data" valueReference="1001" causality="input" mimeType="{MIME}" variability="discrete" clocks="1002"/>
    <Clock name="P.Tx_Clock" valueReference="1004" causality="input" variability="discrete" intervalVariability="countdown"/>
    <Binary name="P.Tx_Data" valueReference="1003" causality="output" mimeType="{tx_mime}" variability="discrete" clocks="1004"/>
    <Boolean name="BusNotifications" valueReference="1005" causality="parameter" variability="fixed" start="false"/>
  </ModelVariables>
  <ModelStructure><Output valueReference="1003"/></ModelStructure>
</fmiModelDescription>"#
        )
    }

    fn terminals(rule: &str, config_name: &str) -> String {
        format!(
            r#"<fmiTerminalsAndIcons fmiVersion="3.0"><Terminals>
<Terminal terminalKind="org.fmi-ls-bus.network-terminal" name="P" matchingRule="{rule}">
  <TerminalMemberVariable variableName="P.Rx_Clock" memberName="Rx_Clock" variableKind="signal"/>
  <TerminalMemberVariable variableName="P.Rx_Data" memberName="Rx_Data" variableKind="signal"/>
  <TerminalMemberVariable variableName="P.Tx_Clock" memberName="Tx_Clock" variableKind="signal"/>
  <TerminalMemberVariable variableName="P.Tx_Data" memberName="Tx_Data" variableKind="signal"/>
  <Terminal terminalKind="org.fmi-ls-bus.network-terminal.configuration" name="{config_name}" matchingRule="bus">
    <TerminalMemberVariable variableName="BusNotifications" memberName="BusNotifications" variableKind="signal"/>
  </Terminal>
</Terminal></Terminals></fmiTerminalsAndIcons>"#
        )
    }

    fn manifest(name: &str) -> String {
        format!(
            r#"<fmiLayeredStandardManifest xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest" fmi-ls:fmi-ls-name="{name}" fmi-ls:fmi-ls-version="1.0.0" fmi-ls:fmi-ls-description="{}" isBusSimulationFMU="false"/>"#,
            crate::xml::LS_BUS_DESCRIPTION
        )
    }

    #[test]
    fn a_network_fmu_as_the_standard_describes_it_has_no_problem() {
        let p = ls_bus_problems(
            Some(&terminals("org.fmi-ls-bus.transceiver", "Configuration")),
            &md("triggered", MIME),
            Some(&manifest("org.fmi-standard.fmi-ls-bus")),
        );
        assert!(p.is_empty(), "{p:#?}");
    }

    #[test]
    fn each_broken_rule_is_named() {
        let good_t = terminals("org.fmi-ls-bus.transceiver", "Configuration");
        let good_md = md("triggered", MIME);
        let good_m = manifest("org.fmi-standard.fmi-ls-bus");
        let cases: [(Option<String>, String, Option<String>, &str); 7] = [
            (
                Some(good_t.clone()),
                good_md.clone(),
                None,
                "requires the use of a layered standard manifest file",
            ),
            (
                None,
                good_md.clone(),
                Some(good_m.clone()),
                "without a network terminal",
            ),
            (
                Some(good_t.clone()),
                good_md.clone(),
                Some(manifest("org.fmi-standard.fmi-ls-ref")),
                "the schema fixes it",
            ),
            (
                Some(terminals("plug", "Configuration")),
                good_md.clone(),
                Some(good_m.clone()),
                "must be org.fmi-ls-bus.transceiver",
            ),
            (
                Some(terminals("org.fmi-ls-bus.transceiver", "Config")),
                good_md.clone(),
                Some(good_m.clone()),
                "name must be",
            ),
            (
                Some(good_t.clone()),
                md("countdown", MIME),
                Some(good_m.clone()),
                "shall be triggered Clocks",
            ),
            (
                Some(good_t.clone()),
                md("triggered", "application/octet-stream"),
                Some(good_m.clone()),
                "none of FMI-LS-BUS 1.0.0's",
            ),
        ];
        for (t, m, man, words) in cases {
            let p = ls_bus_problems(t.as_deref(), &m, man.as_deref());
            assert!(p.iter().any(|x| x.contains(words)), "{words}: {p:#?}");
        }
    }
}
