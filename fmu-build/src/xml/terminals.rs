//! `terminalsAndIcons.xml` (FMI 3.0), and the FMI-LS-BUS manifest of an FMU with a network
//! terminal.

use super::{Xml, close, document, empty, finish, open};
use rustfmu::description::{ModelDescription, Terminal};

/// `terminalKind` of an FMI-LS-BUS 1.0.0 Bus Terminal ("Terminal Definitions").
pub const NETWORK_TERMINAL_KIND: &str = "org.fmi-ls-bus.network-terminal";
/// Where FMI-LS-BUS 1.0.0 puts its manifest ("Layered Standard Manifest File").
pub const LS_BUS_MANIFEST: &str = "extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml";
/// The manifest's fixed `fmi-ls-description` (`fmi3LayeredStandardBusManifest.xsd`).
pub const LS_BUS_DESCRIPTION: &str = "Layered Standard for the simulation of bus communication on a Physical Signal Abstraction or Network Abstraction based level.";

/// `terminalsAndIcons/terminalsAndIcons.xml` (FMI 3.0, 2.4.9) of a description with terminals,
/// in the order of `fmi3TerminalsAndIcons.xsd` (a terminal's members, then its nested
/// terminals); `None` without terminals. Every member names a variable of the description
/// (checked here, as the derive checked it).
pub fn terminals_and_icons(d: &ModelDescription) -> Result<Option<String>, String> {
    if d.terminals.is_empty() {
        return Ok(None);
    }
    let mut w = document()?;
    open(&mut w, "fmiTerminalsAndIcons", &[("fmiVersion", "3.0")])?;
    open(&mut w, "Terminals", &[])?;
    for t in d.terminals {
        terminal(&mut w, d, t)?;
    }
    close(&mut w, "Terminals")?;
    close(&mut w, "fmiTerminalsAndIcons")?;
    finish(w).map(Some)
}

fn terminal(w: &mut Xml, d: &ModelDescription, t: &Terminal) -> Result<(), String> {
    let mut attrs = vec![("name", t.name), ("matchingRule", t.matching_rule)];
    if !t.kind.is_empty() {
        attrs.push(("terminalKind", t.kind));
    }
    if !t.description.is_empty() {
        attrs.push(("description", t.description));
    }
    open(w, "Terminal", &attrs)?;
    for m in t.members {
        if d.by_name(m.variable).is_none() {
            return Err(format!(
                "{}: terminal '{}': member '{}' names '{}', which is no variable",
                d.model_identifier, t.name, m.member, m.variable
            ));
        }
        empty(
            w,
            "TerminalMemberVariable",
            &[
                ("variableName", m.variable),
                ("memberName", m.member),
                ("variableKind", m.kind),
            ],
        )?;
    }
    for nested in t.terminals {
        terminal(w, d, nested)?;
    }
    close(w, "Terminal")
}

/// `extra/org.fmi-standard.fmi-ls-bus/fmi-ls-manifest.xml` of a description with an FMI-LS-BUS
/// network terminal ("The manifest file shall be stored inside the FMU at the following path"),
/// `None` otherwise; `isBusSimulationFMU` says whether it is a bus simulation
/// (`#[fmu(bus_simulation)]`).
pub fn ls_bus_manifest(d: &ModelDescription) -> Option<String> {
    d.terminals.iter().any(|t| t.kind == NETWORK_TERMINAL_KIND).then(|| {
        format!(
            r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiLayeredStandardManifest
    xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
    fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-bus"
    fmi-ls:fmi-ls-version="1.0.0"
    fmi-ls:fmi-ls-description="{LS_BUS_DESCRIPTION}"
    isBusSimulationFMU="{}"/>
"#,
            d.bus_simulation
        )
    })
}
